// One station step as a function of (simulation, input, state): the same scene, seed and input
// stream give the same state hash at every step in two stations; a state copied into a fresh
// simulation (cold caches: thread factorisation and BVH, tissue mesh, patterns and factors)
// continues exactly as the original; a copy stepped twice gives equal results.
#include "station/station_step.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "common/state/state_hash.h"
#include "station/sim_trainee.h"

namespace microdex::station {
namespace {

std::string SceneFile(const std::string& name) {
  const char* dir = std::getenv("MICRODEX_SOURCE_DIR");
  return std::string(dir ? dir : ".") + "/assets/scenes/" + name;
}

// The scenes of the station's modules: needle + tremor, thread, tissue, thread + tissue, grasp,
// and the training scenes' task tracking (a hold, the needle's passes).
const char* const kScenes[] = {
    "needle_tube.yaml",       "thread_pull.yaml",     "tissue_press.yaml",
    "suture_on_tissue.yaml",  "grasp.yaml",           "tremor_hold.yaml",
    "needle_along_tube.yaml", "loop_along_wire.yaml", "knot_topology.yaml",
    "knot_placement.yaml",    "nylon_loop.yaml",      "needle_through_tissue.yaml",
    "knot_tying.yaml"};

// One step's input as recorded: the device sample and the cues that arrived with it.
struct RecordedStep {
  DeviceSample device;
  std::vector<state::CueRequest> cues;
};

// Runs a novice simulated trainee (large motion: contacts, faults, strain) through `steps`
// steps of a station, with cues arriving on the way, and returns the input stream.
std::vector<RecordedStep> RecordInputs(const scene::SceneModel& scene, int steps) {
  SimTraineeDef def;
  def.skill = 0.0;
  def.seed = 5;
  SimTrainee trainee(scene, def);
  Simulation sim(scene);
  state::StationState s = sim.MakeInitialState(9);
  std::vector<RecordedStep> inputs(static_cast<std::size_t>(steps));
  for (int k = 0; k < steps; ++k) {
    RecordedStep& r = inputs[static_cast<std::size_t>(k)];
    r.device = trainee.Read(s.step);
    if (k == 100) r.cues.push_back({1, cues::CueKind::kConvergentField, 300, 0});
    if (k == 150) r.cues.push_back({2, cues::CueKind::kAmplifiedTremor, 4, 400});
    if (k == 600) r.cues.push_back({3, cues::CueKind::kDivergentField, 200, 650});
    if (k == 900) r.cues.push_back({4, cues::CueKind::kClear, 0, 0});
    StepStation(sim, {r.device, r.cues}, s);
    trainee.WriteForce(s.tool.f_T_W);
  }
  return inputs;
}

void Step(Simulation& sim, const RecordedStep& r, state::StationState& s) {
  StepStation(sim, {r.device, r.cues}, s);
}

TEST(StationStep, TwoStationsWithTheSameInputsHaveEqualHashesAtEveryStep) {
  for (const char* file : kScenes) {
    SCOPED_TRACE(file);
    const scene::SceneModel scene = scene::LoadScene(SceneFile(file));
    const std::vector<RecordedStep> inputs = RecordInputs(scene, 1200);
    Simulation a(scene), b(scene);
    state::StationState sa = a.MakeInitialState(9), sb = b.MakeInitialState(9);
    ASSERT_EQ(state::CalcStateHash(sa), state::CalcStateHash(sb));
    for (const RecordedStep& r : inputs) {
      Step(a, r, sa);
      Step(b, r, sb);
      ASSERT_EQ(state::CalcStateHash(sa), state::CalcStateHash(sb)) << "step " << sa.step;
    }
    EXPECT_TRUE(sa == sb);
    EXPECT_GT(sa.score.time_s, 1.0);
    // The run did something: the cues were applied, and the tool moved.
    EXPECT_EQ(sa.cues.active, cues::CueBit(cues::CueKind::kWall))
        << "the last cue clears every cue but the wall";
    EXPECT_GT(sa.score.path_length_m, 1e-3);
  }
}

TEST(StationStep, DifferentSeedOrInputGivesADifferentHash) {
  const scene::SceneModel scene = scene::LoadScene(SceneFile("needle_tube.yaml"));
  const std::vector<RecordedStep> inputs = RecordInputs(scene, 300);
  Simulation sim(scene);
  state::StationState a = sim.MakeInitialState(9), b = sim.MakeInitialState(10);
  EXPECT_NE(state::CalcStateHash(a), state::CalcStateHash(b)) << "the seed is state";
  state::StationState c = sim.MakeInitialState(9);
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    Step(sim, inputs[k], a);
    RecordedStep altered = inputs[k];
    if (k == 200) altered.device.X_WT.translation().x() += 1e-9;  // one sample, 1 nm
    Step(sim, altered, c);
    if (k < 200) {
      ASSERT_EQ(state::CalcStateHash(a), state::CalcStateHash(c)) << "step " << k;
    } else {
      ASSERT_NE(state::CalcStateHash(a), state::CalcStateHash(c)) << "step " << k;
    }
  }
}

// The caches are not state: a copy of the state stepped by a fresh simulation (every cache
// cold) continues bit for bit as the original with its warm caches.
TEST(StationStep, StateCopiedIntoAFreshSimulationContinuesExactly) {
  for (const char* file : kScenes) {
    SCOPED_TRACE(file);
    const scene::SceneModel scene = scene::LoadScene(SceneFile(file));
    const std::vector<RecordedStep> inputs = RecordInputs(scene, 1400);
    Simulation original(scene);
    state::StationState s = original.MakeInitialState(9);
    constexpr std::size_t kCopyAt = 700;
    for (std::size_t k = 0; k < kCopyAt; ++k) Step(original, inputs[k], s);
    state::StationState copy = s;
    ASSERT_TRUE(copy == s);
    Simulation fresh(scene);
    for (std::size_t k = kCopyAt; k < inputs.size(); ++k) {
      Step(original, inputs[k], s);
      Step(fresh, inputs[k], copy);
      ASSERT_EQ(state::CalcStateHash(s), state::CalcStateHash(copy)) << "step " << k;
    }
    EXPECT_TRUE(copy == s);
  }
}

TEST(StationStep, ACopySteppedTwiceGivesEqualResults) {
  for (const char* file : kScenes) {
    SCOPED_TRACE(file);
    const scene::SceneModel scene = scene::LoadScene(SceneFile(file));
    const std::vector<RecordedStep> inputs = RecordInputs(scene, 900);
    Simulation sim(scene);
    state::StationState s = sim.MakeInitialState(9);
    for (std::size_t k = 0; k < 600; ++k) Step(sim, inputs[k], s);
    // Two branches from the same state through the same simulation, interleaved, so each
    // step finds the caches as the other branch left them.
    state::StationState b1 = s, b2 = s;
    for (std::size_t k = 600; k < inputs.size(); ++k) {
      Step(sim, inputs[k], b1);
      Step(sim, inputs[k], b2);
      ASSERT_TRUE(b1 == b2) << "step " << k;
    }
  }
}

TEST(StationStep, RandomNumbersAreStateToo) {
  state::StationState a, b;
  state::SeedStationState(42, a);
  state::SeedStationState(42, b);
  const std::uint64_t first = state::NextRandom(a);
  EXPECT_NE(state::CalcStateHash(a), state::CalcStateHash(b));
  state::StationState copy = a;
  EXPECT_EQ(state::NextRandom(copy), state::NextRandom(a));
  EXPECT_EQ(state::NextRandom(b), first);
}

}  // namespace
}  // namespace microdex::station
