#pragma once
// A simulated trainee holding the tool: the scene's scripted ideal path, plus physiological
// tremor (8–12 Hz), plus slow drift of position and orientation, held by a compliant hand
// that yields to the rendered force. A skill parameter (0 novice … 1 expert) scales tremor
// and drift. Seeded and deterministic: the same scene, def and step sequence (and forces)
// give the same samples bit for bit.
//
// Model, per step k (t = k dt):
//   p_WT = p_ideal(v t) + tremor(t) + drift(t) − correction(t) + f_prev / k_hand
//   v:      the trainee's pace along the task's path (minimum-jerk passes, the scene's
//           timing scaled by v), slower for a novice (pace_novice … pace_expert);
//   tremor: per axis, three sinusoids with frequencies drawn in [8, 12] Hz and random phases,
//           scaled to an RMS of tremor_rms_m (novice … expert, interpolated by skill);
//   drift:  per axis, four sinusoids with frequencies drawn in [drift_min_hz, drift_max_hz]
//           and random phases, scaled to a standard deviation of drift_std_m (likewise for the
//           orientation, a small rotation vector with drift_std_rad). Smooth, unlike a random
//           walk, whose path length would grow without bound with the sampling rate;
//   correction: corrective sub-movements. The trainee sees the drift with the reaction delay
//           τ_r (visual loop, thesis §2.1: 200 ms or more for a novice): when the drift seen,
//           less the corrections made, exceeds correction_threshold_m and no correction is
//           under way, a minimum-jerk sub-movement of correction_duration_s removes it. The
//           drift left is then bounded by the threshold plus what grows within τ_r;
//   grasp:  (task kind grasp) descend along the task's line, close the jaws (minimum jerk over
//           close_duration_s), lift back along the line and hold. The jaws come down turned
//           about the shaft by a yaw error and shifted across the jaw by an offset, each of the
//           skill's size (jaw_yaw_rad, jaw_offset_m) within ±20 %, either way, drawn once from
//           the seed: poorly aligned jaws make the object turn (thesis Fig. 2.2d);
//   knots:  (task kind knot_topology) names each knot shown after a response time
//           (response_time_novice_s … expert, ±20 %), pressing the button of its class for
//           0.1 s; of the N knots it names round((1 − p) N) wrongly (p = accuracy_novice …
//           expert; which ones drawn from the seed), confusing square with granny, surgeon's
//           with square, slip with half hitch;
//   knot tying: (task kind knot_tying) holds the needle holder at its rest pose (the task's
//           target; the forceps at the second hand's) and chooses each throw with a button
//           (1 right, 2 left) after a response time (response_time_novice_s … expert, ±20 %,
//           each choice timed from the last; the knot is tied once all are chosen): the first
//           throw's hand drawn from the seed,
//           each next throw of the other hand (a square knot), or, below square_rule_skill, of
//           the same hand (the granny habit);
//   placement: (task kind knot_placement) moves the tip around the vessel wall from stitch to
//           stitch (minimum jerk in azimuth and height, placement.move_s / pace each), resting
//           at each and pressing a button there; each stitch misplaced by a uniform error of
//           standard deviation placement_angle_novice_rad … expert and placement_bite_novice_m
//           … expert, drawn from the seed;
//   hand:   a spring of stiffness k_hand holding the planned pose, yielding with a time
//           constant τ_hand: the offset o follows f / k_hand by o' = (f / k_hand − o) / τ_hand
//           (explicit Euler, f the force of the previous step), so guidance fields and the
//           wall act on the tool. A quasi-static hand (o = f / k_hand at once) would make the
//           wall loop diverge whenever k_wall > k_hand.

#include <vector>

#include "common/scene/scene.h"
#include "station/device.h"

namespace microdex::station {

struct SimTraineeDef {
  double skill = 0.5;  // 0 novice .. 1 expert
  std::uint64_t seed = 1;
  // Which of the trainee's hands this device is: 0 the first tool (the task's), 1 the second
  // tool of a bimanual scene (it follows the scene's second-hand pose, gripper closed, with
  // its own tremor and drift drawn from a seed of its own).
  int hand = 0;
  double tremor_rms_novice_m = 60e-6;
  double tremor_rms_expert_m = 10e-6;
  double drift_std_novice_m = 300e-6;
  double drift_std_expert_m = 40e-6;
  double drift_std_novice_rad = 0.03;
  double drift_std_expert_rad = 0.004;
  double drift_min_hz = 0.05;
  double drift_max_hz = 0.5;
  double pace_novice = 0.6;  // of the scene's pass timing
  double pace_expert = 1.3;
  double reaction_delay_novice_s = 0.30;
  double reaction_delay_expert_s = 0.15;
  double correction_threshold_novice_m = 250e-6;
  double correction_threshold_expert_m = 40e-6;
  double correction_duration_s = 0.25;
  double close_duration_s = 0.4;
  double jaw_yaw_novice_rad = 0.35;
  double jaw_yaw_expert_rad = 0.02;
  double jaw_offset_novice_m = 0.25e-3;
  double jaw_offset_expert_m = 0.02e-3;
  double response_time_novice_s = 7.0;
  double response_time_expert_s = 2.5;
  double accuracy_novice = 0.4;
  double accuracy_expert = 0.95;
  double square_rule_skill = 0.35;
  double placement_angle_novice_rad = 0.25;
  double placement_angle_expert_rad = 0.03;
  double placement_bite_novice_m = 0.15e-3;
  double placement_bite_expert_m = 0.02e-3;
  double hand_stiffness_N_per_m = 400;
  double hand_time_constant_s = 0.05;
  // Throws std::invalid_argument("field: reason") (the contract of every Def's Validate()).
  void Validate() const;
};

class SimTrainee final : public Device {
 public:
  static constexpr int kTremorComponents = 3;
  static constexpr int kDriftComponents = 4;

  SimTrainee(const scene::SceneModel& scene, const SimTraineeDef& def);
  DeviceSample Read(std::uint64_t step) override;
  void WriteForce(const Eigen::Vector3d& f_T_W) override { f_prev_W_ = f_T_W; }

  double tremor_rms_m() const { return tremor_rms_m_; }
  double pace() const { return pace_; }
  double drift_std_m() const { return drift_std_m_; }

 private:
  const scene::SceneModel& scene_;
  double dt_s_;
  double tremor_rms_m_, drift_std_m_, drift_std_rad_;
  double hand_stiffness_N_per_m_;
  double freq_hz_[3][kTremorComponents];
  double phase_rad_[3][kTremorComponents];
  // Drift: [0..2] position axes, [3..5] rotation-vector axes.
  double drift_freq_hz_[6][kDriftComponents];
  double drift_phase_rad_[6][kDriftComponents];
  double hand_time_constant_s_;
  double pace_, reaction_delay_s_, correction_threshold_m_, correction_duration_s_;
  double close_duration_s_, jaw_yaw_rad_ = 0, jaw_offset_m_ = 0;
  // Knot topology: when each answer is pressed and which class it names (sized at construction).
  std::vector<double> press_s_;
  std::vector<std::uint32_t> answer_;
  std::size_t next_answer_ = 0;
  // Knot placement: each stitch's planned azimuth and height (sized at construction).
  std::vector<double> stitch_azimuth_rad_, stitch_z_m_;
  // The planned tool pose and gripper at time t (the task's passes, or the grasp's phases).
  Eigen::Isometry3d CalcPlannedPose(double t_s, double* gripper) const;
  // The corrective sub-movement under way (or the last one): from, to, start time.
  Eigen::Vector3d correction_from_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d correction_to_m_ = Eigen::Vector3d::Zero();
  double correction_start_s_ = -1e9;
  Eigen::Vector3d CalcDrift(double t_s, Eigen::Vector3d* drift_rad) const;
  Eigen::Vector3d CalcCorrection(double t_s) const;
  Eigen::Vector3d f_prev_W_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d hand_offset_m_ = Eigen::Vector3d::Zero();
  int hand_ = 0;
};

}  // namespace microdex::station
