// The state hash and the state's equality: every field of StationState counts (changing any
// one element of any field changes both), the streamed hash is the documented XXH3-64 of the
// field bytes, a copy is equal, and hashing allocates nothing.
#include "common/state/state_hash.h"

#include <gtest/gtest.h>
#define XXH_STATIC_LINKING_ONLY
#include <xxhash.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include "common/state/station_state_visit.h"
#include "station/sim_trainee.h"
#include "station/station_step.h"
#include "tests/support/alloc_counter.h"

namespace microdex::state {
namespace {

std::string SceneFile(const std::string& name) {
  const char* dir = std::getenv("MICRODEX_SOURCE_DIR");
  return std::string(dir ? dir : ".") + "/assets/scenes/" + name;
}

// A state with every module section present and busy: the suture-on-tissue scene (thread,
// tissue, tremor) with the needle, grasp, loop, knots and placement modules added, after 400 steps
// of a novice with cues pending.
struct BusyState {
  BusyState() : scene(scene::LoadScene(SceneFile("suture_on_tissue.yaml"))) {
    scene.modules.push_back("needle");
    scene.modules.push_back("grasp");
    scene.grasp = scene::GraspSceneDef{};
    scene.modules.push_back("loop");
    scene.loop = scene::LoadScene(SceneFile("loop_along_wire.yaml")).loop;
    scene.modules.push_back("knots");
    scene.knots = scene::KnotQuizSceneDef{{knot::StitchKnotType::kSquare}, 30e-6};
    scene.modules.push_back("placement");
    scene.placement = scene::PlacementSceneDef{};
    // A second tool, holding the thread's node 0.
    scene.second_hand = scene::SecondHandDef{};
    scene.second_hand->X_WT_start.translation() = scene.thread->p_W_anchor;
    station::Simulation sim(scene);
    s = sim.MakeInitialState(3);
    station::SimTraineeDef def;
    def.skill = 0.0;
    station::SimTrainee trainee(scene, def);
    def.hand = 1;
    station::SimTrainee other_hand(scene, def);
    const CueRequest requests[] = {{1, cues::CueKind::kAmplifiedTremor, 3, 0},
                                   {2, cues::CueKind::kConvergentField, 100, 100000},
                                   {3, cues::CueKind::kDivergentField, 50, 200000}};
    for (int k = 0; k < 400; ++k) {
      station::StationInput in{trainee.Read(s.step), {}, other_hand.Read(s.step)};
      if (k == 399) in.cues = requests;  // one applied at once, two left pending
      station::StepStation(sim, in, s);
      trainee.WriteForce(s.tool.f_T_W);
    }
    NextRandom(s);
    // A contact force carried by a held knot (no scene here holds one after 400 steps).
    s.thread->thread.carry_contact_forces = true;
    s.thread->thread.num_carried = 1;
    s.thread->thread.carried[0] = {3, 40, Eigen::Vector3d::UnitY(), 4e-3};
  }
  scene::SceneModel scene;
  StationState s;
};

// Flips one element: the lowest bit of a floating-point value, +1 for an integer, !b.
template <typename T>
void Perturb(T& x) {
  if constexpr (std::is_same_v<T, bool>) {
    x = !x;
  } else if constexpr (std::is_floating_point_v<T>) {
    using Bits = std::conditional_t<sizeof(T) == 8, std::uint64_t, std::uint32_t>;
    Bits b;
    std::memcpy(&b, &x, sizeof b);
    b ^= 1;
    std::memcpy(&x, &b, sizeof b);
  } else {
    x = static_cast<T>(x + 1);
  }
}

// Visits the fields of `s`, and for each field changes elements spread over it (every element
// of a short field; of a long one the first, the last and 62 evenly spaced between, so that
// the test stays linear in the state's size), checks that the hash and the equality see each
// change, and restores it.
struct PerturbSpreadElements {
  template <typename T>
  void operator()(const char* name, T* p, std::size_t n) {
    // Presence flags and the grasp count are read from the containers, not stored: changing
    // the visited copy changes nothing.
    static const std::set<std::string> kDerived = {
        "second_tool", "needle", "tremor", "thread",    "tissue",
        "grasp",       "loop",   "knots",  "placement", "thread.grasps.size"};
    if (kDerived.count(name)) return;
    names.insert(name);
    const std::size_t count = std::min<std::size_t>(n, 64);
    for (std::size_t k = 0; k < count; ++k) {
      const std::size_t i = count == 1 ? 0 : k * (n - 1) / (count - 1);
      const T saved = p[i];
      Perturb(p[i]);
      ++elements;
      if (CalcStateHash(*state) == base_hash) {
        ADD_FAILURE() << name << "[" << i << "]: the hash did not change";
      }
      if (*state == *reference) ADD_FAILURE() << name << "[" << i << "]: still equal";
      p[i] = saved;
    }
  }
  StationState* state = nullptr;
  const StationState* reference = nullptr;
  std::uint64_t base_hash = 0;
  std::size_t elements = 0;
  std::set<std::string> names;
};

TEST(StateHash, ChangingAnyFieldAnywhereChangesHashAndEquality) {
  BusyState busy;
  StationState s = busy.s;
  const StationState reference = busy.s;
  PerturbSpreadElements p;
  p.state = &s;
  p.reference = &reference;
  p.base_hash = CalcStateHash(s);
  VisitStationState(s, p);
  EXPECT_TRUE(s == reference) << "every element was restored";
  EXPECT_EQ(CalcStateHash(s), p.base_hash);
  // Every section was present and visited.
  for (const char* field :
       {"step", "rng", "tool.X_WT", "cues.pending[].apply_at_step", "cues.acks[].cue_id",
        "score.contacts", "needle.X_WN", "tremor.mean_square_m2", "thread.x_W",
        "thread.grasps[].p_WT", "tissue.field_w_m", "tissue.leaves[].ci", "tissue.contact_force_N",
        "second_tool.X_WT", "second_tool.f_T_W", "thread.f_T2_W", "tool.tau_T_W",
        "thread.carry_contact_forces", "thread.carried[].force_N"}) {
    EXPECT_TRUE(p.names.count(field)) << field;
  }
  EXPECT_GT(p.elements, 500u);
}

TEST(StateHash, ACopyIsEqualAndHashesEqual) {
  BusyState busy;
  const StationState copy = busy.s;
  EXPECT_TRUE(copy == busy.s);
  EXPECT_EQ(CalcStateHash(copy), CalcStateHash(busy.s));
  StationState other = busy.s;
  other.tissue.reset();
  EXPECT_FALSE(other == busy.s) << "a missing module section differs";
  EXPECT_NE(CalcStateHash(other), CalcStateHash(busy.s));
}

// The documented definition, computed independently: one-shot XXH3-64 (seed 0) of the
// version's bytes followed by every field's bytes in visit order (bools as 0/1).
struct Concatenate {
  template <typename T>
  void operator()(const char* /*name*/, const T* p, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      if constexpr (std::is_same_v<T, bool>) {
        bytes.push_back(p[i] ? 1 : 0);
      } else {
        unsigned char b[sizeof(T)];
        std::memcpy(b, &p[i], sizeof(T));
        bytes.insert(bytes.end(), b, b + sizeof(T));
      }
    }
  }
  std::vector<unsigned char> bytes;
};

TEST(StateHash, IsXxh3OfTheFieldBytesInVisitOrder) {
  BusyState busy;
  Concatenate c;
  const std::uint32_t version = kStateHashVersion;
  c("version", &version, 1);
  VisitStationState(busy.s, c);
  EXPECT_GT(c.bytes.size(), 10000u);
  EXPECT_EQ(CalcStateHash(busy.s), XXH3_64bits(c.bytes.data(), c.bytes.size()));
}

TEST(StateHash, DoesNotAllocate) {
  BusyState busy;
  std::uint64_t h = 0;
  testing::StartCountingAllocations();
  for (int i = 0; i < 10; ++i) h ^= CalcStateHash(busy.s);
  EXPECT_EQ(testing::StopCountingAllocations(), 0u);
  EXPECT_EQ(h, 0u) << "an even number of equal hashes";
}

}  // namespace
}  // namespace microdex::state
