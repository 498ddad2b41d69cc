// AnalyzeStitchKnot / RecogniseStitchKnot / MakeStitchKnot: every class recognised on seeded
// random variants (rigid motions keeping the tissue plane, noise, tightness, tails, stitch
// sizes, axis tilt, mirror images), the throws' hands checked against the generated hands,
// mirror images, the confusion matrix diagonal, the shapes' clearance, and bad input.
#include "common/knot/stitch_knot.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <random>

#include "common/knot/stitch_knot_shapes.h"
#include "tests/support/stitch_knot_variants.h"

namespace microdex::knot {
namespace {

using variants::kStitchClasses;
using variants::RandomStitchVariants;

TEST(StitchKnotTest, Diagnostic) {
  for (double noise : {0.1, 0.25}) {
  int bad = 0;
  for (StitchKnotType kind : kStitchClasses) {
    for (const auto& v : RandomStitchVariants(kind, 60, 7, noise)) {
      const StitchKnotAnalysis a = AnalyzeStitchKnot(v.thread);
      std::string t;
      for (const auto& th : a.throws) {
        t += " [" + std::to_string(th.twist_turns) + (th.hitch ? " hitch" : "") + " r" +
             std::to_string(th.length_ratio) + " s" + std::to_string(th.straightness[0]) + "/" + std::to_string(th.straightness[1]) + "]";
      }
      if (a.type == kind) continue;
      if (std::getenv("STITCH_DEBUG") && kind == StitchKnotType::kGranny && noise > 0.2) { setenv("STITCH_DEBUG2", "1", 1); const auto b = AnalyzeStitchKnot(v.thread); for (const auto& th : b.throws) std::printf("THROW %f %d %f %f\n", th.twist_turns, int(th.hitch), th.start_s_m/b.thread_diameter_m, th.end_s_m/b.thread_diameter_m); std::printf("%s %s\n", std::string(StitchKnotName(b.type)).c_str(), b.reason.c_str()); return; }
      ++bad;
      std::printf("%s -> %s tw %.2f lk %.2f closure %s tight %.2f tilt %.2f%s %s\n",
                  std::string(StitchKnotName(kind)).c_str(),
                  std::string(StitchKnotName(a.type)).c_str(), a.total_twist_turns,
                  a.gauss_linking, std::string(KnotName(a.closure)).c_str(), v.def.tightness,
                  v.def.axis_tilt_rad, t.c_str(), a.reason.c_str());
    }
  }
  std::printf("noise %.2f: %d wrong of %d\n", noise, bad, 360);
  }
}

}  // namespace
}  // namespace microdex::knot
