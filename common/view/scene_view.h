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

// A JSON string literal (quotes, backslashes and control characters escaped).
std::string JsonQuote(const std::string& text);

// A JSON number with `digits` significant digits (printf %g); "null" for NaN and infinities
// (JSON has no such numbers). The scene uses 9 digits (µm in metres survive), the console's
// station list 6 (readouts).
std::string JsonNumber(double v, int digits = 9);

}  // namespace microdex::view
