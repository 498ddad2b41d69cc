#pragma once
// The "loop along a wire" dexterity task (thesis §2.2): the trainee passes a loop, a ring of
// wire, along a wire course in straight and turning motions, in several orientations, without
// touching it. Both are solids of circular section:
//   the loop: its core circle of radius R in the xy plane of the loop frame L, centred at L's
//             origin, thickened by the loop wire's radius r_l (a torus);
//   the wire: a path of straight segments and circular arcs (its axis), thickened by r_w.
//
//   clearance = min over wire-axis points of distance(point, loop core circle) − r_l − r_w,
//
// positive: the gap between the two surfaces; ≤ 0: they touch (negative: interpenetration
// depth along the line of the two axes' nearest points). It is the needle–vessel problem of
// thesis chapter 4 turned round: there an arc against the torus around a circle, here every
// piece of the wire against the torus around the loop's circle (README.md, "Loop along a
// wire").
//
// The Defs are validated once (Validate() throws std::invalid_argument naming the field); the
// model is built from them once; the queries do not allocate, lock or throw, and report
// numerical trouble and bad poses through a status.

#include <Eigen/Geometry>
#include <vector>

namespace microdex::geometry {

// One piece of the wire's axis, in world.
struct WirePieceDef {
  enum class Kind { kSegment, kArc };
  Kind kind = Kind::kSegment;
  // Segment: from p_W0 to p_W1.
  Eigen::Vector3d p_W0 = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_W1 = Eigen::Vector3d::UnitX() * 1e-2;
  // Arc: p(s) = p_WO + radius_m (cos s u_W + sin s (axis_W × u_W)), s ∈ [0, sweep_rad]; it
  // turns right-handedly about axis_W. axis_W and u_W unit and orthogonal (to 1e-9).
  Eigen::Vector3d p_WO = Eigen::Vector3d::Zero();     // centre
  Eigen::Vector3d axis_W = Eigen::Vector3d::UnitZ();  // unit normal of the arc's plane
  Eigen::Vector3d u_W = Eigen::Vector3d::UnitX();     // unit, from the centre to s = 0
  double radius_m = 5e-3;                             // > 0
  double sweep_rad = 3.14159265358979323846 / 2;      // (0, 2π]

  static WirePieceDef Segment(const Eigen::Vector3d& p_W0, const Eigen::Vector3d& p_W1);
  static WirePieceDef Arc(const Eigen::Vector3d& p_WO, const Eigen::Vector3d& axis_W,
                          const Eigen::Vector3d& u_W, double radius_m, double sweep_rad);

  Eigen::Vector3d StartPoint() const;
  Eigen::Vector3d EndPoint() const;
  double Length() const;  // m
};

struct WireDef {
  std::vector<WirePieceDef> pieces;  // joined end to end, in order
  double radius_m = 0.25e-3;         // r_w > 0

  double Length() const;  // of the axis, m: the pieces' lengths summed

  // Throws std::invalid_argument("WireDef.<field>: reason"): no pieces; a non-finite value; a
  // piece shorter than 1e-12 of the course's extent (zero length); an arc radius ≤ 0, sweep
  // outside (0, 2π], axis or u not unit or not orthogonal (1e-9); a gap between one piece's
  // end and the next one's start beyond 1e-9 of the extent; radius_m ≤ 0.
  void Validate() const;
};

// One step of a course built from its start: a straight run, or a turn of turn_angle_rad on a
// circle of turn_radius_m, bending towards the direction that makes turn_plane_rad with the
// current normal about the current tangent (0: towards the normal, π/2: towards the
// binormal). The frame (tangent, normal, binormal) is carried along the course, so turns in
// several orientations are written relative to the path.
struct WireCourseStepDef {
  double length_m = 0;        // straight run when turn_angle_rad == 0; > 0
  double turn_radius_m = 0;   // > 0 for a turn
  double turn_angle_rad = 0;  // (0, 2π] for a turn
  double turn_plane_rad = 0;  // rotation of the turn's plane about the tangent

  static WireCourseStepDef Straight(double length_m) { return {length_m, 0, 0, 0}; }
  static WireCourseStepDef Turn(double radius_m, double angle_rad, double plane_rad = 0) {
    return {0, radius_m, angle_rad, plane_rad};
  }
};

// The course starting at X_WS's origin along its x axis, with its y axis as the first normal.
// Throws std::invalid_argument("WireCourseStepDef[i].<field>: reason") on a bad step, and
// whatever WireDef::Validate throws.
WireDef MakeWireCourse(const Eigen::Isometry3d& X_WS, const std::vector<WireCourseStepDef>& steps,
                       double wire_radius_m);

// The loop, in its frame L: core circle of radius R in L's xy plane around L's origin.
struct LoopDef {
  double radius_m = 2e-3;         // R > 0
  double wire_radius_m = 0.1e-3;  // r_l, 0 < r_l < R (a ring)

  // Throws std::invalid_argument("LoopDef.<field>: reason").
  void Validate() const;
};

// The description, built once: per piece its geometry, its arc-length offset, and a bounding
// sphere, so that a query over a long course solves exactly only the pieces whose sphere
// comes closer to the loop than the best piece found so far.
class LoopWireModel {
 public:
  struct Piece {
    WirePieceDef::Kind kind = WirePieceDef::Kind::kSegment;
    Eigen::Vector3d p_W0, p_W1;      // segment ends (arc: its first and last point)
    Eigen::Vector3d t_W;             // segment: unit direction
    Eigen::Vector3d p_WO, u_W, v_W;  // arc: centre and unit in-plane axes (v = axis × u)
    double radius_m = 0;             // arc radius
    double sweep_rad = 0;            // arc sweep
    double length_m = 0;             // m
    double s0_m = 0;                 // arc length of the course at the piece's start
    Eigen::Vector3d p_WBall;         // bounding sphere centre (on the piece: its midpoint)
    double ball_radius_m = 0;        // every point of the piece lies within this of p_WBall
  };

  // Validates both Defs (throws std::invalid_argument).
  LoopWireModel(const LoopDef& loop, const WireDef& wire);

  const LoopDef& loop() const { return loop_; }
  double wire_radius_m() const { return wire_radius_m_; }
  const std::vector<Piece>& pieces() const { return pieces_; }
  double length_m() const { return length_m_; }
  // The scale of the scene (the loop radius), for relative tolerances.
  double scale_m() const { return loop_.radius_m; }

 private:
  LoopDef loop_;
  double wire_radius_m_ = 0;
  std::vector<Piece> pieces_;
  double length_m_ = 0;
};

enum class LoopWireStatus {
  kOk,            // every field valid
  kInvalidPose,   // X_WL (or p_W) not finite, or its linear part not a rotation (1e-9)
  kNotConverged,  // an arc's certificate rounds ran out: the result is the best point found
                  // (an upper bound of the distance), still finite
};
const char* ToString(LoopWireStatus status);

struct LoopWireClearance {
  LoopWireStatus status = LoopWireStatus::kInvalidPose;
  double clearance_m = 0;  // distance_m − r_l − r_w (NaN when kInvalidPose)
  double distance_m = 0;   // between the wire's axis and the loop's core circle
  bool contact = false;    // clearance_m ≤ 0
  Eigen::Vector3d p_WA = Eigen::Vector3d::Zero();  // A: nearest point on the wire's axis
  Eigen::Vector3d p_WC = Eigen::Vector3d::Zero();  // C: nearest point on the loop's core circle
  int piece = -1;                                  // the piece holding A
  double s_m = 0;                                  // arc length of A along the course
  int num_solved = 0;  // pieces solved exactly (the others were excluded by their spheres)
};

// The clearance for the loop at pose X_WL. No allocation, no exception.
LoopWireClearance CalcLoopWireClearance(const LoopWireModel& model, const Eigen::Isometry3d& X_WL);

// The queries' working frame: world points in the loop frame L in units of the loop radius R
// (the translation subtracted first, then rotated), and the cheap bounds of the pieces.
struct LoopFrameInR {
  LoopFrameInR(const LoopWireModel& model, const Eigen::Isometry3d& X_WL);
  Eigen::Vector3d ToL(const Eigen::Vector3d& p_W) const { return inv_R * (R_LW * (p_W - p_WLo)); }
  // A piece's sphere centre's distance to the loop circle (units of R).
  double CentreDistance(const LoopWireModel::Piece& piece) const;
  // Its sphere's lower bound of the piece's distance: CentreDistance − ball radius.
  double LowerBound(const LoopWireModel::Piece& piece) const;
  // The least CentreDistance of the pieces: an upper bound of the wire's distance.
  double UpperBound(const LoopWireModel& model) const;

  double R = 1, inv_R = 1;
  Eigen::Matrix3d R_LW = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_WLo = Eigen::Vector3d::Zero();
};

struct WireProgress {
  LoopWireStatus status = LoopWireStatus::kInvalidPose;
  double s_m = 0;         // arc length of the wire-axis point nearest to p (0 … length)
  double distance_m = 0;  // from p to that point: the offset from the wire's axis
  int piece = -1;
  Eigen::Vector3d p_WA = Eigen::Vector3d::Zero();  // that point
  Eigen::Vector3d t_W = Eigen::Vector3d::Zero();   // unit tangent of the course there
};

// Where along the course the point p_W (the loop's centre) is: task progress (s_m / length),
// completion, and the offset from the wire's axis. Ties (equidistant pieces, or a point on an
// arc's axis) go to the lowest arc length. No allocation, no exception.
WireProgress CalcWireProgress(const LoopWireModel& model, const Eigen::Vector3d& p_W);

}  // namespace microdex::geometry
