// The simulated trainee: tremor in the 8–12 Hz band at the configured RMS, drift slow and at
// its standard deviation, novice worse than expert, deterministic for a seed.
#include "station/sim_trainee.h"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <stdexcept>
#include <vector>

namespace microdex::station {
namespace {

constexpr double kPi = 3.14159265358979323846;

scene::SceneModel Scene() { return scene::ParseScene("name: t\nmodules: [needle]\n", "inline"); }

// Deviation of the device position from the ideal path, n steps.
std::vector<Eigen::Vector3d> Deviation(const scene::SceneModel& scene, const SimTraineeDef& def,
                                       int n) {
  SimTrainee t(scene, def);
  std::vector<Eigen::Vector3d> out;
  const double dt = 1.0 / scene.haptic.rate_hz;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d p = t.Read(static_cast<std::uint64_t>(k)).X_WT.translation();
    out.push_back(p - scene.CalcIdealToolPose(t.pace() * k * dt).translation());
  }
  return out;
}

// Power of one axis in [f_lo, f_hi] as a fraction of the total power (mean removed, Hann
// window against leakage): the band bins by a direct DFT (brute force reference), the total by
// Parseval, sum_k |X_k|^2 = n sum_i x_i^2.
double BandFraction(const std::vector<Eigen::Vector3d>& x, int axis, double fs, double f_lo,
                    double f_hi) {
  const int n = static_cast<int>(x.size());
  double mean = 0;
  for (const auto& v : x) mean += v[axis];
  mean /= n;
  std::vector<double> w(n);
  double energy = 0;
  for (int i = 0; i < n; ++i) {
    w[i] = (x[i][axis] - mean) * 0.5 * (1 - std::cos(2 * kPi * i / n));
    energy += w[i] * w[i];
  }
  double band = 0;
  for (int k = static_cast<int>(std::ceil(f_lo * n / fs)); k * fs / n <= f_hi; ++k) {
    std::complex<double> acc = 0;
    for (int i = 0; i < n; ++i) acc += w[i] * std::polar(1.0, -2 * kPi * k * i / n);
    band += (k == 0 ? 1 : 2) * std::norm(acc);  // bins k and n - k
  }
  return band / (n * energy);
}

TEST(SimTrainee, TremorIsInThePhysiologicalBandAtItsRms) {
  const auto scene = Scene();
  SimTraineeDef def;
  def.skill = 0.0;
  def.drift_std_novice_m = 0;  // tremor alone
  def.drift_std_novice_rad = 0;
  def.correction_threshold_novice_m = 1;  // no corrective sub-movements
  const auto dev = Deviation(scene, def, 4000);
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_GT(BandFraction(dev, axis, 1000, 7.5, 12.5), 0.97) << "axis " << axis;
  }
  double sq = 0;
  for (const auto& v : dev) sq += v.squaredNorm() / 3;
  const double rms = std::sqrt(sq / static_cast<double>(dev.size()));
  // Three sinusoids of incommensurate frequencies over 4 s: the RMS is within a few percent.
  EXPECT_NEAR(rms, def.tremor_rms_novice_m, 0.1 * def.tremor_rms_novice_m);
}

TEST(SimTrainee, DriftIsSlow) {
  const auto scene = Scene();
  SimTraineeDef def;
  def.skill = 0.0;
  def.tremor_rms_novice_m = 0;  // drift alone
  def.drift_std_novice_rad = 0;
  def.correction_threshold_novice_m = 1;  // no corrective sub-movements
  const auto dev = Deviation(scene, def, 8000);
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_GT(BandFraction(dev, axis, 1000, 0.0, 1.0), 0.97) << "axis " << axis;
  }
  // Smooth: the largest step-to-step change is tiny against the standard deviation.
  double max_step = 0;
  for (std::size_t i = 1; i < dev.size(); ++i)
    max_step = std::max(max_step, (dev[i] - dev[i - 1]).norm());
  EXPECT_LT(max_step, 0.01 * def.drift_std_novice_m);
}

TEST(SimTrainee, NoviceDeviatesMoreThanExpert) {
  const auto scene = Scene();
  auto rms = [&](double skill) {
    SimTraineeDef def;
    def.skill = skill;
    const auto dev = Deviation(scene, def, 5000);
    double sq = 0;
    for (const auto& v : dev) sq += v.squaredNorm();
    return std::sqrt(sq / static_cast<double>(dev.size()));
  };
  const double novice = rms(0.0), middle = rms(0.5), expert = rms(1.0);
  EXPECT_GT(novice, middle);
  EXPECT_GT(middle, expert);
  EXPECT_GT(novice, 3 * expert);
}

// Corrective sub-movements: the slow error left is bounded by the threshold plus what the drift
// adds within the reaction delay, far below the uncorrected drift's excursions.
TEST(SimTrainee, CorrectiveSubMovementsBoundTheDrift) {
  const auto scene = Scene();
  auto max_error = [&](double threshold_m) {
    SimTraineeDef def;
    def.skill = 0.0;
    def.tremor_rms_novice_m = 0;
    def.drift_std_novice_rad = 0;
    def.correction_threshold_novice_m = threshold_m;
    double sq = 0;
    const auto dev = Deviation(scene, def, 60000);
    for (const auto& v : dev) sq += v.squaredNorm();
    return std::sqrt(sq / static_cast<double>(dev.size()));
  };
  const double uncorrected = max_error(1.0);
  const double corrected = max_error(SimTraineeDef{}.correction_threshold_novice_m);
  // Uncorrected: three axes of standard deviation σ, RMS √3 σ.
  const double sigma = SimTraineeDef{}.drift_std_novice_m;
  EXPECT_NEAR(uncorrected, std::sqrt(3.0) * sigma, 0.15 * sigma);
  std::printf("drift RMS: uncorrected %.0f um, corrected %.0f um\n", uncorrected * 1e6,
              corrected * 1e6);
  EXPECT_LT(corrected, 0.6 * uncorrected);
  EXPECT_LT(corrected, 1.5 * SimTraineeDef{}.correction_threshold_novice_m);
}

// A skilled trainee moves along the task faster: pace rises with skill.
TEST(SimTrainee, PaceRisesWithSkill) {
  const auto scene = Scene();
  double prev = 0;
  for (double skill : {0.0, 0.2, 0.5, 0.9, 1.0}) {
    SimTraineeDef def;
    def.skill = skill;
    const SimTrainee t(scene, def);
    EXPECT_GT(t.pace(), prev) << skill;
    prev = t.pace();
  }
}

TEST(SimTrainee, DeterministicForASeed) {
  const auto scene = Scene();
  SimTraineeDef a, b;
  a.seed = b.seed = 99;
  const auto x = Deviation(scene, a, 500), y = Deviation(scene, b, 500);
  b.seed = 100;
  const auto z = Deviation(scene, b, 500);
  for (int i = 0; i < 500; ++i) EXPECT_EQ(x[i], y[i]);
  EXPECT_NE(x[250], z[250]);
}

TEST(SimTrainee, HandYieldsToForceWithItsStiffness) {
  // A constant force held long enough displaces the tool by f / k_hand.
  const auto scene = Scene();
  SimTraineeDef def;
  def.tremor_rms_novice_m = def.tremor_rms_expert_m = 0;
  def.drift_std_novice_m = def.drift_std_expert_m = 0;
  def.drift_std_novice_rad = def.drift_std_expert_rad = 0;
  SimTrainee free_hand(scene, def), pushed(scene, def);
  const Eigen::Vector3d f(0.2, -0.1, 0.05);
  Eigen::Vector3d d;
  for (std::uint64_t k = 0; k < 2000; ++k) {
    pushed.WriteForce(f);
    d = pushed.Read(k).X_WT.translation() - free_hand.Read(k).X_WT.translation();
  }
  EXPECT_LT((d - f / def.hand_stiffness_N_per_m).norm(), 1e-9);
  EXPECT_NO_THROW(def.Validate());
  def.skill = 2;
  try {
    def.Validate();
    ADD_FAILURE() << "skill 2 was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind("skill: ", 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace microdex::station
