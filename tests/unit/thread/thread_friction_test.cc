// Contact friction and the exact pair coupling of the linearly implicit step, against
// independent references: the capstan equation T_high / T_low = exp(mu theta) for a thread
// slipping over a fixed cylinder (and the load it presses on the cylinder), and rigid motion of two
// crossing strands in contact, which only the fluid drag may resist.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "common/thread/grasp.h"
#include "common/thread/thread_contacts.h"
#include "common/thread/thread_step.h"
#include "tests/support/thread_scenarios.h"

namespace microdex::thread {
namespace {

// Nylon 10-0 without gravity, links of 50 um, nearly no bending stiffness: the capstan equation
// is for a perfectly flexible thread (bending adds normal force where the thread leaves the
// cylinder).
ThreadDef FlexibleNylon(int num_nodes, double mu) {
  ThreadDef def = StiffNylon10_0();
  def.num_nodes = num_nodes;
  def.length_m = 50e-6 * (num_nodes - 1);
  def.gravity_m_per_s2.setZero();
  def.bend_stiffness_N_m = 1e-10;
  def.twist_stiffness_N_m = 1e-10;
  def.twist_coupling_N = 0.0;
  def.friction_coefficient = mu;
  def.object_friction_coefficient = mu;
  return def;
}

struct CapstanResult {
  double ratio = 0.0;      // T_high / T_low, mean over the slipping steps
  int slipping_steps = 0;  // steps with every friction contact at the cone's rim
  int stuck_steps = 0;     // steps before the first slip
  double max_strain = 0.0;
  // The thread's load on the cylinder (CalcColliderLoad) against its tails' pulls, largest
  // |F − (T_high t_high − T_low t_low)| / |F| over the slipping steps.
  double load_error = 0.0;
  int load_samples = 0;
};

// A thread over a fixed cylinder (capsule along z, radius 1 mm) wrapped by theta, both tails
// tangent. The low side's hand holds tension T_low like a weight (it gives thread when pulled
// harder); the high side's hand is pulled outward slowly. At the onset of slip and while the
// thread slides, T_high / T_low = exp(mu theta).
CapstanResult RunCapstan(double mu, double theta) {
  const double kCylinder_m = 1e-3;
  const double kTail_m = 1e-3;
  const double kLowTension_N = 5e-3;
  const double kPullSpeed_m_per_s = 0.5e-3;
  const double kGain_m_per_s_N = 0.3;  // the weight's hand: slow enough to stay stable at 1 ms
  const double link_m = 50e-6;
  // Centreline radius: cylinder + thread radius + a few um of contact gap.
  const double rho = kCylinder_m + 12.5e-6 + 3e-6;
  const double length = 2.0 * kTail_m + rho * theta;
  const int n = static_cast<int>(std::lround(length / link_m)) + 1;
  const ThreadModel model = MakeThreadModel(FlexibleNylon(n, mu));
  const double phi0 = 0.5 * std::numbers::pi + 0.5 * theta;  // clockwise from phi0
  auto tangent = [](double phi) { return Eigen::Vector3d(std::sin(phi), -std::cos(phi), 0.0); };
  auto on_arc = [&](double phi) {
    return Eigen::Vector3d(rho * std::cos(phi), rho * std::sin(phi), 0.0);
  };
  Eigen::Matrix3Xd x(3, n);
  for (int i = 0; i < n; ++i) {
    const double s = i * model.rest_length_m[0];
    if (s < kTail_m) {
      x.col(i) = on_arc(phi0) - (kTail_m - s) * tangent(phi0);
    } else if (s < kTail_m + rho * theta) {
      x.col(i) = on_arc(phi0 - (s - kTail_m) / rho);
    } else {
      const double phi1 = phi0 - theta;
      x.col(i) = on_arc(phi1) + (s - kTail_m - rho * theta) * tangent(phi1);
    }
  }
  ThreadState state = MakeThreadState(model, x);
  ThreadWorkspace ws = MakeThreadWorkspace(model);
  const std::vector<Collider> colliders = {
      Collider::Capsule(Eigen::Vector3d(0, 0, -2e-3), Eigen::Vector3d(0, 0, 2e-3), kCylinder_m)};
  const int low = GraspNode(model, 0, state);
  const int high = GraspNode(model, n - 1, state);
  const Eigen::Vector3d t_low = tangent(phi0);           // from the low hand towards the arc
  const Eigen::Vector3d t_high = tangent(phi0 - theta);  // from the arc towards the high hand
  const double h = model.def.time_step_s;
  CapstanResult r;
  double ratio_sum = 0.0;
  bool slipped = false;
  for (int k = 0; k < 2500; ++k) {
    Grasp& gl = state.grasps[low];
    Grasp& gh = state.grasps[high];
    // Tensions: the thread pulls each hand towards the cylinder.
    const double tension_low = gl.f_T_W.dot(t_low);
    SetGraspTarget(state, low,
                   gl.p_WT + (h * kGain_m_per_s_N * (tension_low - kLowTension_N)) * t_low, 0.0);
    // The high hand first takes up the thread to the low tension, then pulls on steadily.
    SetGraspTarget(state, high, gh.p_WT + (h * kPullSpeed_m_per_s) * t_high, 0.0);
    StepThread(model, colliders, ws, state);
    r.max_strain = std::max(r.max_strain, state.status.max_strain);
    const int nf = state.status.num_friction_contacts;
    // Frictionless (mu = 0): no friction contacts, always slipping.
    const bool slipping = state.status.num_sliding_contacts == nf;
    if (!slipped && !slipping) ++r.stuck_steps;
    slipped = slipped || slipping;
    // While both tails leave the cylinder 3 links or more from their ends (the slipping
    // thread draws its low tail onto the cylinder).
    int first = model.num_links, last = -1;
    for (int c = 0; c < ws.num_object_contacts; ++c) {
      first = std::min(first, ws.object_contacts[c].link);
      last = std::max(last, ws.object_contacts[c].link);
    }
    if (k >= 300 && first > 4 && last < model.num_links - 5) {
      const double t_hi = -state.grasps[high].f_T_W.dot(t_high);
      const double t_lo = state.grasps[low].f_T_W.dot(t_low);
      const Eigen::Vector3d expected = t_hi * t_high - t_lo * t_low;
      const Eigen::Vector3d load = CalcColliderLoad(model, ws, state, 0, 3);
      r.load_error = std::max(r.load_error, (load - expected).norm() / expected.norm());
      ++r.load_samples;
    }
    if (slipping && k >= 1500) {  // past the transient of the weight's hand
      const double t_hi = -state.grasps[high].f_T_W.dot(t_high);
      const double t_lo = state.grasps[low].f_T_W.dot(t_low);
      ratio_sum += t_hi / t_lo;
      ++r.slipping_steps;
    }
  }
  r.ratio = r.slipping_steps > 0 ? ratio_sum / r.slipping_steps : 0.0;
  return r;
}

TEST(ThreadFriction, CapstanEquationAtTheOnsetOfSlip) {
  for (double mu : {0.1, 0.3}) {
    for (double theta : {0.5 * std::numbers::pi, std::numbers::pi}) {
      const CapstanResult r = RunCapstan(mu, theta);
      const double expected = std::exp(mu * theta);
      EXPECT_GT(r.slipping_steps, 500) << "mu " << mu << " theta " << theta;
      EXPECT_GT(r.stuck_steps, 0) << "mu " << mu << " theta " << theta;
      // 3 % of the ratio: the polygonal wrap (0.05 rad per link) and the weight's hand moving
      // at the pull speed are far smaller; the thread's residual bending is what remains.
      EXPECT_NEAR(r.ratio, expected, 0.02 * expected) << "mu " << mu << " theta " << theta;
      EXPECT_LT(r.max_strain, 0.05);
      // What the thread presses on the cylinder, from its pull 3 links beyond the wrap, is
      // what its tails pull with (2 T sin(theta / 2) without friction).
      std::printf("mu %.1f theta %.2f: load error %.4f over %d steps\n", mu, theta, r.load_error,
                  r.load_samples);
      EXPECT_GT(r.load_samples, 100) << "mu " << mu << " theta " << theta;
      EXPECT_LT(r.load_error, 0.03) << "mu " << mu << " theta " << theta;
    }
  }
}

TEST(ThreadFriction, FrictionlessThreadSlipsWithEqualTensions) {
  const CapstanResult r = RunCapstan(0.0, std::numbers::pi);
  EXPECT_EQ(r.stuck_steps, 0);
  EXPECT_NEAR(r.ratio, 1.0, 0.03);
  EXPECT_GT(r.load_samples, 100);
  EXPECT_LT(r.load_error, 0.03);
}

// Two strands of one thread crossing at ~100 degrees, pressed into contact by four grasps near
// the crossing (a loop of the prolate cycloid (t - 2 sin t, -2 cos t), the strands 0.9 d apart
// along z at the crossing), then all four grasps translated together along the contact normal.
// Rigid motion: nothing but the fluid drag may resist, drag_N_s_per_m2 * length * speed. The
// exact pair coupling stiffens only the strands' relative motion; the diagonal bound anchors
// the contact nodes in absolute terms (h 2 |g| k per node) and resists.
Eigen::Vector3d RigidMoveForce(int exact_pairs, double* drag_N) {
  const double scale = 0.3e-3;
  const double link_m = 50e-6;
  const double t_cross = 1.895494267033981;  // t - 2 sin t = 0
  ThreadDef probe = FlexibleNylon(3, 0.2);
  const double zc = 0.45 * probe.diameter_m;
  auto curve = [&](double t) {
    return Eigen::Vector3d(scale * (t - 2.0 * std::sin(t)), -scale * 2.0 * std::cos(t),
                           zc * t / t_cross);
  };
  // Resample the curve at the link length.
  std::vector<Eigen::Vector3d> pts = {curve(-std::numbers::pi)};
  std::vector<double> ts = {-std::numbers::pi};
  for (double t = -std::numbers::pi; t <= std::numbers::pi; t += 1e-5) {
    if ((curve(t) - pts.back()).norm() >= link_m) {
      pts.push_back(curve(t));
      ts.push_back(t);
    }
  }
  const int n = static_cast<int>(pts.size());
  ThreadDef def = FlexibleNylon(n, 0.2);
  def.bend_stiffness_N_m = 0.0;  // derived: the real thread, which the grasps hold bent
  def.twist_stiffness_N_m = 0.0;
  def.exact_contact_pairs = exact_pairs;
  const ThreadModel model = MakeThreadModel(def);
  Eigen::Matrix3Xd x(3, n);
  for (int i = 0; i < n; ++i) x.col(i) = pts[i];
  ThreadState state = MakeThreadState(model, x);
  ThreadWorkspace ws = MakeThreadWorkspace(model);
  // Grasp each strand 3 links either side of the crossing.
  std::vector<int> slots;
  for (double tc : {-t_cross, t_cross}) {
    int centre = 0;
    for (int i = 0; i < n; ++i) {
      if (std::abs(ts[i] - tc) < std::abs(ts[centre] - tc)) centre = i;
    }
    slots.push_back(GraspNode(model, centre - 3, state));
    slots.push_back(GraspNode(model, centre + 3, state));
  }
  const std::vector<Collider> none;
  for (int k = 0; k < 300; ++k) StepThread(model, none, ws, state);  // settle
  EXPECT_GT(state.status.num_self_contacts, 0);
  const double speed = 1e-3;
  const double h = model.def.time_step_s;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int samples = 0;
  for (int k = 0; k < 200; ++k) {
    for (int s : slots) {
      SetGraspTarget(state, s, state.grasps[s].p_WT + Eigen::Vector3d(0, 0, speed * h), 0.0);
    }
    StepThread(model, none, ws, state);
    if (k >= 100) {
      for (int s : slots) sum += state.grasps[s].f_T_W;
      ++samples;
    }
  }
  EXPECT_GT(state.status.num_self_contacts, 0);
  EXPECT_EQ(state.status.nonfinite_resets + state.status.factorization_failures, 0);
  *drag_N = def.drag_N_s_per_m2 * model.rest_length_m.sum() * speed;
  return sum / samples;
}

TEST(ThreadContactCoupling, RigidMotionOfCrossingStrandsFeelsOnlyTheDrag) {
  double drag_N = 0.0;
  const Eigen::Vector3d exact = RigidMoveForce(64, &drag_N);
  const Eigen::Vector3d bound = RigidMoveForce(0, &drag_N);
  // The thread pulls the tools back against the motion (-z) with the drag.
  EXPECT_NEAR(exact.z(), -drag_N, 0.1 * drag_N) << "drag " << drag_N;
  EXPECT_LT(exact.head<2>().norm(), 0.1 * drag_N);
  EXPECT_GT(bound.norm(), 100.0 * drag_N) << "drag " << drag_N;
}

// friction_self_contacts: a thread folded into a U over a capsule has many self contacts and
// some object contacts. With the self cap at 4 the step gives implicit friction to the 4
// deepest self contacts and to every object contact (within friction_contacts); with the cap
// above the count, to all of them.
TEST(ThreadFriction, SelfContactsBeyondTheCapTakeNoImplicitFriction) {
  for (const int cap : {4, 1024}) {
    ThreadDef def = StiffNylon10_0();
    def.friction_self_contacts = cap;
    def.friction_contacts = 1024;
    const ThreadModel model = MakeThreadModel(def);
    ThreadState state;
    const std::vector<Collider> colliders = FoldIntoUOverACapsule(model, state);
    ThreadWorkspace ws = MakeThreadWorkspace(model);
    GraspNode(model, 0, state);
    GraspNode(model, 64, state);
    int capped_steps = 0;
    for (int k = 0; k < 50; ++k) {
      StepThread(model, colliders, ws, state);
      const int self = state.status.num_self_contacts;
      const int objects = state.status.num_object_contacts;
      ASSERT_EQ(state.status.num_friction_contacts, std::min(self, cap) + objects)
          << "cap " << cap << " step " << k;
      if (self > cap) {
        ++capped_steps;
        // The deepest go first: no contact beyond the cap is deeper than one within it.
        double within = -1.0;
        for (int c = 0; c < cap; ++c) within = std::max(within, ws.self_contacts[c].gap_m);
        for (int c = cap; c < self; ++c) EXPECT_GE(ws.self_contacts[c].gap_m, within);
      }
    }
    if (cap == 4) {
      EXPECT_GT(capped_steps, 0);
    }
  }
}

}  // namespace
}  // namespace microdex::thread
