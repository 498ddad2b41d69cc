#include "common/record/recorder.h"

#include <time.h>

#include <algorithm>

namespace microdex::record {
namespace {

double ThreadCpuS() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

}  // namespace

Recorder::Recorder(const std::string& path, const std::map<std::string, std::string>& metadata,
                   const RecorderConfig& config)
    : path_(path),
      config_(config),
      writer_(std::make_unique<SessionWriter>(path, metadata, !config.checkpoint_thread)) {
  queue_.reserve(config_.batch_wake);
  thread_ = std::thread([this] { Run(); });
  if (config_.checkpoint_thread) checkpoint_thread_ = std::thread([this] { RunCheckpoints(); });
}

Recorder::~Recorder() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  checkpoint_wake_.notify_one();
  // The checkpointer first: the writer's close then checkpoints what is left on its own.
  if (checkpoint_thread_.joinable()) checkpoint_thread_.join();
  thread_.join();
}

bool Recorder::Push(RecordedMessage&& m) {
  bool wake = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++stats_.pushed;
    if (queue_.size() >= config_.queue_capacity) {
      ++stats_.dropped;
      return false;
    }
    queue_.push_back(std::move(m));
    wake = queue_.size() == config_.batch_wake;
  }
  if (wake) wake_.notify_one();
  return true;
}

void Recorder::Flush() {
  std::unique_lock<std::mutex> lock(mutex_);
  const std::uint64_t ticket = ++flush_requested_;
  wake_.notify_one();
  flushed_.wait(lock, [&] { return flush_done_ >= ticket || !stats_.error.empty(); });
}

void Recorder::SetMetadata(const std::string& key, const std::string& value) {
  std::lock_guard<std::mutex> lock(mutex_);
  pending_metadata_[key] = value;
}

RecorderStats Recorder::stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

void Recorder::Run() {
  std::vector<RecordedMessage> batch;
  batch.reserve(config_.batch_wake);
  std::map<std::string, std::string> metadata;
  auto last_commit = std::chrono::steady_clock::now();
  for (;;) {
    bool stopping = false;
    std::uint64_t flush_ticket = 0;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait_for(lock, config_.commit_period, [&] {
        return stop_ || queue_.size() >= config_.batch_wake || flush_requested_ > flush_done_;
      });
      batch.swap(queue_);
      metadata.swap(pending_metadata_);
      stopping = stop_;
      flush_ticket = flush_requested_;
    }
    const auto now = std::chrono::steady_clock::now();
    std::string error;
    try {
      for (const auto& [k, v] : metadata) writer_->SetMetadata(k, v);
      writer_->Write(batch);
    } catch (const std::exception& e) {
      error = e.what();
    }
    const double write_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - now).count();
    const double cpu = ThreadCpuS();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!batch.empty() && stats_.error.empty()) {
        stats_.written += batch.size();
        ++stats_.commits;
        stats_.max_commit_gap_s = std::max(
            stats_.max_commit_gap_s, std::chrono::duration<double>(now - last_commit).count());
        stats_.max_write_s = std::max(stats_.max_write_s, write_s);
      }
      if (!error.empty() && stats_.error.empty()) stats_.error = error;
      stats_.thread_cpu_s = cpu;
      flush_done_ = flush_ticket;
    }
    flushed_.notify_all();
    if (!batch.empty()) last_commit = now;
    if (batch.empty()) last_commit = std::chrono::steady_clock::now();
    batch.clear();
    metadata.clear();
    if (stopping) break;
  }
  writer_.reset();  // closes the file (WAL checkpointed)
}

void Recorder::RunCheckpoints() {
  std::string error;
  try {
    WalCheckpointer checkpointer(path_);
    std::unique_lock<std::mutex> lock(mutex_);
    while (!stop_) {
      checkpoint_wake_.wait_for(lock, config_.checkpoint_period, [&] { return stop_; });
      if (stop_) break;
      lock.unlock();
      const int copied = checkpointer.Checkpoint();
      lock.lock();
      if (copied > 0) ++stats_.checkpoints;
    }
  } catch (const std::exception& e) {
    error = e.what();
  }
  if (!error.empty()) {
    // The WAL then grows until the file is closed; the recording itself goes on.
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.checkpoint_error = error;
  }
}

}  // namespace microdex::record
