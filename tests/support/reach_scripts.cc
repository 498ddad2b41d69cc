#include "tests/support/reach_scripts.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace microdex::testing {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kHitLead_ms = 150;

Eigen::Vector3d InPlane(double angle) { return {std::cos(angle), std::sin(angle), 0}; }

}  // namespace

std::vector<Reach> MakeReaches(const ReachSetDef& def) {
  std::mt19937_64 rng(def.seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Reach> out;
  for (int i = 0; i < def.reaches; ++i) {
    Reach r;
    r.start = Eigen::Vector3d(0.01 * u(rng), 0.01 * u(rng), 0.002 * u(rng));
    const double amp = def.amplitude_min_m + (def.amplitude_max_m - def.amplitude_min_m) * u(rng);
    r.target = r.start + amp * InPlane(2 * kPi * u(rng));
    r.erring = u(rng) < def.erring_fraction;
    const double miss = def.limit_m * (r.erring ? def.err_min + (def.err_max - def.err_min) * u(rng)
                                                : def.ok_max * u(rng));
    r.end = r.target + miss * InPlane(2 * kPi * u(rng));
    r.duration_s = def.duration_min_s + (def.duration_max_s - def.duration_min_s) * u(rng);
    r.tremor_m = def.tremor_min_m + (def.tremor_max_m - def.tremor_min_m) * u(rng);
    r.tremor_hz = 8 + 4 * u(rng);
    r.tremor_phase = 2 * kPi * u(rng);
    out.push_back(r);
  }
  return out;
}

std::vector<Eigen::Vector3d> SampleReach(const ReachSetDef& def, const Reach& r, double rest_s,
                                         std::uint64_t noise_seed, int* reach_start) {
  std::mt19937_64 rng(noise_seed);
  std::normal_distribution<double> noise(0, def.noise_m);
  const double dt = 1 / def.rate_hz;
  const int n_rest = static_cast<int>(std::lround(rest_s * def.rate_hz));
  const int n_reach = static_cast<int>(std::lround(r.duration_s * def.rate_hz));
  *reach_start = n_rest;
  std::vector<Eigen::Vector3d> out;
  const Eigen::Vector3d tremor_dir = Eigen::Vector3d(1, 1, 0.3).normalized();
  for (int i = 0; i < 2 * n_rest + n_reach; ++i) {
    const double tau = std::clamp(static_cast<double>(i - n_rest) / n_reach, 0.0, 1.0);
    const double s = tau * tau * tau * (10 - 15 * tau + 6 * tau * tau);
    const double t = i * dt;
    Eigen::Vector3d p = r.start + s * (r.end - r.start);
    p += r.tremor_m * std::sin(2 * kPi * r.tremor_hz * t + r.tremor_phase) * tremor_dir;
    p += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    out.push_back(p);
  }
  return out;
}

PredictiveReport EvaluatePredictive(const ReachSetDef& def,
                                    const cues::EndPointPredictorDef& predictor) {
  cues::EndPointPredictorDef pd = predictor;
  pd.sample_rate_hz = def.rate_hz;
  const cues::EndPointPredictorModel model = cues::MakeEndPointPredictor(pd);
  const double dt = 1 / def.rate_hz;
  PredictiveReport rep;
  const std::vector<Reach> reaches = MakeReaches(def);
  for (std::size_t k = 0; k < reaches.size(); ++k) {
    const Reach& r = reaches[k];
    int start = 0;
    const std::vector<Eigen::Vector3d> p = SampleReach(def, r, 0.4, def.seed * 7919 + k, &start);
    const int end = start + static_cast<int>(std::lround(r.duration_s * def.rate_hz));
    cues::EndPointPredictorState s;
    int first_warning = -1;
    for (int i = 0; i < static_cast<int>(p.size()); ++i) {
      const cues::EndPointPrediction e = cues::StepEndPointPredictor(model, p[i], s);
      const double err = e.valid ? (e.p_W_end - r.target).norm() : 0.0;
      const bool warn = cues::StepPredictiveWarning(e, err, def.limit_m, dt, s);
      if (warn && first_warning < 0) first_warning = i;
    }
    if (r.erring) {
      ++rep.erring;
      if (first_warning >= 0) {
        ++rep.warned_erring;
        const double lead_ms = (end - first_warning) * dt * 1e3;
        rep.lead_ms.push_back(lead_ms);
        if (lead_ms >= kHitLead_ms) ++rep.hits;
      }
    } else {
      ++rep.correct;
      if (first_warning >= 0) ++rep.false_alarms;
    }
  }
  std::vector<double> sorted = rep.lead_ms;
  std::sort(sorted.begin(), sorted.end());
  rep.lead_ms_median =
      sorted.empty() ? std::numeric_limits<double>::quiet_NaN() : sorted[sorted.size() / 2];
  rep.hit_rate = rep.erring ? static_cast<double>(rep.hits) / rep.erring : 0.0;
  rep.false_alarm_rate = rep.correct ? static_cast<double>(rep.false_alarms) / rep.correct : 0.0;
  return rep;
}

}  // namespace microdex::testing
