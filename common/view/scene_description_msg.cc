#include "common/view/scene_description_msg.h"

namespace microdex::view {

msg::SceneDescription ToSceneDescription(const SceneFiles& files, const std::string& station_id,
                                         const std::string& session_id, std::int64_t stamp_ns) {
  msg::SceneDescription d;
  d.station_id(station_id);
  d.session_id(session_id);
  d.step(0);
  d.stamp_ns(stamp_ns);
  d.scene_path(files.scene_path);
  d.hash(files.hash);
  d.files().resize(files.files.size());
  for (std::size_t i = 0; i < files.files.size(); ++i) {
    d.files()[i].path(files.files[i].path);
    d.files()[i].bytes().assign(files.files[i].bytes.begin(), files.files[i].bytes.end());
  }
  return d;
}

}  // namespace microdex::view
