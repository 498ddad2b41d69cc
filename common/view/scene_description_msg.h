#pragma once
// A scene's files on the SceneDescription topic (idl/scene_description.idl): the sample a
// station (or a replay) sends once before its StationInfo names their hash.

#include <cstdint>
#include <string>

#include "common/view/scene_files.h"
#include "scene_description.h"

namespace microdex::view {

msg::SceneDescription ToSceneDescription(const SceneFiles& files, const std::string& station_id,
                                         const std::string& session_id, std::int64_t stamp_ns);

}  // namespace microdex::view
