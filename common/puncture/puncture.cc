#include "common/puncture/puncture.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "common/fem/tool_contact.h"

namespace microdex::puncture {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

void Require(bool ok, const char* field, const char* reason) {
  if (!ok) throw std::invalid_argument(std::string(field) + ": " + reason);
}

bool Positive(double v) { return std::isfinite(v) && v > 0; }

// The azimuth of q's projection on the needle's plane in [0, 2π); false on the axis.
bool Azimuth(const NeedleArc& arc, const Eigen::Vector3d& q_S, double* phi) {
  const Eigen::Vector3d q = q_S - arc.c_S;
  const double u = q.dot(arc.e1_S), v = q.dot(arc.e2_S);
  if (u == 0 && v == 0) return false;
  double a = std::atan2(v, u);
  if (a < 0) a += kTwoPi;
  *phi = a;
  return true;
}

// The needle's nearest point to q: its parameter, and whether q's azimuth lies within the
// sweep (false: the nearest point is an end and q lies beyond it).
double Project(const NeedleArc& arc, const Eigen::Vector3d& q_S, bool* within) {
  double phi = 0;
  if (!Azimuth(arc, q_S, &phi)) {
    *within = true;
    return arc.sweep_rad;
  }
  *within = phi <= arc.sweep_rad;
  if (*within) return phi;
  const double d_tail = (q_S - arc.Point(0)).squaredNorm();
  const double d_tip = (q_S - arc.Point(arc.sweep_rad)).squaredNorm();
  return d_tail < d_tip ? 0.0 : arc.sweep_rad;
}

bool AllFinite(const NeedleArc& arc) {
  return arc.c_S.allFinite() && arc.e1_S.allFinite() && arc.e2_S.allFinite() &&
         std::isfinite(arc.radius_m) && std::isfinite(arc.sweep_rad) && arc.radius_m > 0 &&
         arc.sweep_rad > 0;
}

// Lets the membrane relax (no tool on it) unless it already has.
void Relax(const fem::TissueModel& model, const Eigen::Vector3d& p_S_tip, fem::TissueWorkspace& ws,
           fem::TissueState& tissue) {
  if (tissue.status == fem::TissueStatus::kNoContact && tissue.num_contacts == 0) return;
  const Eigen::Vector3d above(p_S_tip.x(), p_S_tip.y(), 1.0);
  fem::StepTissue(model, fem::MakePointTool(above, 0.0), ws, tissue);
}

// The hole's forces on the needle this step: the elasto-plastic lateral spring (tearing), the
// membrane's normal spring and the bristle friction along the needle.
void StepHole(const PunctureDef& def, const NeedleArc& arc, PunctureState& st, Hole& hole) {
  bool within = false;
  const double s = Project(arc, hole.p_SH, &within);
  if (!within) {
    hole.status = s == 0.0 ? HoleStatus::kLeftByTail : HoleStatus::kLeftByTip;
    hole.f_S.setZero();
    hole.strain = 0;
    return;
  }
  hole.s_rad = s;
  const Eigen::Vector3d p = arc.Point(s);
  const Eigen::Vector3d t = arc.Tangent(s);
  Eigen::Vector3d delta = hole.p_SH - p;
  // Tearing: the in-plane offset is capped at the tear strain; beyond it the hole moves.
  Eigen::Vector2d d_xy = delta.head<2>();
  const double limit_m = def.tear_strain * def.wire_radius_m;
  const double n = d_xy.norm();
  if (n > limit_m) {
    const double move = n - limit_m;
    hole.p_SH.head<2>() -= d_xy * (move / n);
    st.torn_m += move;
    d_xy *= limit_m / n;
  }
  hole.strain = d_xy.norm() / def.wire_radius_m;
  st.peak_strain = std::max(st.peak_strain, hole.strain);
  const Eigen::Vector3d f_hold(def.lateral_stiffness_N_per_m * d_xy.x(),
                               def.lateral_stiffness_N_per_m * d_xy.y(),
                               hole.normal_stiffness_N_per_m * delta.z());
  // Friction: the needle has slid ρ (s_anchor − s) along t through the hole since the bristle
  // was anchored; the bristle pulls it back up to the Coulomb limit, then slips.
  const double limit_N = def.friction_coefficient * (def.grip_force_N + f_hold.norm());
  const double x_m = arc.radius_m * (hole.s_anchor_rad - s);
  double f_t = -def.bristle_stiffness_N_per_m * x_m;
  if (std::abs(f_t) > limit_N) {
    const double sign = x_m > 0 ? 1.0 : -1.0;
    f_t = -sign * limit_N;
    hole.s_anchor_rad = s + sign * limit_N / (def.bristle_stiffness_N_per_m * arc.radius_m);
  }
  hole.friction_N = f_t;
  hole.f_S = f_hold + f_t * t;
  // The needle's own motion at the hole across its tangent. Against the tangent halfway
  // through the step: a turn about the needle's own axis moves each needle point along a chord
  // parallel to it, so the sum is exactly zero along the circle.
  if (st.have_prev != 0) {
    const Eigen::Vector3d dp = p - st.prev_arc.Point(s);
    const Eigen::Vector3d t_mid = (t + st.prev_arc.Tangent(s)).normalized();
    if (t_mid.allFinite()) st.off_circle_m += (dp - dp.dot(t_mid) * t_mid).norm();
  }
}

// A new hole where the needle crosses the rest plane nearest its tip (where the tip has just
// gone through); the tip's own point when the needle does not cross it.
void MakeHole(const NeedleArc& arc, bool from_below, double force_N, double depth_m,
              PunctureState& st) {
  ++st.punctures;
  std::array<double, 2> crossings{};
  const int count = RestPlaneCrossings(arc, crossings);
  const double s = count > 0 ? crossings[count - 1] : arc.sweep_rad;
  Eigen::Vector3d p_SH = arc.Point(s);
  p_SH.z() = 0;
  if (from_below) {
    if (st.have_exit == 0) st.p_S_exit = p_SH;
    st.have_exit = 1;
  } else {
    if (st.have_entry == 0) st.p_S_entry = p_SH;
    st.have_entry = 1;
  }
  // Reuse a slot the needle has left, else a new one.
  Hole* slot = nullptr;
  for (int i = 0; i < st.num_holes; ++i) {
    if (st.holes[i].status != HoleStatus::kOpen) slot = &st.holes[i];
  }
  if (slot == nullptr && st.num_holes < kMaxHoles) slot = &st.holes[st.num_holes++];
  if (slot == nullptr) return;  // counted, not held (more holes than the needle can be in)
  *slot = Hole{};
  slot->from_below = from_below ? 1 : 0;
  slot->p_SH = p_SH;
  slot->s_rad = s;
  slot->s_anchor_rad = s;
  slot->normal_stiffness_N_per_m = force_N / depth_m;
}

}  // namespace

void PunctureDef::Validate() const {
  Require(Positive(puncture_force_N), "puncture_force_N", "expected a positive force in N");
  Require(Positive(wire_radius_m), "wire_radius_m", "expected a positive radius in m");
  Require(std::isfinite(lateral_stiffness_N_per_m) && lateral_stiffness_N_per_m >= 0,
          "lateral_stiffness_N_per_m", "expected a stiffness >= 0 in N/m");
  Require(Positive(tear_strain), "tear_strain", "expected a positive strain");
  Require(std::isfinite(grip_force_N) && grip_force_N >= 0, "grip_force_N",
          "expected a force >= 0 in N");
  Require(std::isfinite(friction_coefficient) && friction_coefficient >= 0, "friction_coefficient",
          "expected a coefficient >= 0");
  Require(Positive(bristle_stiffness_N_per_m), "bristle_stiffness_N_per_m",
          "expected a positive stiffness in N/m");
}

Eigen::Vector3d NeedleArc::Point(double s) const {
  return c_S + radius_m * (std::cos(s) * e1_S + std::sin(s) * e2_S);
}

Eigen::Vector3d NeedleArc::Tangent(double s) const {
  return -std::sin(s) * e1_S + std::cos(s) * e2_S;
}

double ClosestArcParameter(const NeedleArc& arc, const Eigen::Vector3d& q_S, double* distance_m) {
  bool within = false;
  const double s = Project(arc, q_S, &within);
  if (distance_m != nullptr) *distance_m = (q_S - arc.Point(s)).norm();
  return s;
}

int RestPlaneCrossings(const NeedleArc& arc, std::array<double, 2>& s_out) {
  // z(s) = c_z + A cos s + B sin s = c_z + R cos(s − ψ).
  const double a = arc.radius_m * arc.e1_S.z(), b = arc.radius_m * arc.e2_S.z();
  const double r = std::hypot(a, b);
  if (!(r > 0)) return 0;
  const double c = -arc.c_S.z() / r;
  if (!(std::abs(c) <= 1)) return 0;
  const double psi = std::atan2(b, a), alpha = std::acos(c);
  int count = 0;
  for (const double s0 : {psi - alpha, psi + alpha}) {
    double s = std::fmod(s0, kTwoPi);
    if (s < 0) s += kTwoPi;
    if (s <= arc.sweep_rad && (count == 0 || s != s_out[0])) s_out[count++] = s;
  }
  if (count == 2 && s_out[1] < s_out[0]) std::swap(s_out[0], s_out[1]);
  return count;
}

int CountOpenHoles(const PunctureState& state) {
  int open = 0;
  for (int i = 0; i < state.num_holes; ++i) open += state.holes[i].status == HoleStatus::kOpen;
  return open;
}

void StepPuncture(const PunctureDef& def, const fem::TissueModel& model, const NeedleArc& arc,
                  fem::TissueWorkspace& ws, fem::TissueState& tissue, PunctureState& st) {
  st.f_S.setZero();
  st.pressing = 0;
  st.press_N = 0;
  if (!AllFinite(arc)) {
    ++st.warnings;
    return;
  }
  for (int i = 0; i < st.num_holes; ++i) {
    Hole& hole = st.holes[i];
    if (hole.status != HoleStatus::kOpen) continue;
    StepHole(def, arc, st, hole);
    st.f_S += hole.f_S;
  }
  // The tip against the membrane, from the side it is on.
  const bool below = CountOpenHoles(st) % 2 == 1;
  const Eigen::Vector3d tip = arc.Point(arc.sweep_rad);
  const double depth_m = below ? tip.z() : -tip.z();
  const double margin_m = def.wire_radius_m;
  const bool over_patch = tip.x() > margin_m && tip.x() < model.def.length_x_m - margin_m &&
                          tip.y() > margin_m && tip.y() < model.def.length_y_m - margin_m;
  if (over_patch && depth_m > 0) {
    // From below, the membrane is pushed up: the mirror image of a press from above.
    const Eigen::Vector3d p_press(tip.x(), tip.y(), -depth_m);
    fem::StepTissue(model, fem::MakePointTool(p_press, def.wire_radius_m), ws, tissue);
    const double f_N = tissue.f_T_S.z();  // up on a tool pressing from above
    if (fem::IsGood(tissue.status) && std::isfinite(f_N)) {
      st.pressing = 1;
      st.peak_press_N = std::max(st.peak_press_N, f_N);
      if (f_N >= def.puncture_force_N) {
        MakeHole(arc, below, f_N, depth_m, st);
        Relax(model, tip, ws, tissue);
        st.pressing = 0;
      } else {
        st.press_N = f_N;
        st.f_S.z() += below ? -f_N : f_N;
      }
    }
  } else {
    Relax(model, tip, ws, tissue);
  }
  st.prev_arc = arc;
  st.have_prev = 1;
}

}  // namespace microdex::puncture
