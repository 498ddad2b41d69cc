#pragma once
// Knot tying with the thread module (thesis §5.5, Fig. 5.7): the scripted instrument tie, its
// hold, and the stitch it is tied around. Shared by the knot-tying scene's station module,
// microdex-bench thread --tie and the knot tests.
//
// The scripts are plain values of fixed size: constructing, copying and stepping one never
// allocates, so a station keeps the script of the throw under way in its state and starts the
// next throw in the haptic thread. The thread's workspace is passed to Step (a cache).

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "common/thread/colliders.h"
#include "common/thread/thread_model.h"

namespace microdex::thread {

// The two hands of a bimanual tie: the standing hand holds the standing end, the driver (the
// needle holder) holds the working end. Grasp slots of the thread state.
struct KnotTyingHands {
  int standing_slot = -1;
  int driver_slot = -1;
};

// Fixed bounds of a script: colliders (two pegs, two jaws and the fixed ones) and waypoints.
inline constexpr int kMaxKnotFixedColliders = 4;
inline constexpr int kMaxKnotTieColliders = 4 + kMaxKnotFixedColliders;
inline constexpr int kMaxKnotThrowPasses = 3;
inline constexpr int kMaxKnotThrowWaypoints = 4 + (36 * kMaxKnotThrowPasses + 18 + 1) + 2;

// Field visitors of the scripts (VisitFields).
template <typename E, typename V>
void VisitEnum(const char* name, E& e, V& v) {
  using U = std::underlying_type_t<std::remove_const_t<E>>;
  using P = std::conditional_t<std::is_const_v<E>, const U, U>;
  v(name, reinterpret_cast<P*>(&e), 1);
}
template <typename C, typename V>
void VisitCollider(C& c, V& v) {
  VisitEnum("colliders[].kind", c.kind, v);
  v("colliders[].a_W", c.a_W.data(), 3);
  v("colliders[].b_W", c.b_W.data(), 3);
  v("colliders[].radius_m", &c.radius_m, 1);
  v("colliders[].enabled", &c.enabled, 1);
  v("colliders[].ignore_node", &c.ignore_node, 1);
  v("colliders[].ignore_links", &c.ignore_links, 1);
}

// One throw, tied as by hand on a jig (thesis §5.5, Fig. 5.7): the driver carries the working
// end under a first peg, over it and a second peg (the loop), back across the standing part
// and `passes` times around the standing part inside the loop (a helix), then away to +x.
// The helix is wrapped on an instrument's jaws: two rigid rods along the standing part, one on
// either side of it, which keep the standing part (held only by thread tension) inside the
// wraps, as in an instrument tie. Meanwhile the standing hand keeps the thread taut at
// hold_tension_N by feeding or taking in thread along x. Then pegs and jaws shrink to nothing
// over 0.1 s (release: the instrument opens) and both hands pull apart until each feels
// pull_tension_N. passes = 1 ties an overhand knot (trefoil), 2 a double overhand; right picks the
// handedness (all crossings positive seen from +z). A second throw on the same thread, next to the
// first, makes a square (opposite handedness) or granny knot; it is tied with the other end (the
// hands swap roles), whose tail is the long one after the first throw. With the driver's end
// towards -x of the knot the jig is turned by pi about the y axis.
struct KnotThrowOptions {
  int passes = 1;
  bool right = true;
  double knot_x_m = 4e-3;  // the jig's centre along the standing part
  double speed_m_per_s = 4e-3;
  double pull_speed_m_per_s = 2e-3;
  double hold_tension_N = 2e-3;
  double pull_tension_N = 10e-3;
  double max_pull_m = 8e-3;
  // The pull: false, both hands move apart at pull_speed_m_per_s until each feels
  // pull_tension_N (position control: a hand that already feels it goes on pulling while the
  // other does not); true, each hand limits its own force, moving out at most at
  // pull_speed_m_per_s while below 1.05 pull_tension_N and giving thread back while above.
  bool force_limited_pull = false;
  // Colliders present throughout and never withdrawn with the jig (a stitch), at most
  // kMaxKnotFixedColliders.
  std::vector<Collider> fixed_colliders;
  // Throws std::invalid_argument naming the bad field.
  void Validate() const;
};

// Where the hands are this step against where the script plans them (a trainee's tremor and
// drift; zero for the scripted tie). Each hand's grasp target is its plan plus its offset.
struct KnotHandOffsets {
  Eigen::Vector3d standing_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d driver_W = Eigen::Vector3d::Zero();
};

class KnotThrowScript {
 public:
  enum class Phase : int { kLoop, kHelix, kExit, kRelease, kPull, kDone };

  KnotThrowScript() = default;  // no throw: done
  // The jig is placed on the standing part as it lies in `state` (it need not be straight
  // after an earlier throw). Precomputes the driver's path. The fixed colliders are the
  // options' followed by more_fixed. Throws std::invalid_argument for bad options (Validate,
  // or more fixed colliders than kMaxKnotFixedColliders).
  KnotThrowScript(const ThreadModel& model, const ThreadState& state, KnotTyingHands hands,
                  const KnotThrowOptions& options, std::span<const Collider> more_fixed = {});

  // Moves the hands by one time step of model.def.time_step_s and steps the thread. Returns
  // false when the throw is over. The driver advances along its path by advance_m this step
  // (before the release; the scripted tie: speed_m_per_s times the step).
  bool Step(const ThreadModel& model, ThreadWorkspace& ws, ThreadState& state,
            const KnotHandOffsets& offsets, double advance_m);
  bool Step(const ThreadModel& model, ThreadWorkspace& ws, ThreadState& state) {
    return Step(model, ws, state, KnotHandOffsets{}, speed_m_per_s_ * model.def.time_step_s);
  }
  Phase phase() const { return phase_; }
  bool done() const { return phase_ == Phase::kDone; }
  std::span<const Collider> colliders() const {
    return {colliders_.data(), static_cast<std::size_t>(num_colliders_)};
  }
  const KnotTyingHands& hands() const { return hands_; }
  // The fixed colliders (the options' followed by more_fixed) come last in colliders(); one of
  // them replaced, as the tissue moves a stitch's rod (k < their count).
  int num_fixed_colliders() const { return num_colliders_ - num_jig_; }
  void SetFixedCollider(int k, const Collider& c);
  // Driver path length before the release, done and left, m.
  double path_done_m() const { return path_s_m_; }
  double path_total_m() const { return path_total_m_; }
  double path_left_m() const { return path_total_m_ - path_s_m_; }

  // Calls v(name, p, n) for each field (p: n consecutive scalars; enums and bools through
  // their integer; the waypoints and colliders up to their counts): the station state's
  // visitor (common/state/station_state_visit.h). Self is KnotThrowScript or its const.
  template <typename Self, typename V>
  static void VisitFields(Self& s, V& v) {
    v("slots", &s.hands_.standing_slot, 1);
    v("slots", &s.hands_.driver_slot, 1);
    v("speeds", &s.speed_m_per_s_, 1);
    v("speeds", &s.pull_speed_m_per_s_, 1);
    v("tensions", &s.hold_tension_N_, 1);
    v("tensions", &s.pull_tension_N_, 1);
    v("max_pull_m", &s.max_pull_m_, 1);
    v("force_limited_pull", &s.force_limited_pull_, 1);
    v("num_colliders", &s.num_colliders_, 1);
    v("num_jig", &s.num_jig_, 1);
    for (int k = 0; k < std::clamp(s.num_colliders_, 0, kMaxKnotTieColliders); ++k) {
      VisitCollider(s.colliders_[k], v);
      v("radii", &s.radii_[k], 1);
    }
    v("num_path", &s.num_path_, 1);
    for (int k = 0; k < std::clamp(s.num_path_, 0, kMaxKnotThrowWaypoints); ++k) {
      v("path[].p_W", s.path_[k].p_W.data(), 3);
      VisitEnum("path[].phase", s.path_[k].phase, v);
    }
    v("segment", &s.segment_, 1);
    v("path_s_m", &s.path_s_m_, 1);
    v("path_total_m", &s.path_total_m_, 1);
    v("segment_s_m", &s.segment_s_m_, 1);
    v("pulled_m", &s.pulled_m_, 1);
    v("released_s", &s.released_s_, 1);
    v("sx", &s.sx_, 1);
    v("plan_standing_W", s.plan_standing_W_.data(), 3);
    v("plan_driver_W", s.plan_driver_W_.data(), 3);
    VisitEnum("phase", s.phase_, v);
  }

 private:
  struct Waypoint {
    Eigen::Vector3d p_W = Eigen::Vector3d::Zero();
    Phase phase = Phase::kLoop;
  };
  void Add(const Eigen::Vector3d& p_W, Phase phase);
  // The standing hand's plan moves to keep hold_tension_N.
  void KeepTension(const ThreadState& state, double h);

  KnotTyingHands hands_;
  double speed_m_per_s_ = 0.0;
  double pull_speed_m_per_s_ = 0.0;
  double hold_tension_N_ = 0.0;
  double pull_tension_N_ = 0.0;
  double max_pull_m_ = 0.0;
  bool force_limited_pull_ = false;
  std::array<Collider, kMaxKnotTieColliders> colliders_{};
  std::array<double, kMaxKnotTieColliders> radii_{};  // of the jig's colliders, before the release
  int num_colliders_ = 0;
  int num_jig_ = 0;  // colliders_[0, num_jig_): pegs and jaws; then the fixed ones
  std::array<Waypoint, kMaxKnotThrowWaypoints> path_{};
  int num_path_ = 0;
  int segment_ = 0;
  double path_s_m_ = 0.0;
  double path_total_m_ = 0.0;
  double segment_s_m_ = 0.0;
  double pulled_m_ = 0.0;
  double released_s_ = 0.0;
  double sx_ = 1.0;  // +1: the driver's end lies towards +x of the knot, -1: towards -x
  // The hands' planned positions (their grasp targets less the offsets).
  Eigen::Vector3d plan_standing_W_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d plan_driver_W_ = Eigen::Vector3d::Zero();
  Phase phase_ = Phase::kDone;
};

// ---- Hold ------------------------------------------------------------------------------------
// After the pull: each hand keeps tension_N along the thread for duration_s (it moves away from
// the other hand when the pull is below that and towards it when above, as the standing hand
// of a throw does).
struct KnotHoldOptions {
  double tension_N = 20e-3;
  double duration_s = 2.0;
  // The hands' own pull: a hand offset (KnotHandOffsets) by d outward along x, away from the
  // other hand, keeps tension_N + pull_gain_N_per_m d instead (never below 0.1 tension_N): a
  // trainee pulling an end further out pulls it harder. 0: the offsets move the ends only.
  double pull_gain_N_per_m = 0.0;
  std::vector<Collider> fixed_colliders;  // e.g. the stitch; at most kMaxKnotFixedColliders
  // Throws std::invalid_argument naming the bad field.
  void Validate() const;
};

class KnotHoldScript {
 public:
  KnotHoldScript() = default;  // no hold: over
  // The hands' plans start at their grasp targets in `state`.
  KnotHoldScript(const ThreadModel& model, const ThreadState& state, KnotTyingHands hands,
                 const KnotHoldOptions& options);
  // One step of model.def.time_step_s; false when the hold is over.
  bool Step(const ThreadModel& model, ThreadWorkspace& ws, ThreadState& state,
            const KnotHandOffsets& offsets = {});
  int steps_left() const { return steps_left_; }
  // The fixed colliders (the options'), as the last step used them; one of them replaced.
  std::span<const Collider> colliders() const {
    return {colliders_.data(), static_cast<std::size_t>(num_colliders_)};
  }
  void SetFixedCollider(int k, const Collider& c);

  // As KnotThrowScript::VisitFields.
  template <typename Self, typename V>
  static void VisitFields(Self& s, V& v) {
    v("slots", &s.hands_.standing_slot, 1);
    v("slots", &s.hands_.driver_slot, 1);
    v("tension_N", &s.tension_N_, 1);
    v("pull_gain_N_per_m", &s.pull_gain_N_per_m_, 1);
    v("num_colliders", &s.num_colliders_, 1);
    for (int k = 0; k < std::clamp(s.num_colliders_, 0, kMaxKnotFixedColliders); ++k) {
      VisitCollider(s.colliders_[k], v);
    }
    v("steps_left", &s.steps_left_, 1);
    v("plan_standing_W", s.plan_standing_W_.data(), 3);
    v("plan_driver_W", s.plan_driver_W_.data(), 3);
  }

 private:
  KnotTyingHands hands_;
  double tension_N_ = 0.0;
  double pull_gain_N_per_m_ = 0.0;
  std::array<Collider, kMaxKnotFixedColliders> colliders_{};
  int num_colliders_ = 0;
  int steps_left_ = 0;
  Eigen::Vector3d plan_standing_W_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d plan_driver_W_ = Eigen::Vector3d::Zero();
};

// Throws of a knot as "2" (double overhand), "1r" (overhand), "1r,1l" (square), "1r,1r"
// (granny), "2r,1l" (surgeon's): passes and r/l handedness per throw. Throws
// std::invalid_argument naming the bad item.
std::vector<KnotThrowOptions> ParseKnotThrows(const std::string& spec);

// A stitch for the knot-tying jig (the thread module's picture of a bite through tissue, in the
// jig's frame: the thread along +x at y = 0, y up): the thread runs flat from the standing end
// at start_x_m to a guide rod under it (the first puncture), down under a deep rod (the bite),
// up over a second guide rod (the second puncture) and flat again to its other end. All rods
// are capsules along z. The first throw's jig (at x = 4 mm) lies on the standing part before
// the first guide, so the stitch is inside the throw's loop: the knot is tied around it and
// slides onto the first puncture when pulled.
struct KnotStitchDef {
  double x_m = 9e-3;               // the bite's centre
  double depth_m = 1e-3;           // the bite rod's centre below the thread's line
  double guide_offset_m = 2.5e-3;  // guides at x_m -+ this
  double rod_radius_m = 0.15e-3;
  double guide_radius_m = 0.1e-3;
  double start_x_m = -2e-3;  // the standing end
  // The rods, for a thread of this radius (the guides' tops at y = 0 under its centreline).
  std::vector<Collider> Colliders(double thread_radius_m) const;
  // The thread laid along the stitch's path from start_x_m.
  ThreadState Lay(const ThreadModel& model) const;
  // Throws std::invalid_argument("field: reason").
  void Validate() const;
};

}  // namespace microdex::thread
