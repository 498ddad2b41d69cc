#pragma once
// The knot-tying scene's stitch on the tissue module's patch: the rods of the stitch (the
// first puncture, the bite, the second puncture; thread::KnotStitchDef::Colliders) as points
// of the patch, and the patch's compliance there. The thread's loads on the rods along the
// patch's normal (thread::CalcColliderLoad), low-passed, load the patch at them; the rods move
// by the patch's displacement under those loads. The thread module moves the rods; the tissue
// module adds the loads' field to the patch it draws and under the instrument it presses with.
// Both build this from the scene alike, so both see the same numbers. Left out: the in-plane
// pull that draws the punctures together (the antiplane model has no in-plane displacement).

#include <Eigen/Core>
#include <array>
#include <optional>

#include "common/fem/point_compliance.h"
#include "common/scene/scene.h"

namespace microdex::station {

inline constexpr int kStitchRods = 3;
inline constexpr int kBiteRod = 1;

struct StitchOnTissue {
  Eigen::Vector3d n_W = Eigen::Vector3d::UnitZ();  // the patch's normal (out of the tissue)
  std::array<Eigen::Vector2d, kStitchRods> p_S{};  // the rods' points in the patch plane
  fem::PointCompliance compliance;                 // at p_S, along n_W
  // The rods' displacement along n_W for the loads (N, along n_W) on them, m.
  Eigen::Vector3d Displacement_m(const std::array<double, kStitchRods>& load_N) const {
    return compliance.c_m_per_N * Eigen::Map<const Eigen::Vector3d>(load_N.data());
  }
};

// Empty unless the scene ties a knot (knot_tying) on a tissue module with stitch_relax_s > 0.
// display_level: the grid of the fields per newton (compliance.grid_m_per_N). Throws
// std::runtime_error naming the scene and the field when a rod lies off the patch.
std::optional<StitchOnTissue> MakeStitchOnTissue(const scene::SceneModel& scene, int display_level);

}  // namespace microdex::station
