#pragma once
// The task score, from the running totals the haptic thread keeps (state::ScoreState).
//
// Scenes of a training task (scene::TaskKind other than follow_path) name their terms in the
// scene file (`scoring:`): each metric's value v scores
//     points = weight · clamp(1 − v / limit, 0, 1)
// and the score is 100 Σ points / Σ weights, so a term at 0 earns its whole weight and one at
// or beyond its limit nothing. The metrics:
//   time_s             time to the task's end (completion, or the time limit), s
//   deviation_mean_m   mean distance of the device from the ideal path (the hold target), m
//   deviation_max_m    the largest such distance, m
//   drift_m            the same for the device's slow motion (its 8–12 Hz band removed), m
//   outside_fraction   share of the time farther than task.tolerance_m
//   tremor_rms_m       RMS of the device's 8–12 Hz band (the tremor module), m
//   contact_fraction   share of the time at fault (needle on the wall, thread overstretched,
//                      tissue pressed too hard)
//   contacts           fault episodes
//   clearance_deficit  1 − mean needle clearance / tube radius (0: on the core circle)
//   excess_path        device path length / the path the task asks for − 1
//   progress_deficit   share of the task not done when it ended (0 when completed)
//   object_rotation_rad  grasp: the largest rotation the jaws induced in the object
//   jaw_alignment_rad    grasp: angle between the closing direction and the object's face
//   object_drops         grasp: lifted objects that fell out of the jaws
//   wrong_fraction       knot topology: knots named wrongly or not at all, of those shown
//   response_time_s      knot topology: mean time from a knot's appearance to its answer
//   spacing_error_rad    knot placement: RMS of the angular gaps against 2π / n
//   shape_error_m        nylon control: RMS distance of the thread's nodes from the target shape
//                        after the rigid motion that best aligns them (Kabsch)
//   bite_error_m         knot placement: RMS of the stitches' distance from the edge against the
//                        scene's bite
//   entry_error_m        needle through tissue: distance of the first hole made from above
//                        from puncture.entry_target_m (1 m until it is made)
//   exit_error_m         ... of the first hole made from below from exit_target_m (likewise)
//   peak_strain          ... the largest hole strain, |lateral offset| / wire radius
//   torn_m               ... the length the holes tore (common/puncture/README.md)
//   off_circle_m         ... the needle's motion across its holes, summed
//   extra_punctures      ... punctures beyond the two the task needs
//   knot_wrong         knot tying: 0 when the knot recognised at the task's end is square or
//                      surgeon's, else 1 (granny, slip, half hitch, none, unknown, or not yet
//                      recognised: totals.tied_knot is set off the haptic thread by
//                      RecogniseTiedKnot at the end)
//   tension_error      knot tying: RMS over the hold of (|pull on an end| − hold tension) /
//                      hold tension, both ends (no value before the hold)
//
// follow_path (the module demos) keeps its own formula:
//   needle:        100 (1 − c) (1 + g) / 2,  c the contact fraction, g = clamp(mean
//                  clearance / tube radius, 0, 1)
//   other modules: 100 (1 − c)

#include <span>
#include <vector>

#include "common/knot/stitch_knot.h"
#include "common/net/messages.h"
#include "common/scene/scene.h"
#include "common/state/station_state.h"

namespace microdex::station {

net::Score CalcScore(const scene::SceneModel& scene, const state::ScoreState& totals);

// Knot tying: the knot around the stitch in the thread's nodes x_W (the scene's frame), named
// by the stitch-knot recogniser (kUnknown for a scene without knot_tying or a polyline that is
// not through the tissue). Allocates and takes milliseconds: never in the haptic thread.
knot::StitchKnotType RecogniseTiedKnot(const scene::SceneModel& scene,
                                       std::span<const Eigen::Vector3d> x_W);
// The thread's nodes x_W as the recogniser reads them: in the tissue's frame (the surface z = 0,
// z out of the tissue), tails that lie below the surface away from the stitch lifted onto it
// (the polyline of `microdex-bench knot` and of knots.tied; empty without knot_tying).
std::vector<Eigen::Vector3d> CalcStitchKnotPolyline(const scene::SceneModel& scene,
                                                    std::span<const Eigen::Vector3d> x_W);

// The value of a named metric (the list above); NaN for an unknown name.
double CalcScoreMetric(const scene::SceneModel& scene, const state::ScoreState& totals,
                       const std::string& metric);

// The length of the path the task asks for (all passes), m; 0 for a hold.
double CalcTaskPathLength(const scene::SceneModel& scene);

}  // namespace microdex::station
