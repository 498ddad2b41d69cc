// The haptic loop: no allocation after warm-up (the whole tick: device, cues, modules, force,
// snapshot), regular periods and overruns on an injected clock, cues applied at a definite
// step and acknowledged with it, forces always finite and saturated, and bit-for-bit
// determinism for a given seed.
#include "station/haptic_loop.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <thread>
#include <vector>

#include "station/sim_trainee.h"
#include "station/thread_module.h"
#include "station/tissue_module.h"
#include "tests/support/alloc_counter.h"

namespace microdex::station {
namespace {

scene::SceneModel NeedleScene() {
  return scene::ParseScene(R"(
name: test-needle
modules: [needle, tremor]
vessel: {core_radius_m: 5.0e-3, tube_radius_m: 0.5e-3, segment_angle_rad: 4.71238898}
needle: {radius_m: 5.0e-3, sweep_rad: 1.04719755}
task: {pass_duration_s: 2.0, start_azimuth_rad: 0.2, end_azimuth_rad: 3.3}
haptic: {rate_hz: 1000, max_force_N: 0.5, wall_stiffness_N_per_m: 1000}
)",
                           "inline");
}

struct Rig {
  explicit Rig(double skill = 0.0, std::uint64_t seed = 7, std::int64_t lateness_ns = 0)
      : scene(NeedleScene()),
        device(scene, Def(skill, seed)),
        clock(1'000'000'000, lateness_ns),
        loop(scene, device, rings, clock, Config()) {}
  // The state hash after every step, so that the allocation test covers it too.
  static HapticLoopConfig Config() {
    HapticLoopConfig c;
    c.hash_period_steps = 1;
    return c;
  }
  static SimTraineeDef Def(double skill, std::uint64_t seed) {
    SimTraineeDef d;
    d.skill = skill;
    d.seed = seed;
    return d;
  }
  // Runs n more steps, draining the snapshot ring into `out` (when given) as the publisher
  // thread would.
  void Steps(std::uint64_t n, std::vector<TickSnapshot>* out = nullptr) {
    const std::uint64_t end = loop.step() + n;
    std::atomic<bool> stop{false};
    while (loop.step() < end) {
      loop.Run(stop, std::min(end, loop.step() + 256));
      TickSnapshot s;
      while (rings.snapshots.TryPop(s)) {
        if (out) out->push_back(s);
      }
    }
  }
  scene::SceneModel scene;
  SimTrainee device;
  rt::ManualClock clock;
  StationRings rings;
  HapticLoop loop;
};

TEST(HapticLoop, TickNeverAllocatesAfterWarmUp) {
  Rig rig(/*skill=*/0.0);  // a novice: contacts, wall forces, contact events
  rig.Steps(500);          // warm-up
  // Cues enter as they would from the publisher thread.
  ASSERT_TRUE(rig.rings.cues.TryPush({1, cues::CueKind::kDivergentField, 300, 0}));
  ASSERT_TRUE(rig.rings.cues.TryPush({2, cues::CueKind::kAmplifiedTremor, 3, 1500}));
  ASSERT_TRUE(rig.rings.cues.TryPush({3, cues::CueKind::kConvergentField, 500, 3000}));
  ASSERT_TRUE(rig.rings.cues.TryPush({4, cues::CueKind::kClear, 0, 4000}));
  std::atomic<bool> stop{false};
  testing::StartCountingAllocations();
  // 5000 steps without draining: the ring (4096) fills and drops are counted, not allocated.
  rig.loop.Run(stop, rig.loop.step() + 5000);
  const std::uint64_t allocations = testing::StopCountingAllocations();
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(rig.loop.ring_dropped(), 0u);
  EXPECT_GT(rig.loop.last_snapshot().score.contacts, 0u) << "the test should exercise contacts";
}

TEST(HapticLoop, PeriodsAndOverrunsOnTheInjectedClock) {
  Rig rig;
  std::vector<TickSnapshot> snaps;
  rig.Steps(1000, &snaps);
  ASSERT_EQ(snaps.size(), 1000u);
  for (std::size_t i = 0; i < snaps.size(); ++i) {
    EXPECT_EQ(snaps[i].step, i);
    EXPECT_EQ(snaps[i].period_ns, 1'000'000);
    EXPECT_EQ(snaps[i].overrun, 0);
    if (i > 0) {
      EXPECT_EQ(snaps[i].tick_start_ns - snaps[i - 1].tick_start_ns, 1'000'000);
    }
  }
  // A clock that wakes 1.5 ms after every deadline it sleeps for: the deadlines stay on the
  // absolute 1 ms grid, so the loop catches up (the next deadline is already past, no sleep)
  // and 1000 steps still take 1000 ms of clock time: lateness does not accumulate. Ticks that
  // start more than a period after their deadline are overruns: every second one here.
  Rig late(0.0, 7, 1'500'000);
  const std::int64_t t0 = late.clock.NowNs();
  std::vector<TickSnapshot> late_snaps;
  late.Steps(1000, &late_snaps);
  const std::int64_t elapsed = late.clock.NowNs() - t0;
  EXPECT_NEAR(static_cast<double>(elapsed), 1000e6, 3e6);
  EXPECT_EQ(late.loop.overruns(), 500u);
  std::uint64_t flagged = 0;
  for (const auto& s : late_snaps) flagged += s.overrun;
  EXPECT_EQ(flagged, 500u);
}

TEST(HapticLoop, CueAppliedAtItsStepAndAcknowledged) {
  Rig rig;
  std::vector<TickSnapshot> snaps;
  rig.Steps(100, &snaps);
  ASSERT_TRUE(rig.rings.cues.TryPush({42, cues::CueKind::kConvergentField, 250, 777}));
  ASSERT_TRUE(rig.rings.cues.TryPush({43, cues::CueKind::kAmplifiedTremor, 4, 0}));  // now
  rig.Steps(1000, &snaps);
  int acks_42 = 0, acks_43 = 0;
  for (const auto& s : snaps) {
    for (int i = 0; i < s.ack_count; ++i) {
      if (s.acks[i].cue_id == 42) {
        ++acks_42;
        EXPECT_EQ(s.step, 777u);
        EXPECT_EQ(s.acks[i].kind, cues::CueKind::kConvergentField);
      }
      if (s.acks[i].cue_id == 43) {
        ++acks_43;
        EXPECT_EQ(s.step, 100u) << "a cue due at once is applied at the next step";
      }
    }
    const bool field = (s.active_cues >> unsigned(cues::CueKind::kConvergentField)) & 1u;
    EXPECT_EQ(field, s.step >= 777) << "at step " << s.step;
  }
  EXPECT_EQ(acks_42, 1);
  EXPECT_EQ(acks_43, 1);
}

TEST(HapticLoop, ConvergentFieldPullsTowardsThePath) {
  // The simulated hand yields to the force, so a convergent field must shrink the distance
  // of the tool to its ideal circle and a divergent one grow it (same seed, same script).
  auto mean_error = [](cues::CueKind kind, double k) {
    Rig rig(0.0, 11);
    if (k > 0) {
      EXPECT_TRUE(rig.rings.cues.TryPush({1, kind, k, 0}));
    }
    std::vector<TickSnapshot> snaps;
    rig.Steps(4000, &snaps);
    cues::PathCircle path{rig.scene.vessel.X_WV, rig.scene.needle.radius_m};
    double sum = 0;
    for (const auto& s : snaps) {
      const Eigen::Vector3d p(s.p_WT[0], s.p_WT[1], s.p_WT[2]);
      Eigen::Vector3d q;
      EXPECT_TRUE(cues::CalcNearestOnCircle(path, p, &q));
      sum += (p - q).norm();
    }
    return sum / static_cast<double>(snaps.size());
  };
  const double none = mean_error(cues::CueKind::kClear, 0);
  const double conv = mean_error(cues::CueKind::kConvergentField, 400);
  const double div = mean_error(cues::CueKind::kDivergentField, 200);
  EXPECT_LT(conv, 0.8 * none);
  EXPECT_GT(div, 1.1 * none);
}

TEST(HapticLoop, ForceIsFiniteAndSaturated) {
  Rig rig(0.0, 3);
  ASSERT_TRUE(rig.rings.cues.TryPush({1, cues::CueKind::kDivergentField, 2000, 0}));
  std::vector<TickSnapshot> snaps;
  rig.Steps(5000, &snaps);
  double max_force = 0;
  for (const auto& s : snaps) {
    const Eigen::Vector3d f(s.f_T_W[0], s.f_T_W[1], s.f_T_W[2]);
    ASSERT_TRUE(f.allFinite());
    max_force = std::max(max_force, f.norm());
  }
  EXPECT_LE(max_force, rig.scene.haptic.max_force_N * (1 + 1e-12));
  EXPECT_GT(max_force, 0.9 * rig.scene.haptic.max_force_N) << "saturation not exercised";
}

TEST(HapticLoop, SameSeedSameRunBitForBit) {
  auto run = [](std::uint64_t seed) {
    Rig rig(0.3, seed);
    EXPECT_TRUE(rig.rings.cues.TryPush({5, cues::CueKind::kDivergentField, 150, 1234}));
    std::vector<TickSnapshot> snaps;
    rig.Steps(3000, &snaps);
    return snaps;
  };
  const auto a = run(21), b = run(21), c = run(22);
  ASSERT_EQ(a.size(), b.size());
  bool differs_from_c = false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].p_WT, b[i].p_WT) << i;
    EXPECT_EQ(a[i].f_T_W, b[i].f_T_W) << i;
    EXPECT_EQ(std::memcmp(&a[i].needle.clearance_m, &b[i].needle.clearance_m, sizeof(double)), 0);
    if (a[i].p_WT != c[i].p_WT) differs_from_c = true;
  }
  EXPECT_EQ(a.back().score.time_in_contact_s, b.back().score.time_in_contact_s);
  EXPECT_TRUE(differs_from_c) << "another seed gave the same trainee";
}

std::string SceneFile(const std::string& name) {
  const char* dir = std::getenv("MICRODEX_SOURCE_DIR");
  return std::string(dir ? dir : ".") + "/assets/scenes/" + name;
}

// A station's loop on a shipped scene (thread, tissue), the trainee novice for large motion.
struct SceneRig {
  explicit SceneRig(scene::SceneModel s, double skill = 0.0)
      : scene(std::move(s)),
        device(scene, Rig::Def(skill, 11)),
        second(scene, SecondHand(Rig::Def(skill, 11))),
        loop(scene, device, rings, clock, Rig::Config(), scene.hands() == 2 ? &second : nullptr) {}
  static SimTraineeDef SecondHand(SimTraineeDef d) {
    d.hand = 1;
    return d;
  }
  void Steps(std::uint64_t n) {
    std::atomic<bool> stop{false};
    const std::uint64_t end = loop.step() + n;
    while (loop.step() < end) {
      loop.Run(stop, std::min(end, loop.step() + 256));
      TickSnapshot s;
      while (rings.snapshots.TryPop(s)) {
      }
    }
  }
  template <class M>
  const M* Find() const {
    for (std::size_t i = 0; i < loop.module_count(); ++i) {
      if (auto* t = dynamic_cast<const M*>(&loop.simulation().module(i))) return t;
    }
    return nullptr;
  }
  scene::SceneModel scene;
  SimTrainee device;
  SimTrainee second;  // the other hand, read in bimanual scenes
  rt::ManualClock clock;
  StationRings rings;
  HapticLoop loop;
};

// The thread and tissue modules inside the tick, their large frames every 16 steps included:
// no allocation after warm-up, with the tool moving so that the tissue's mesh selection
// changes (new sparsity patterns) and the thread is pulled taut and let slack; 4500 steps
// without draining, so the snapshot ring also fills and drops. Outside sanitizer builds
// malloc itself is counted, so allocations inside C libraries and Eigen's heap temporaries
// (which use malloc, not operator new) show too.

// The training scenes' modules and task tracking inside the tick (grasp contacts, the loop–wire
// query, the knot answers, the stitches, the nylon's shape error): no allocation after warm-up.
// A run ends early when its task does.
TEST(HapticLoop, TrainingSceneTicksNeverAllocate) {
  for (const char* file : {"tremor_hold.yaml", "loop_along_wire.yaml", "needle_along_tube.yaml",
                           "grasp.yaml", "nylon_loop.yaml", "knot_topology.yaml",
                           "knot_placement.yaml", "needle_through_tissue.yaml"}) {
    SCOPED_TRACE(file);
    SceneRig rig(scene::LoadScene(SceneFile(file)));
    rig.Steps(500);
    ASSERT_EQ(rig.loop.state().score.outcome, 0) << "the task ended during the warm-up";
    std::atomic<bool> stop{false};
    testing::StartCountingAllocations();
    rig.loop.Run(stop, rig.loop.step() + 2500);
    const std::uint64_t allocations = testing::StopCountingAllocations();
    EXPECT_EQ(allocations, 0u);
    EXPECT_GT(rig.loop.step(), 2000u);
  }
}

// Knot tying inside the tick: the throws chosen, each throw's script built in the state and
// stepped, the ends' roles swapped, the hold started and run, and the task ended, with no
// allocation after warm-up (an expert trainee, whose choices come within the first 6 s); also
// with the stitch moving in the patch's plane (knot_tying.stitch_in_plane, off in the scene).
TEST(HapticLoop, KnotTyingTicksNeverAllocate) {
  for (const bool in_plane : {false, true}) {
    SCOPED_TRACE(in_plane ? "stitch_in_plane" : "normal only");
    scene::SceneModel scene = scene::LoadScene(SceneFile("knot_tying.yaml"));
    scene.knot_tying->stitch_in_plane = in_plane;
    SceneRig rig(std::move(scene), 1.0);
    rig.Steps(500);
    ASSERT_EQ(rig.loop.state().thread->tie.started, 0) << "a throw started during the warm-up";
    std::atomic<bool> stop{false};
    testing::StartCountingAllocations();
    rig.loop.Run(stop, rig.loop.step() + 20000);
    const std::uint64_t allocations = testing::StopCountingAllocations();
    EXPECT_EQ(allocations, 0u);
    const state::KnotTieState& tie = rig.loop.state().thread->tie;
    EXPECT_EQ(tie.pulled, 2);
    EXPECT_EQ(tie.done, 1);
    EXPECT_EQ(rig.loop.state().score.outcome, 1);
    double in_plane_load_N = 0;
    for (const double f : tie.stitch_in_plane_load_N) {
      in_plane_load_N = std::max(in_plane_load_N, std::abs(f));
    }
    if (in_plane) {
      EXPECT_GT(in_plane_load_N, 1e-3) << "the in-plane path did not run";
    } else {
      EXPECT_EQ(in_plane_load_N, 0.0);
    }
  }
}

TEST(HapticLoop, ThreadAndTissueTicksNeverAllocate) {
  for (const char* file : {"suture_on_tissue.yaml", "tissue_press.yaml", "thread_pull.yaml"}) {
    SCOPED_TRACE(file);
    SceneRig rig(scene::LoadScene(SceneFile(file)));
    rig.Steps(1000);  // warm-up: the pattern cache, the first frames
    const TissueModule* tissue = rig.Find<TissueModule>();
    const std::uint32_t revision0 = tissue ? tissue->mesh_revision() : 0;
    ASSERT_TRUE(rig.rings.cues.TryPush({1, cues::CueKind::kConvergentField, 200, 1500}));
    std::atomic<bool> stop{false};
    testing::StartCountingAllocations();
    rig.loop.Run(stop, rig.loop.step() + 4500);
    const std::uint64_t allocations = testing::StopCountingAllocations();
    EXPECT_EQ(allocations, 0u);
    EXPECT_GT(rig.loop.ring_dropped(), 0u);
    if (rig.scene.thread) {
      EXPECT_TRUE(rig.rings.frames.thread.Update()) << "no thread frame was published";
      EXPECT_GT(rig.loop.state().thread->thread.status.steps, 5000);
    }
    if (tissue) {
      EXPECT_GT(tissue->mesh_revision(), revision0 + 100)
          << "the mesh hardly changed (its selection or, attached, its nodes' places)";
      EXPECT_EQ(rig.loop.state().tissue->tissue.num_failed_steps, 0u);
      EXPECT_TRUE(rig.rings.frames.tissue.Update()) << "no tissue frame was published";
    }
  }
}

// The haptic thread and a publisher-side consumer at once, as in the station (the tsan preset
// checks the handoffs): snapshots arrive in step order with none lost but those counted as
// dropped, cues pushed from the consumer side are acknowledged, and the thread and tissue
// frames taken are whole and newer each time, written at multiples of the frame period.
TEST(HapticLoop, HapticAndPublisherSidesRunConcurrently) {
  SceneRig rig(scene::LoadScene(SceneFile("suture_on_tissue.yaml")));
  constexpr std::uint64_t kSteps = 3000;
  std::atomic<bool> stop{false};
  std::atomic<bool> finished{false};
  std::thread haptic([&] {
    rig.loop.Run(stop, kSteps);
    finished = true;
  });
  std::uint64_t next_step = 0, received = 0, acks = 0, thread_frames = 0, tissue_frames = 0;
  std::uint64_t last_thread_step = 0, last_tissue_step = 0;
  bool ordered = true, framed = true;
  bool cue_sent = false;
  for (;;) {
    const bool done = finished.load();
    TickSnapshot s;
    while (rig.rings.snapshots.TryPop(s)) {
      ordered = ordered && s.step >= next_step;  // gaps only where the ring was full
      next_step = s.step + 1;
      ++received;
      acks += static_cast<std::uint64_t>(s.ack_count);
    }
    if (!cue_sent && received > 100) {
      cue_sent = rig.rings.cues.TryPush({9, cues::CueKind::kAmplifiedTremor, 2, 0});
    }
    if (rig.rings.frames.thread.Update()) {
      const ThreadFrame& f = rig.rings.frames.thread.front();
      framed = framed && f.step % 16 == 0 && (thread_frames == 0 || f.step > last_thread_step) &&
               f.num_nodes == 65;
      last_thread_step = f.step;
      ++thread_frames;
    }
    if (rig.rings.frames.tissue.Update()) {
      const TissueFrame& f = rig.rings.frames.tissue.front();
      framed = framed && f.step % 16 == 0 && (tissue_frames == 0 || f.step > last_tissue_step) &&
               f.nodes_x == 65;
      last_tissue_step = f.step;
      ++tissue_frames;
    }
    if (done && rig.rings.snapshots.size() == 0) break;
    std::this_thread::yield();
  }
  haptic.join();
  EXPECT_TRUE(ordered);
  EXPECT_TRUE(framed);
  EXPECT_EQ(received + rig.loop.ring_dropped(), kSteps);
  EXPECT_TRUE(cue_sent);
  EXPECT_EQ(acks, 1u);
  EXPECT_GT(thread_frames, 0u);
  EXPECT_GT(tissue_frames, 0u);
  EXPECT_EQ(last_thread_step, (kSteps - 1) / 16 * 16);
}

// Why the shipped tissue scenes use the warm-started IC(0) CG: CHOLMOD's factorisation of
// every new sparsity pattern allocates inside CHOLMOD (malloc), which a tick must not do. This
// is the documented exclusion: the cholmod solver is kept out of the haptic tick.
TEST(HapticLoop, CholmodAllocatesInTheTickWhenTheMeshChanges) {
  if (!testing::CountsMalloc()) GTEST_SKIP() << "malloc is not counted under sanitizers";
  scene::SceneModel scene = scene::LoadScene(SceneFile("tissue_press.yaml"));
  scene.tissue->def.solver = fem::SolverKind::kCholmod;
  SceneRig rig(std::move(scene));
  rig.Steps(1000);
  std::atomic<bool> stop{false};
  testing::StartCountingAllocations();
  rig.loop.Run(stop, rig.loop.step() + 3000);
  const std::uint64_t allocations = testing::StopCountingAllocations();
  std::printf("cholmod in the tick: %llu allocations in 3000 steps\n",
              static_cast<unsigned long long>(allocations));
  EXPECT_GT(allocations, 0u);
}

// Every cue kind on at once (each at its default, the fields at their extreme stiffness, the
// audio and visual signals and the end-point predictor running): still no allocation.
TEST(HapticLoop, TickWithEveryCueOnNeverAllocates) {
  for (const char* file : {"needle_along_tube.yaml", "loop_along_wire.yaml", "tremor_hold.yaml"}) {
    SCOPED_TRACE(file);
    SceneRig rig(scene::LoadScene(SceneFile(file)));
    rig.Steps(300);
    for (std::uint32_t k = 1; k < cues::kCueKindCount; ++k) {
      const auto kind = static_cast<cues::CueKind>(k);
      const double param = kind == cues::CueKind::kDivergentField
                               ? cues::CueParamLimits(kind).max
                               : cues::CueParamLimits(kind).default_value;
      ASSERT_TRUE(rig.rings.cues.TryPush({k, kind, param, 0, false}));
    }
    std::atomic<bool> stop{false};
    testing::StartCountingAllocations();
    rig.loop.Run(stop, rig.loop.step() + 2000);
    const std::uint64_t allocations = testing::StopCountingAllocations();
    EXPECT_EQ(allocations, 0u);
    const state::CueState& c = rig.loop.state().cues;
    // The divergent field came after the convergent one: it replaced it.
    EXPECT_FALSE(c.on(cues::CueKind::kConvergentField));
    EXPECT_TRUE(c.on(cues::CueKind::kDivergentField));
    EXPECT_TRUE(c.on(cues::CueKind::kPredictive));
    EXPECT_TRUE(c.on(cues::CueKind::kAudioGeiger));
  }
}

// Each kind switched on and off by request, acknowledged with the step it took effect at; the
// mask the mirrors see follows; clear leaves the wall; requests that fail the check (NaN, out
// of limits) never reach the state, whichever path they took.
TEST(HapticLoop, EveryCueSwitchesOnAndOffAndIsAcknowledged) {
  Rig rig(/*skill=*/0.5);
  rig.Steps(10);
  std::vector<TickSnapshot> snaps;
  std::uint64_t id = 100;
  for (std::uint32_t k = 1; k < cues::kCueKindCount; ++k) {
    const auto kind = static_cast<cues::CueKind>(k);
    SCOPED_TRACE(cues::CueKindName(kind));
    const double param = cues::CueParamLimits(kind).max;
    const std::uint64_t at = rig.loop.step() + 5;
    ASSERT_TRUE(rig.rings.cues.TryPush({++id, kind, param, at, false}));
    snaps.clear();
    rig.Steps(10, &snaps);
    bool acked = false;
    for (const TickSnapshot& s : snaps) {
      for (int i = 0; i < s.ack_count; ++i) {
        if (s.acks[i].cue_id == id) {
          acked = true;
          EXPECT_EQ(s.step, at);
          EXPECT_EQ(s.acks[i].kind, kind);
          EXPECT_EQ(s.acks[i].param, param);
        }
      }
    }
    EXPECT_TRUE(acked);
    EXPECT_TRUE(snaps.back().active_cues & cues::CueBit(kind));
    EXPECT_EQ(snaps.back().cue.param[k], param);
    ASSERT_TRUE(rig.rings.cues.TryPush({++id, kind, 0, 0, true}));
    snaps.clear();
    rig.Steps(3, &snaps);
    EXPECT_FALSE(snaps.back().active_cues & cues::CueBit(kind)) << "switched off";
  }
  ASSERT_TRUE(rig.rings.cues.TryPush({++id, cues::CueKind::kAudioClick, 0.5, 0, false}));
  ASSERT_TRUE(rig.rings.cues.TryPush({++id, cues::CueKind::kWall, 1, 0, false}));
  ASSERT_TRUE(rig.rings.cues.TryPush({++id, cues::CueKind::kClear, 0, 0, false}));
  snaps.clear();
  rig.Steps(3, &snaps);
  EXPECT_EQ(snaps.back().active_cues, cues::CueBit(cues::CueKind::kWall)) << "clear keeps the wall";
  // Bad parameters pushed straight into the ring (bypassing the publisher's check).
  const double kept = rig.loop.state().cues.p(cues::CueKind::kConvergentField);
  ASSERT_TRUE(rig.rings.cues.TryPush(
      {++id, cues::CueKind::kConvergentField, std::numeric_limits<double>::quiet_NaN(), 0, false}));
  ASSERT_TRUE(rig.rings.cues.TryPush({++id, cues::CueKind::kConvergentField, 1e9, 0, false}));
  ASSERT_TRUE(rig.rings.cues.TryPush({++id, static_cast<cues::CueKind>(99), 1, 0, false}));
  snaps.clear();
  rig.Steps(3, &snaps);
  EXPECT_FALSE(rig.loop.state().cues.on(cues::CueKind::kConvergentField));
  EXPECT_EQ(rig.loop.state().cues.p(cues::CueKind::kConvergentField), kept);
  for (const TickSnapshot& s : snaps) EXPECT_EQ(s.ack_count, 0);
}

// The haptic cues at the extremes of their parameters on a novice (contacts, wall forces):
// every force sent is finite, within max_force_N, and changes by at most the rate limit.
TEST(HapticLoop, ForceStaysWithinItsLimitsAtEveryCueExtreme) {
  struct Case {
    cues::CueKind kind;
    double param;
  };
  const Case cases[] = {{cues::CueKind::kConvergentField, 0},
                        {cues::CueKind::kConvergentField, 1e6},
                        {cues::CueKind::kDivergentField, 1e6},
                        {cues::CueKind::kAmplifiedTremor, 20},
                        {cues::CueKind::kWall, 10},
                        {cues::CueKind::kWall, 0}};
  for (const Case& c : cases) {
    SCOPED_TRACE(::testing::Message() << cues::CueKindName(c.kind) << " " << c.param);
    Rig rig(/*skill=*/0.0);
    ASSERT_TRUE(rig.rings.cues.TryPush({1, c.kind, c.param, 0, false}));
    std::vector<TickSnapshot> snaps;
    rig.Steps(6000, &snaps);
    const double max_step = cues::kMaxForceRate_N_per_s * rig.loop.dt_s();
    Eigen::Vector3d prev = Eigen::Vector3d::Zero();
    double largest = 0;
    for (const TickSnapshot& s : snaps) {
      const Eigen::Vector3d f(s.f_T_W[0], s.f_T_W[1], s.f_T_W[2]);
      ASSERT_TRUE(f.allFinite());
      ASSERT_LE(f.norm(), rig.scene.haptic.max_force_N + 1e-12);
      ASSERT_LE((f - prev).norm(), max_step + 1e-12) << "step " << s.step;
      largest = std::max(largest, f.norm());
      prev = f;
    }
    if (c.param > 1 && c.kind != cues::CueKind::kAmplifiedTremor) {
      EXPECT_GT(largest, 0.1) << "the case should exercise the limits";
    }
    EXPECT_GT(snaps.back().score.contacts, 0u) << "the case should exercise the wall";
  }
}

TEST(HapticLoop, CueLimits) {
  EXPECT_EQ(CheckCue(cues::CueKind::kClear, 0), "");
  EXPECT_EQ(CheckCue(cues::CueKind::kConvergentField, 100), "");
  EXPECT_EQ(CheckCue(cues::CueKind::kConvergentField, 0), "");
  EXPECT_EQ(CheckCue(cues::CueKind::kDivergentField, 1e6), "");
  EXPECT_NE(CheckCue(cues::CueKind::kDivergentField, 1.0001e6), "");
  EXPECT_NE(CheckCue(cues::CueKind::kConvergentField, -1), "");
  EXPECT_NE(CheckCue(cues::CueKind::kAmplifiedTremor, 0.5), "");
  EXPECT_NE(CheckCue(cues::CueKind::kAmplifiedTremor, std::nan("")), "");
  EXPECT_EQ(CheckCue(cues::CueKind::kAmplifiedTremor, std::nan(""), /*off=*/true), "")
      << "switching off takes no parameter";
  EXPECT_NE(CheckCue(static_cast<cues::CueKind>(17), 1), "");
}

}  // namespace
}  // namespace microdex::station
