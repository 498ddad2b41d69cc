#pragma once
// Needle puncture of a tissue membrane (the composite task "needle through tissue", thesis
// §2.2 and §4: a curved needle should pass through tissue along its own circle so that it does
// not waver at the two points where it pierces and tear them).
//
// The tissue is the chapter-3 patch: a membrane at rest in the plane z = 0 of its frame S,
// deflecting out of plane (the antiplane FEM, common/fem). The needle is a rigid circular arc.
// Per step (README.md "Model"):
//   - before a puncture the needle's tip presses the membrane as a point tool of the wire's
//     radius (from above, or from below once the needle is through one hole); the FEM gives the
//     reaction. When it reaches puncture_force_N the membrane gives way: a hole is made where
//     the needle crosses the rest plane nearest its tip, and the membrane relaxes (the "pop");
//   - a hole holds the needle: its in-plane offset from the needle's nearest point pulls the
//     needle back with lateral_stiffness_N_per_m until the hole's strain |δ_xy| / wire radius
//     reaches tear_strain, beyond which the hole moves with the needle (it tears: elasto-
//     plastic, the torn length accumulates); its out-of-plane offset pulls with the membrane's
//     point stiffness there, measured at the puncture (puncture force / indentation depth);
//   - the needle slides through a hole against Coulomb friction μ (grip + |hole force|), as an
//     elasto-plastic bristle along the needle's tangent (Hayward and Armstrong's haptic friction
//     model): stiction up to the limit, then slip, with no velocity in the law.
// Driving the needle along its own circle keeps every hole on it: no lateral force, no tear.
// Any other motion moves the needle across its holes: that "off-circle" motion is summed.

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "common/fem/tissue_model.h"
#include "common/fem/tissue_step.h"

namespace microdex::puncture {

struct PunctureDef {
  double puncture_force_N = 0.03;           // the membrane gives way under the tip at this force
  double wire_radius_m = 0.1e-3;            // the needle's wire: tip contact and hole radius
  double lateral_stiffness_N_per_m = 200;   // in-plane resistance of a hole to the needle
  double tear_strain = 1.0;                 // hole strain |δ_xy| / wire radius at which it tears
  double grip_force_N = 0.01;               // the hole's grip on the wire (friction's normal load)
  double friction_coefficient = 0.3;        // μ, needle on tissue
  double bristle_stiffness_N_per_m = 2000;  // stiction spring along the needle before it slips
  // Throws std::invalid_argument("field: reason") for the first bad field.
  void Validate() const;
};

// The needle in the tissue frame S: p(s) = c + ρ (cos s e1 + sin s e2), s ∈ [0, sweep]; the
// tail (held by the tool) at s = 0, the tip at s = sweep.
struct NeedleArc {
  Eigen::Vector3d c_S = Eigen::Vector3d::Zero();
  Eigen::Vector3d e1_S = Eigen::Vector3d::UnitX();
  Eigen::Vector3d e2_S = Eigen::Vector3d::UnitY();
  double radius_m = 3e-3;
  double sweep_rad = 2.356194490192345;  // 3/8 circle
  Eigen::Vector3d Point(double s) const;
  Eigen::Vector3d Tangent(double s) const;  // unit, towards the tip
  bool operator==(const NeedleArc&) const = default;
};

// The arc parameter of the needle point nearest q (analytic: the azimuth of q's projection on
// the needle's plane, clamped to the nearer end outside [0, sweep]); writes the distance. A
// point on the circle's axis is equally near every point of the circle: the answer is then the
// tip end (s = sweep).
double ClosestArcParameter(const NeedleArc& arc, const Eigen::Vector3d& q_S, double* distance_m);

// The arc parameters s ∈ [0, sweep] where the needle crosses the plane z = 0 (none, one or
// two, ascending); returns their count.
int RestPlaneCrossings(const NeedleArc& arc, std::array<double, 2>& s_out);

inline constexpr int kMaxHoles = 4;

enum class HoleStatus : std::uint8_t {
  kOpen,       // the needle passes through it
  kLeftByTip,  // the needle was drawn back out of it
  kLeftByTail  // the needle has passed through it completely
};

struct Hole {
  HoleStatus status = HoleStatus::kOpen;
  std::uint8_t from_below = 0;                     // pierced by the tip coming up from below
  Eigen::Vector3d p_SH = Eigen::Vector3d::Zero();  // the hole at rest (z = 0), m; moves on tearing
  double s_rad = 0;                     // needle parameter at the hole (its nearest point)
  double s_anchor_rad = 0;              // where the friction bristle is anchored on the needle
  double normal_stiffness_N_per_m = 0;  // the membrane's point stiffness, measured at puncture
  double strain = 0;                    // |δ_xy| / wire radius after tearing
  double friction_N = 0;  // the friction part of f_S, along the needle's tangent (to the tip)
  Eigen::Vector3d f_S = Eigen::Vector3d::Zero();  // the hole's force on the needle, N
};

struct PunctureState {
  std::array<Hole, kMaxHoles> holes{};
  std::int32_t num_holes = 0;   // holes made (capacity kMaxHoles; more are counted only)
  std::int32_t punctures = 0;   // every puncture, including those beyond the capacity
  std::uint8_t pressing = 0;    // the tip pressed the membrane this step ...
  double press_N = 0;           // ... this hard (below the puncture force)
  std::uint8_t have_entry = 0;  // the first hole from above ...
  std::uint8_t have_exit = 0;   // ... and the first from below, as made
  Eigen::Vector3d p_S_entry = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_S_exit = Eigen::Vector3d::Zero();
  double peak_strain = 0;   // the largest hole strain so far
  double torn_m = 0;        // the length the holes have torn, summed
  double off_circle_m = 0;  // the needle's motion across its holes (normal to its tangent), summed
  double peak_press_N = 0;  // the largest force the tip pressed with before a puncture
  NeedleArc prev_arc;       // the needle at the previous step (for the motion across the holes)
  std::uint8_t have_prev = 0;
  std::uint32_t warnings = 0;                     // steps skipped for a non-finite needle
  Eigen::Vector3d f_S = Eigen::Vector3d::Zero();  // tissue on the needle this step, N
};

// Open holes (the needle passes through them). The tip is below the membrane when that count
// is odd (the tail is held from above).
int CountOpenHoles(const PunctureState& state);

// One step: the tip against the membrane (the FEM step writes `tissue`), the holes, friction,
// tearing, the metrics; writes state.f_S. Never allocates (StepTissue's own contract aside),
// never throws; a non-finite needle skips the step and counts a warning.
void StepPuncture(const PunctureDef& def, const fem::TissueModel& model, const NeedleArc& arc,
                  fem::TissueWorkspace& ws, fem::TissueState& tissue, PunctureState& state);

}  // namespace microdex::puncture
