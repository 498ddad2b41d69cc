#pragma once
// The station's microscope view (`--view PORT`): serves the station page (bundled from
// station/page/ and common/view/src/) and the scene (/scene.json) on 127.0.0.1, and streams
// the state frames the publisher thread encodes at the mirror rate. With `--device page` the
// page's keyboard and mouse messages go to the PageDevice's ring.
//
// Threads: the publisher thread fills frames() (TripleBuffer: producer publisher thread,
// consumer the view server's thread, which polls it every 2 ms and broadcasts a new frame);
// the view server's thread pushes device input into the PageDevice's SpscRing (consumer: the
// haptic thread). The haptic thread never meets the server.

#include <memory>
#include <string>

#include "common/scene/scene.h"
#include "common/view/view_frame.h"
#include "common/view/view_server.h"
#include "station/page_device.h"
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
  std::uint16_t port() const { return server_->port(); }
  std::uint64_t inputs_dropped() const { return inputs_dropped_.load(); }

 private:
  std::string OnText(const std::string& message);

  rt::TripleBuffer<view::FrameBytes> frames_;  // producer: publisher; consumer: view server
  PageDevice* device_;
  std::string scene_json_;
  std::string info_json_;
  std::atomic<std::uint64_t> inputs_dropped_{0};
  std::unique_ptr<view::ViewServer> server_;
};

}  // namespace microdex::station
