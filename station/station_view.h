#pragma once
// The station's microscope view (`--view PORT`): serves the station page (bundled from
// station/page/ and common/view/src/) and the scene (/scene.json) on 127.0.0.1, and streams
// the state frames the publisher thread encodes at the mirror rate. With `--device page` the
// page's keyboard and mouse messages go to the PageDevice's ring.
//
// Threads: the publisher thread fills frames() (TripleBuffer: producer publisher thread,
// consumer the view server's thread, which polls it every 2 ms and broadcasts a new frame);
// the audio cue blocks go the same way through an SpscRing (producer: the publisher thread's
// AudioBlockStream, consumer: the poll, which sends each to the pages that asked for audio);
// the view server's thread pushes device input into the PageDevice's SpscRing (consumer: the
// haptic thread). The haptic thread never meets the server.

#include <memory>
#include <string>

#include "common/scene/scene.h"
#include "common/view/view_audio.h"
#include "common/view/view_frame.h"
#include "common/view/view_server.h"
#include "station/page_device.h"
#include "station/rt/spsc_ring.h"
#include "station/rt/triple_buffer.h"

namespace microdex::station {

// Where the bundled pages are: $MICRODEX_WEB_DIR, else the build tree's web/ folder.
std::string DefaultWebDir();

class StationView {
 public:
  // device: the page device fed by the page, or null (the page only watches). Throws
  // std::runtime_error when the pages are missing or the port cannot be bound.
  StationView(const scene::SceneModel& scene, int port, const std::string& web_dir,
              const std::string& station_id, PageDevice* device);
  ~StationView();
  StationView(const StationView&) = delete;
  StationView& operator=(const StationView&) = delete;

  rt::TripleBuffer<view::FrameBytes>& frames() { return frames_; }
  // Publisher thread: some page has asked for audio (as of the server's last poll).
  bool audio_wanted() const { return server_->audio_clients() > 0; }
  // Publisher thread: hands an audio block to the pages; false when the ring is full (the
  // server's thread has not kept up: the block is dropped).
  bool PushAudio(const view::AudioBlock& block) { return audio_.TryPush(block); }
  std::uint64_t audio_dropped() const { return server_->audio_dropped(); }
  std::uint16_t port() const { return server_->port(); }
  std::uint64_t inputs_dropped() const { return inputs_dropped_.load(); }

 private:
  std::string OnText(const std::string& message);

  rt::TripleBuffer<view::FrameBytes> frames_;  // producer: publisher; consumer: view server
  // 32 blocks: 320 ms of 10 ms blocks; producer: publisher thread; consumer: view server.
  rt::SpscRing<view::AudioBlock> audio_{32};
  PageDevice* device_;
  std::string scene_json_;
  std::string info_json_;
  std::atomic<std::uint64_t> inputs_dropped_{0};
  std::unique_ptr<view::ViewServer> server_;
};

}  // namespace microdex::station
