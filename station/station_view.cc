#include "station/station_view.h"

#include <chrono>
#include <cstdlib>
#include <stdexcept>

#include "common/base/json_text.h"
#include "common/view/scene_view.h"

namespace microdex::station {

std::string DefaultWebDir() {
  if (const char* dir = std::getenv("MICRODEX_WEB_DIR"); dir != nullptr && *dir != '\0') {
    return dir;
  }
  return MICRODEX_WEB_DIR;
}

StationView::StationView(const scene::SceneModel& scene, int port, const std::string& web_dir,
                         const std::string& station_id, PageDevice* device)
    : device_(device), scene_json_(view::SceneViewJson(scene)) {
  info_json_ = "{\"station_id\":" + JsonQuote(station_id) +
               ",\"device\":" + (device != nullptr ? "\"page\"" : "\"watch\"") + "}";
  std::map<std::string, view::WebFile> files = view::LoadWebFiles(
      web_dir, {"station.html", "station.js", "frame_worker.js", "audio_worklet.js"});
  files["/"] = files["/station.html"];
  view::ViewServerConfig config;
  config.port = static_cast<std::uint16_t>(port);
  config.frame_credit = 4;
  auto dynamic = [this](const std::string& target) -> std::optional<view::WebFile> {
    if (target == "/scene.json") return view::WebFile{"application/json", scene_json_};
    if (target == "/info.json") return view::WebFile{"application/json", info_json_};
    return std::nullopt;
  };
  auto poll = [this] {
    if (frames_.Update())
      server_->BroadcastBinary(frames_.front().bytes.data(), frames_.front().size);
    view::AudioBlock block;
    while (audio_.TryPop(block)) {
      block.sent_ms = std::chrono::duration<double, std::milli>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();
      const std::string bytes = view::EncodeAudioBlock(block);
      server_->BroadcastAudio(bytes.data(), bytes.size());
    }
  };
  server_ = std::make_unique<view::ViewServer>(config, std::move(files), dynamic, poll,
                                               [this](const std::string& m) { return OnText(m); });
  server_->Start();
}

StationView::~StationView() { server_->Stop(); }

std::string StationView::OnText(const std::string& message) {
  if (device_ == nullptr) {
    throw std::invalid_argument("this station's device is not the page (--device page)");
  }
  const PageInput input = ParsePageInput(message);
  if (!device_->Push(input)) {
    ++inputs_dropped_;
    throw std::invalid_argument("device input queue full; input dropped");
  }
  return {};
}

}  // namespace microdex::station
