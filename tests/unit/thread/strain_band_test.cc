// ProjectStrainBand: the direct (tridiagonal) projection of the link lengths into the strain
// band, and the contact projection that uses it.
#include "common/thread/strain_band.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "common/thread/thread_contacts.h"
#include "common/thread/thread_def.h"
#include "common/thread/thread_model.h"
#include "tests/support/alloc_counter.h"

namespace microdex::thread {
namespace {

ThreadModel ChainModel(int nodes) {
  ThreadDef def = StiffNylon10_0();
  def.num_nodes = nodes;
  def.length_m = 50e-6 * (nodes - 1);
  return MakeThreadModel(def);
}

double MaxStrain(const ThreadModel& model, const Eigen::Matrix3Xd& x) {
  double worst = 0.0;
  for (int j = 0; j < model.num_links; ++j) {
    worst =
        std::max(worst, std::abs((x.col(j + 1) - x.col(j)).norm() / model.rest_length_m[j] - 1.0));
  }
  return worst;
}

// A crumpled chain: random directions, link lengths from 0.6 to 1.5 rest lengths.
Eigen::Matrix3Xd CrumpledChain(const ThreadModel& model, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0), stretch(0.6, 1.5);
  Eigen::Matrix3Xd x(3, model.num_nodes);
  x.col(0).setZero();
  Eigen::Vector3d dir = Eigen::Vector3d::UnitX();
  for (int j = 0; j < model.num_links; ++j) {
    dir = (dir + 0.7 * Eigen::Vector3d(u(rng), u(rng), u(rng))).normalized();
    x.col(j + 1) = x.col(j) + stretch(rng) * model.rest_length_m[j] * dir;
  }
  return x;
}

TEST(StrainBand, CrumpledChainEndsInsideTheBandAndKeepsItsCentreOfMass) {
  const ThreadModel model = ChainModel(129);
  StrainBandScratch scratch = MakeStrainBandScratch(model.num_links);
  const Eigen::VectorXd w = model.mass_kg.cwiseInverse();
  for (unsigned seed = 1; seed <= 5; ++seed) {
    Eigen::Matrix3Xd x = CrumpledChain(model, seed);
    ASSERT_GT(MaxStrain(model, x), 0.3);
    const Eigen::Vector3d com = x * model.mass_kg / model.mass_kg.sum();
    const StrainBandResult r = ProjectStrainBand(model, w, 0.05, 8, x, scratch);
    EXPECT_GT(r.corrected_links, 0);
    EXPECT_LE(r.iterations, 8);
    // Inside the band up to the solve's tolerance (1e-4 of a rest length).
    EXPECT_LT(MaxStrain(model, x), 0.05 + 1.01e-4) << "seed " << seed;
    // Mass-weighted moves along the links: internal forces only, the centre of mass stays.
    const Eigen::Vector3d com_after = x * model.mass_kg / model.mass_kg.sum();
    EXPECT_LT((com_after - com).norm(), 1e-12) << "seed " << seed;
  }
}

TEST(StrainBand, AStretchedLinkTakesSlackOnlyFromItsNeighbourhood) {
  // A straight chain at rest length with one link at 1.3: the 0.25 rest lengths above the band
  // are taken up by the neighbouring links (each can give 0.05 before it reaches the band
  // itself), so a few links either side move and the rest of the chain stays where it was.
  const ThreadModel model = ChainModel(65);
  StrainBandScratch scratch = MakeStrainBandScratch(model.num_links);
  const Eigen::VectorXd w = model.mass_kg.cwiseInverse();
  Eigen::Matrix3Xd x(3, model.num_nodes);
  x.col(0).setZero();
  for (int j = 0; j < model.num_links; ++j) {
    const double f = j == 30 ? 1.3 : 1.0;
    x.col(j + 1) = x.col(j) + f * model.rest_length_m[j] * Eigen::Vector3d::UnitX();
  }
  const Eigen::Matrix3Xd before = x;
  const StrainBandResult r = ProjectStrainBand(model, w, 0.05, 8, x, scratch);
  EXPECT_EQ(r.corrected_links, 1);
  EXPECT_NEAR(r.max_violation_m, 0.25 * model.rest_length_m[30], 1e-12);
  EXPECT_NEAR((x.col(31) - x.col(30)).norm() / model.rest_length_m[30], 1.05, 1.01e-4);
  EXPECT_LT(MaxStrain(model, x), 0.05 + 1.01e-4);
  for (int i = 0; i < model.num_nodes; ++i) {
    if (i >= 22 && i <= 39) continue;
    EXPECT_EQ((x.col(i) - before.col(i)).norm(), 0.0) << "node " << i;
  }
}

TEST(StrainBand, GraspedNodesStayAndTheLengthComesFromTheFreeChain) {
  // The hand jerks the grasped end 40 % of a link away (the link next to it at 1.4): a
  // Gauss-Seidel sweep corrects one link and passes the error on to the next; the direct solve
  // draws the length from the whole free chain at once and leaves every link in the band.
  const ThreadModel model = ChainModel(129);
  StrainBandScratch scratch = MakeStrainBandScratch(model.num_links);
  Eigen::VectorXd w = model.mass_kg.cwiseInverse();
  const int last = model.num_nodes - 1;
  w[last] = 0.0;  // grasped
  Eigen::Matrix3Xd x(3, model.num_nodes);
  for (int i = 0; i < model.num_nodes; ++i) {
    // A gentle arc, so that the chain has length to give.
    const double s = i * model.rest_length_m[0];
    x.col(i) = Eigen::Vector3d(s, 0.2e-3 * std::sin(M_PI * i / last), 0.0);
  }
  x(0, last) += 0.4 * model.rest_length_m[0];
  const Eigen::Vector3d hand = x.col(last);
  const StrainBandResult r = ProjectStrainBand(model, w, 0.05, 8, x, scratch);
  EXPECT_EQ(r.corrected_links, 1);
  EXPECT_EQ((x.col(last) - hand).norm(), 0.0);
  EXPECT_LT(MaxStrain(model, x), 0.05 + 1.01e-4);
}

TEST(StrainBand, InfeasibleBandStaysFiniteAndBounded) {
  // Both ends grasped 20 % beyond the chain's length: no position satisfies the band. The
  // solve must not fling nodes (at most half a link per iteration) and stays finite.
  const ThreadModel model = ChainModel(33);
  StrainBandScratch scratch = MakeStrainBandScratch(model.num_links);
  Eigen::VectorXd w = model.mass_kg.cwiseInverse();
  w[0] = 0.0;
  w[model.num_nodes - 1] = 0.0;
  Eigen::Matrix3Xd x(3, model.num_nodes);
  for (int i = 0; i < model.num_nodes; ++i) {
    x.col(i) = Eigen::Vector3d(1.2 * i * model.rest_length_m[0], 1e-9 * (i % 2), 0.0);
  }
  const Eigen::Matrix3Xd before = x;
  const int iterations = 8;
  ProjectStrainBand(model, w, 0.05, iterations, x, scratch);
  EXPECT_TRUE(x.allFinite());
  const double bound = iterations * 0.5 * model.rest_length_m[0] * (1.0 + 1e-12);
  EXPECT_LE((x - before).colwise().norm().maxCoeff(), bound);
  EXPECT_EQ((x.col(0) - before.col(0)).norm(), 0.0);
  EXPECT_EQ((x.col(model.num_nodes - 1) - before.col(model.num_nodes - 1)).norm(), 0.0);
}

TEST(StrainBand, TrackedCallsGiveTheSameBitsAsFullCalls) {
  // The contact projection calls the band after every sweep with only a few nodes moved; a
  // tracked scratch then classifies only the links the last call listed and those touching
  // the moved nodes. Random kicks of a few nodes between calls, with 2 iterations per call
  // (so that some calls end with links still outside the band, listed for the next): the
  // tracked and the full calls must agree to the bit, and the tracked call must list every
  // node it moved with its position before.
  const ThreadModel model = ChainModel(129);
  StrainBandScratch full = MakeStrainBandScratch(model.num_links);
  StrainBandScratch tracked = MakeStrainBandScratch(model.num_links);
  Eigen::VectorXd w = model.mass_kg.cwiseInverse();
  w[0] = 0.0;  // grasped
  Eigen::Matrix3Xd x = CrumpledChain(model, 3);
  tracked.StartTracking();
  Eigen::Matrix3Xd x_tracked = x;
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> node(0, model.num_nodes - 1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int unfinished = 0;
  for (int call = 0; call < 60; ++call) {
    const Eigen::Matrix3Xd before = x;
    const StrainBandResult a = ProjectStrainBand(model, w, 0.05, 2, x, full);
    const StrainBandResult b = ProjectStrainBand(model, w, 0.05, 2, x_tracked, tracked);
    ASSERT_EQ(a.corrected_links, b.corrected_links) << "call " << call;
    ASSERT_EQ(a.max_violation_m, b.max_violation_m) << "call " << call;
    ASSERT_EQ(a.iterations, b.iterations) << "call " << call;
    ASSERT_TRUE((x.array() == x_tracked.array()).all()) << "call " << call;
    if (MaxStrain(model, x) > 0.05 + 1.01e-4) ++unfinished;
    std::vector<int> listed(model.num_nodes, 0);
    for (int k = 0; k < tracked.num_moved; ++k) {
      const int i = tracked.moved[k];
      listed[i] = 1;
      EXPECT_TRUE((tracked.x_before.col(i).array() == before.col(i).array()).all());
    }
    for (int i = 0; i < model.num_nodes; ++i) {
      if ((x.col(i).array() != before.col(i).array()).any()) {
        EXPECT_EQ(listed[i], 1) << "node " << i << " moved, not listed, call " << call;
      }
    }
    tracked.ClearMoved();
    // Kick three nodes (the grasped one stays), as the contacts would.
    for (int k = 0; k < 3; ++k) {
      const int i = node(rng);
      if (w[i] == 0.0) continue;
      const Eigen::Vector3d kick =
          0.3 * model.rest_length_m[0] * Eigen::Vector3d(u(rng), u(rng), u(rng));
      x.col(i) += kick;
      x_tracked.col(i) += kick;
      tracked.MarkMoved(i);
    }
  }
  EXPECT_GT(unfinished, 0) << "every call converged: the carried-over list was not exercised";
}

TEST(StrainBand, NoAllocation) {
  const ThreadModel model = ChainModel(257);
  StrainBandScratch scratch = MakeStrainBandScratch(model.num_links);
  const Eigen::VectorXd w = model.mass_kg.cwiseInverse();
  Eigen::Matrix3Xd x = CrumpledChain(model, 7);
  ::microdex::testing::StartCountingAllocations();
  const StrainBandResult r = ProjectStrainBand(model, w, 0.05, 4, x, scratch);
  EXPECT_EQ(::microdex::testing::StopCountingAllocations(), 0u);
  EXPECT_GT(r.iterations, 0);
}

}  // namespace
}  // namespace microdex::thread
