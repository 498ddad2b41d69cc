#pragma once
// Parametric knots tied around a stitch, for the knot-topology scene and the tests
// (common/knot/README.md, "Knots tied around a stitch").
//
// The tissue is the plane z = 0 and the stitch runs along x: the thread comes down from its
// first free end, enters the tissue at (-w/2, 0, 0), passes under it (a half ellipse of the
// given depth) and comes out at (+w/2, 0, 0). Above the surface the two strands rise to a
// common axis and twist about it: each throw is a full turn of the pair per single throw
// (two for the double throw of a surgeon's knot), right-handed for a positive hand, with a
// straight stretch between throws (shorter as the knot is tighter). In a half hitch one
// strand (the post) runs straight along the axis and the other winds once around it. Then
// each strand moves away from the axis and leaves as a straight tail.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <span>
#include <vector>

#include "common/knot/stitch_knot.h"

namespace microdex::knot {

struct StitchKnotShapeDef {
  // kNone, kSquare, kGranny, kSurgeons, kSlip or kHalfHitch.
  StitchKnotType kind = StitchKnotType::kSquare;
  // Thread diameter (10-0 nylon) and node spacing (0: one diameter).
  double thread_diameter_m = 3e-5;
  double node_spacing_m = 0.0;
  // Distance between the punctures, and the depth of the stitch's deepest point.
  double stitch_width_m = 3e-4;
  double stitch_depth_m = 1e-4;
  // 1: the strands touch and the throws are pressed together (two and a half diameters of
  // straight strand between throws); 0: loose (about twice the radius and the pitch, eight
  // diameters between throws).
  double tightness = 0.7;
  // Length of each straight tail, and the direction it leaves in: azimuth in the tissue plane
  // (from +x towards +y) and elevation above it, in [0, pi/2).
  double tail_length_m = 1e-3;
  double tail_first_azimuth_rad = 3.141592653589793;
  double tail_first_elevation_rad = 0.2;
  double tail_last_azimuth_rad = 0.0;
  double tail_last_elevation_rad = 0.2;
  // The knot's axis: tilt from the vertical (0 standing, towards 1.2 lying over the tissue)
  // and the azimuth it leans towards.
  double axis_tilt_rad = 0.0;
  double axis_azimuth_rad = 0.0;
  // Height of the knot's base above the tissue, in diameters beyond the strands' radius.
  double base_height_diameters = 1.5;
  // Mirror image (y -> -y): every throw of the other hand.
  bool mirror = false;
  // Slip knot: two half hitches of the same sense (a capsized granny, a clove hitch on the
  // post) instead of opposite senses (a capsized square, a lark's head on the post).
  bool slip_same_sense = false;
  // Half hitch and slip: the strand kept straight, 1 the strand of the first node, 2 of the
  // last node.
  int post_strand = 1;
  // Throws std::invalid_argument naming the bad field.
  void Validate() const;
};

// The thread as a polyline in metres, from its first free end through the stitch to its last
// free end, nodes node_spacing_m apart. Throws std::invalid_argument if the definition is
// invalid or if two parts of the thread would come closer than the thread diameter (tails
// aimed through the knot or at each other).
std::vector<Eigen::Vector3d> MakeStitchKnot(const StitchKnotShapeDef& def);

// The shape of item `index` of the knot-topology quiz (scene `knots.items`): varied from item
// to item (mirror image, lean, tails) so that the class, not the picture, is what a trainee
// learns. The station's quiz and the views draw the same shape from it.
StitchKnotShapeDef QuizItemShapeDef(StitchKnotType kind, std::size_t index,
                                    double thread_diameter_m);

// The part of a thread through the tissue (a stitch polyline: both ends above z = 0, nodes
// below it) that a knot tied on the stitch occupies: from the first node below the tissue
// back towards node 0, and from the last one on towards the other end, each tail kept up to
// its first node farther than radius_m from the stitch's nearer puncture. Returns the polyline
// unchanged when it has no node below the tissue.
std::vector<Eigen::Vector3d> CropStitchTails(std::span<const Eigen::Vector3d> polyline,
                                             double radius_m);

// Where the knot is on a stitch polyline (the tissue at z = 0): the box of the nearest points
// of every two links above the tissue that come within `contact_diameters` thread diameters
// of each other at more than about 25 degrees: the strands crossing each other and a strand
// wound on itself (a throw's wraps), not the legs running side by side to the stitch nor
// neighbouring links. thread_diameter_m <= 0: the median link. Empty (isEmpty()) when no
// links cross so near or the polyline has no node below the tissue.
Eigen::AlignedBox3d CalcStitchKnotCore(std::span<const Eigen::Vector3d> polyline,
                                       double thread_diameter_m, double contact_diameters = 4.0);

// `segments` equal arc-length pieces of an open polyline (segments + 1 points, both ends kept);
// at least two points in, segments >= 1.
std::vector<Eigen::Vector3d> ResampleByArcLength(std::span<const Eigen::Vector3d> open,
                                                 int segments);
// The length of an open polyline.
double PolylineLength(std::span<const Eigen::Vector3d> open);
// The median length of the polyline's links of nonzero length (a thread's diameter when its
// nodes are one diameter apart: StitchKnotOptions); 0 when there are none.
double MedianLinkLength(std::span<const Eigen::Vector3d> polyline);

// Smallest distance between two segments of the polyline that are more than `skip_arc_m`
// apart along it (for a thread of diameter d with nodes about d apart, `skip_arc_m` = 2 d
// excludes neighbouring links): the thread does not pass through itself if it is >= d.
double MinSelfDistance(std::span<const Eigen::Vector3d> polyline, double skip_arc_m);

}  // namespace microdex::knot
