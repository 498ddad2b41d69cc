#pragma once
// A scene as the view pages need it (JSON): the shapes to draw and where, resolved from the
// scene model once (the wire course sampled into a polyline, poses as position + quaternion),
// so that the pages need no knowledge of the physics' parameter files. The pages build their
// three.js objects from it (common/view/src/scene_objects.ts); README.md "Scene JSON" lists
// the fields.

#include <string>

#include "common/scene/scene.h"

namespace microdex::view {

std::string SceneViewJson(const scene::SceneModel& scene);

}  // namespace microdex::view
