#pragma once
// Scripted reaches for the predictive cue's test and bench (microdex-bench cues): seeded
// minimum-jerk reaches in the microscope's plane, millimetres long, with physiological tremor
// and sensor noise on top; some aim at the target, some at a point beside it. Each reach is
// fed to the end-point predictor and its warning (common/cues/end_point_predictor.h) from a
// rest before it to a rest after it, and the warning is scored:
//   - an erring reach ends between err_min and err_max × the limit from its target; the error
//     happens when the reach ends (the tool comes to rest beside the target); the lead is the
//     time from the first warning during the reach to then; a hit is a lead >= 150 ms;
//   - a correct reach ends within ok_max × the limit; any warning during it is a false alarm.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "common/cues/end_point_predictor.h"

namespace microdex::testing {

struct ReachSetDef {
  int reaches = 200;
  double erring_fraction = 0.5;
  std::uint64_t seed = 1;
  double limit_m = 0.5e-3;  // the predictive cue's parameter
  double err_min = 1.5, err_max = 4.0, ok_max = 0.5;
  double amplitude_min_m = 3e-3, amplitude_max_m = 8e-3;
  double duration_min_s = 0.6, duration_max_s = 1.2;
  double tremor_min_m = 5e-6, tremor_max_m = 15e-6;  // 8–12 Hz
  double noise_m = 2e-6;                             // white, per sample
  double rate_hz = 1000;
};

struct Reach {
  Eigen::Vector3d start = Eigen::Vector3d::Zero();
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  Eigen::Vector3d end = Eigen::Vector3d::Zero();
  double duration_s = 1;
  double tremor_m = 0, tremor_hz = 10, tremor_phase = 0;
  bool erring = false;
};

std::vector<Reach> MakeReaches(const ReachSetDef& def);

// The samples of one reach: rest_s at the start, the reach, rest_s at the end; *reach_start
// is the index where the reach begins.
std::vector<Eigen::Vector3d> SampleReach(const ReachSetDef& def, const Reach& reach, double rest_s,
                                         std::uint64_t noise_seed, int* reach_start);

struct PredictiveReport {
  int erring = 0;
  int correct = 0;
  int hits = 0;               // erring reaches warned >= 150 ms before their end
  int warned_erring = 0;      // erring reaches warned at all
  int false_alarms = 0;       // correct reaches warned
  double lead_ms_median = 0;  // over the erring reaches warned (NaN when none)
  double hit_rate = 0;
  double false_alarm_rate = 0;
  std::vector<double> lead_ms;
};

PredictiveReport EvaluatePredictive(const ReachSetDef& def,
                                    const cues::EndPointPredictorDef& predictor = {});

}  // namespace microdex::testing
