#include <stdexcept>

#include "station/grasp_module.h"
#include "station/knot_quiz_module.h"
#include "station/loop_module.h"
#include "station/module.h"
#include "station/needle_module.h"
#include "station/placement_module.h"
#include "station/stitch_tissue.h"
#include "station/thread_module.h"
#include "station/tissue_module.h"
#include "station/tremor_module.h"

namespace microdex::station {

std::vector<std::unique_ptr<Module>> MakeModules(const scene::SceneModel& scene) {
  std::vector<std::unique_ptr<Module>> modules;
  // The knot-tying stitch on the tissue, built once for the thread and tissue modules.
  const SharedStitch stitch = scene.HasModule("thread") && scene.HasModule("tissue")
                                  ? MakeSharedStitchOnTissue(scene)
                                  : nullptr;
  for (const std::string& name : scene.modules) {
    if (name == "needle") {
      modules.push_back(std::make_unique<NeedleModule>(scene));
    } else if (name == "tremor") {
      modules.push_back(std::make_unique<TremorModule>(scene));
    } else if (name == "thread") {
      modules.push_back(std::make_unique<ThreadModule>(scene, stitch));
    } else if (name == "tissue") {
      modules.push_back(std::make_unique<TissueModule>(scene, stitch));
    } else if (name == "grasp") {
      modules.push_back(std::make_unique<GraspModule>(scene));
    } else if (name == "loop") {
      modules.push_back(std::make_unique<LoopModule>(scene));
    } else if (name == "knots") {
      modules.push_back(std::make_unique<KnotQuizModule>(scene));
    } else if (name == "placement") {
      modules.push_back(std::make_unique<PlacementModule>(scene));
    } else {
      throw std::runtime_error(scene.path + ": modules: '" + name +
                               "' has no station module in this build yet");
    }
  }
  if (modules.size() > static_cast<std::size_t>(kMaxStationModules)) {
    throw std::runtime_error(scene.path + ": modules: more than " +
                             std::to_string(kMaxStationModules));
  }
  return modules;
}

}  // namespace microdex::station
