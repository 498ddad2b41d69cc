#include "station/stitch_tissue.h"

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

#include "common/fem/tissue_model.h"

namespace microdex::station {

std::optional<StitchOnTissue> MakeStitchOnTissue(const scene::SceneModel& scene, int display_level,
                                                 bool with_in_plane) {
  if (!scene.knot_tying || !scene.tissue || !(scene.knot_tying->stitch_relax_s > 0)) {
    return std::nullopt;
  }
  StitchOnTissue out;
  const Eigen::Isometry3d X_SW = scene.tissue->X_WS.inverse();
  out.n_W = scene.tissue->X_WS.linear().col(2);
  out.t_W = scene.tissue->X_WS.linear().leftCols<2>();
  // The rods' centres (their radii do not move them along the patch).
  const std::vector<thread::Collider> rods = scene.knot_tying->stitch.Colliders(0.0);
  for (int k = 0; k < kStitchRods; ++k) {
    const thread::Collider& c = rods[static_cast<std::size_t>(k)];
    const Eigen::Vector3d p_S = X_SW * (0.5 * (c.a_W + c.b_W));
    out.p_S[static_cast<std::size_t>(k)] = p_S.head<2>();
  }
  // The point tool's compliance depends on how many cells its contact disc spans (one node
  // under a disc narrower than a cell is a smaller, softer disc): solved where the cells are at
  // most half its radius (microdex-bench stitch), up to the model's finest level. Built once.
  fem::TissueDef def = scene.tissue->def;
  while (def.level < def.max_level && std::max(def.length_x_m, def.length_y_m) / (1 << def.level) >
                                          0.5 * scene.tissue->contact_radius_m) {
    ++def.level;
  }
  const fem::TissueModel model = fem::BuildTissueModel(def);
  try {
    out.compliance =
        fem::CalcPointCompliance(model, out.p_S, scene.tissue->contact_radius_m, display_level);
  } catch (const std::exception& e) {
    throw std::runtime_error(scene.path + ": knot_tying.stitch: on the tissue patch: " + e.what());
  }
  if (with_in_plane && scene.knot_tying->stitch_in_plane) {
    // The same grid as the normal compliance's: cells at most half the contact disc's radius
    // (level 7 against 8 differ by 8 % at the scene's 0.3 mm disc: in_plane_compliance_test).
    try {
      out.in_plane_m_per_N =
          fem::CalcInPlaneCompliance(def, def.level, out.p_S, scene.tissue->contact_radius_m)
              .c_m_per_N;
      out.has_in_plane = true;
    } catch (const std::exception& e) {
      throw std::runtime_error(scene.path + ": knot_tying.stitch_in_plane: " + e.what());
    }
  }
  return out;
}

SharedStitch MakeSharedStitchOnTissue(const scene::SceneModel& scene) {
  if (!scene.tissue) return nullptr;
  std::optional<StitchOnTissue> stitch =
      MakeStitchOnTissue(scene, scene.tissue->display_level, /*with_in_plane=*/true);
  if (!stitch) return nullptr;
  return std::make_shared<const StitchOnTissue>(std::move(*stitch));
}

}  // namespace microdex::station
