#include "common/cues/tremor_filter.h"

#include <cmath>
#include <stdexcept>

namespace microdex::cues {
namespace {

constexpr double kPi = 3.14159265358979323846;

// One biquad step, direct form II transposed, on three channels.
Eigen::Vector3d StepBiquad(const Biquad& f, const Eigen::Vector3d& x, Eigen::Vector3d& z1,
                           Eigen::Vector3d& z2) {
  Eigen::Vector3d y = f.b0 * x + z1;
  z1 = f.b1 * x - f.a1 * y + z2;
  z2 = f.b2 * x - f.a2 * y;
  return y;
}

}  // namespace

Biquad MakeButterworthLowPass(double f0_hz, double fs_hz) {
  const double w0 = 2 * kPi * f0_hz / fs_hz;
  const double alpha = std::sin(w0) / (2 * (1 / std::sqrt(2.0)));
  const double c = std::cos(w0);
  const double a0 = 1 + alpha;
  return {(1 - c) / 2 / a0, (1 - c) / a0, (1 - c) / 2 / a0, -2 * c / a0, (1 - alpha) / a0};
}

Biquad MakeButterworthHighPass(double f0_hz, double fs_hz) {
  const double w0 = 2 * kPi * f0_hz / fs_hz;
  const double alpha = std::sin(w0) / (2 * (1 / std::sqrt(2.0)));
  const double c = std::cos(w0);
  const double a0 = 1 + alpha;
  return {(1 + c) / 2 / a0, -(1 + c) / a0, (1 + c) / 2 / a0, -2 * c / a0, (1 - alpha) / a0};
}

void TremorFilterDef::Validate() const {
  if (!(sample_rate_hz > 0)) throw std::invalid_argument("sample_rate_hz: expected > 0");
  if (!(high_pass_hz > 0 && high_pass_hz < low_pass_hz)) {
    throw std::invalid_argument("high_pass_hz: expected 0 < high_pass_hz < low_pass_hz");
  }
  if (!(low_pass_hz < sample_rate_hz / 2)) {
    throw std::invalid_argument("low_pass_hz: expected below Nyquist");
  }
}

TremorFilterModel MakeTremorFilter(const TremorFilterDef& def) {
  def.Validate();
  return {MakeButterworthHighPass(def.high_pass_hz, def.sample_rate_hz),
          MakeButterworthLowPass(def.low_pass_hz, def.sample_rate_hz)};
}

Eigen::Vector3d StepTremorFilter(const TremorFilterModel& model, const Eigen::Vector3d& p,
                                 TremorFilterState& s) {
  if (!s.started) {
    // Steady state for a constant input p: the high-pass outputs y = 0 (b0 + b1 + b2 = 0), so
    // y = b0 p + z1 gives z1 = -b0 p, and z2 = b2 p - a2 y = b2 p; the low-pass rests at 0.
    s.hp_z1 = -model.high_pass.b0 * p;
    s.hp_z2 = model.high_pass.b2 * p;
    s.lp_z1.setZero();
    s.lp_z2.setZero();
    s.started = true;
  }
  const Eigen::Vector3d h = StepBiquad(model.high_pass, p, s.hp_z1, s.hp_z2);
  return StepBiquad(model.low_pass, h, s.lp_z1, s.lp_z2);
}

}  // namespace microdex::cues
