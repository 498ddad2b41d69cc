#pragma once
// The knot-tying scene's stitch on the tissue module's patch: the rods of the stitch (the
// first puncture, the bite, the second puncture; thread::KnotStitchDef::Colliders) as points
// of the patch, and the patch's compliance there. The thread's loads on the rods along the
// patch's normal (thread::CalcColliderLoad), low-passed, load the patch at them; the rods move
// by the patch's displacement under those loads. The thread module moves the rods; the tissue
// module adds the loads' field to the patch it draws and under the instrument it presses with.
// Both use the one MakeSharedStitchOnTissue builds, so both see the same numbers. With
// knot_tying.stitch_in_plane the thread module also builds the patch's in-plane compliance
// (fem::CalcInPlaneCompliance): the loads along the surface, low-passed, move the rods in the
// patch's plane (the legs draw the punctures together). The tissue module draws only the
// normal displacement.

#include <Eigen/Core>
#include <array>
#include <memory>
#include <optional>

#include "common/fem/in_plane_compliance.h"
#include "common/fem/point_compliance.h"
#include "common/scene/scene.h"

namespace microdex::station {

inline constexpr int kStitchRods = 3;
inline constexpr int kBiteRod = 1;

struct StitchOnTissue {
  Eigen::Vector3d n_W = Eigen::Vector3d::UnitZ();  // the patch's normal (out of the tissue)
  std::array<Eigen::Vector2d, kStitchRods> p_S{};  // the rods' points in the patch plane
  fem::PointCompliance compliance;                 // at p_S, along n_W
  // The patch's in-plane axes (its x and y) in W, and its in-plane compliance at p_S
  // (fem::InPlaneCompliance, fixed-size: the haptic step multiplies by it; built only with
  // knot_tying.stitch_in_plane).
  using InPlaneMatrix = Eigen::Matrix<double, 2 * kStitchRods, 2 * kStitchRods>;
  Eigen::Matrix<double, 3, 2> t_W = Eigen::Matrix<double, 3, 2>::Zero();
  bool has_in_plane = false;
  InPlaneMatrix in_plane_m_per_N = InPlaneMatrix::Zero();
  // The rods' displacement along n_W for the loads (N, along n_W) on them, m.
  Eigen::Vector3d Displacement_m(const std::array<double, kStitchRods>& load_N) const {
    return compliance.c_m_per_N * Eigen::Map<const Eigen::Vector3d>(load_N.data());
  }
  bool HasInPlane() const { return has_in_plane; }
  // Rod k's displacement in the patch's plane, in W, for the in-plane loads (x, y of S per rod).
  Eigen::Vector3d InPlaneDisplacement_W(const std::array<double, 2 * kStitchRods>& load_N,
                                        int k) const {
    using Vector6d = Eigen::Matrix<double, 2 * kStitchRods, 1>;
    const Eigen::Vector2d u_S =
        in_plane_m_per_N.middleRows<2>(2 * k) * Eigen::Map<const Vector6d>(load_N.data());
    return t_W * u_S;
  }
};

// Empty unless the scene ties a knot (knot_tying) on a tissue module with stitch_relax_s > 0.
// display_level: the grid of the fields per newton (compliance.grid_m_per_N). with_in_plane:
// also the in-plane compliance, if the scene asks for it (knot_tying.stitch_in_plane; about
// 1 s on one core). Throws std::runtime_error naming the scene and the field when a rod lies
// off the patch.
std::optional<StitchOnTissue> MakeStitchOnTissue(const scene::SceneModel& scene, int display_level,
                                                 bool with_in_plane = false);

// The one stitch of a station's modules: built once (at the tissue's display level, with the
// in-plane compliance if the scene asks for it) and shared by the thread module, which moves
// the rods, and the tissue module, which draws and presses the patch they load. Null unless
// MakeStitchOnTissue would build one.
using SharedStitch = std::shared_ptr<const StitchOnTissue>;
SharedStitch MakeSharedStitchOnTissue(const scene::SceneModel& scene);

}  // namespace microdex::station
