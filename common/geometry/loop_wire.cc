#include "common/geometry/loop_wire.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>

#include "common/geometry/loop_wire_arc.h"
#include "common/geometry/loop_wire_segment.h"

namespace microdex::geometry {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Unit vectors and orthogonality of the Defs, and the pose's rotation, to this.
constexpr double kUnitTol = 1e-9;
// A piece shorter than this fraction of the course's extent has zero length.
constexpr double kMinPieceRel = 1e-12;
// Consecutive pieces must meet to within this fraction of the course's extent.
constexpr double kJoinRel = 1e-9;
// Bounding spheres are widened by this fraction of their radius and of R (their own rounding).
constexpr double kBallSlackRel = 1e-12;

bool Finite(const Eigen::Vector3d& v) { return v.allFinite(); }

[[noreturn]] void Fail(const std::string& field, const std::string& reason) {
  throw std::invalid_argument(field + ": " + reason);
}

std::string PieceField(std::size_t i, const char* member) {
  return "WireDef.pieces[" + std::to_string(i) + "]." + member;
}

bool IsRotation(const Eigen::Matrix3d& m) {
  const Eigen::Matrix3d e = m.transpose() * m - Eigen::Matrix3d::Identity();
  return e.cwiseAbs().maxCoeff() <= kUnitTol && m.determinant() > 0;
}

// The largest distance of the course's pieces' ends and arc centres from the first point,
// plus the largest arc radius: the scale of the relative tolerances.
double CourseExtent(const WireDef& wire) {
  const Eigen::Vector3d origin = wire.pieces.front().StartPoint();
  double extent = 0;
  for (const WirePieceDef& p : wire.pieces) {
    extent = std::max({extent, (p.StartPoint() - origin).norm(), (p.EndPoint() - origin).norm()});
    if (p.kind == WirePieceDef::Kind::kArc) extent = std::max(extent, p.radius_m);
  }
  return extent;
}

// Distance from p (loop frame, units of R) to the unit core circle.
double CircleDist(const Eigen::Vector3d& p) { return std::sqrt(CircleDistSq(p)); }

// The nearest point on the core circle of radius R to p_L (loop frame, metres): radial from
// the axis; on the axis, every point is nearest and (R, 0, 0) is taken.
Eigen::Vector3d NearestCirclePoint_L(const Eigen::Vector3d& p_L, double R) {
  const double k = std::hypot(p_L.x(), p_L.y());
  if (!(k > 0)) return {R, 0, 0};
  return {R * p_L.x() / k, R * p_L.y() / k, 0};
}

}  // namespace

// ---- Defs ---------------------------------------------------------------------------------

WirePieceDef WirePieceDef::Segment(const Eigen::Vector3d& p_W0, const Eigen::Vector3d& p_W1) {
  WirePieceDef d;
  d.kind = Kind::kSegment;
  d.p_W0 = p_W0;
  d.p_W1 = p_W1;
  return d;
}

double WireDef::Length() const {
  double total = 0;
  for (const WirePieceDef& p : pieces) total += p.Length();
  return total;
}

WirePieceDef WirePieceDef::Arc(const Eigen::Vector3d& p_WO, const Eigen::Vector3d& axis_W,
                               const Eigen::Vector3d& u_W, double radius_m, double sweep_rad) {
  WirePieceDef d;
  d.kind = Kind::kArc;
  d.p_WO = p_WO;
  d.axis_W = axis_W;
  d.u_W = u_W;
  d.radius_m = radius_m;
  d.sweep_rad = sweep_rad;
  return d;
}

Eigen::Vector3d WirePieceDef::StartPoint() const {
  return kind == Kind::kSegment ? p_W0 : Eigen::Vector3d(p_WO + radius_m * u_W);
}

Eigen::Vector3d WirePieceDef::EndPoint() const {
  if (kind == Kind::kSegment) return p_W1;
  return p_WO + radius_m * (std::cos(sweep_rad) * u_W + std::sin(sweep_rad) * axis_W.cross(u_W));
}

double WirePieceDef::Length() const {
  return kind == Kind::kSegment ? (p_W1 - p_W0).norm() : radius_m * sweep_rad;
}

void WireDef::Validate() const {
  if (pieces.empty()) Fail("WireDef.pieces", "expected at least one piece");
  if (!std::isfinite(radius_m) || !(radius_m > 0)) Fail("WireDef.radius_m", "expected > 0");
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const WirePieceDef& p = pieces[i];
    if (p.kind == WirePieceDef::Kind::kSegment) {
      if (!Finite(p.p_W0)) Fail(PieceField(i, "p_W0"), "expected finite coordinates");
      if (!Finite(p.p_W1)) Fail(PieceField(i, "p_W1"), "expected finite coordinates");
      continue;
    }
    if (!Finite(p.p_WO)) Fail(PieceField(i, "p_WO"), "expected finite coordinates");
    if (!Finite(p.axis_W) || std::abs(p.axis_W.norm() - 1) > kUnitTol) {
      Fail(PieceField(i, "axis_W"), "expected a unit vector");
    }
    if (!Finite(p.u_W) || std::abs(p.u_W.norm() - 1) > kUnitTol) {
      Fail(PieceField(i, "u_W"), "expected a unit vector");
    }
    if (std::abs(p.u_W.dot(p.axis_W)) > kUnitTol) {
      Fail(PieceField(i, "u_W"), "expected orthogonal to axis_W");
    }
    if (!std::isfinite(p.radius_m) || !(p.radius_m > 0)) {
      Fail(PieceField(i, "radius_m"), "expected > 0");
    }
    if (!std::isfinite(p.sweep_rad) || !(p.sweep_rad > 0) || p.sweep_rad > kTwoPi) {
      Fail(PieceField(i, "sweep_rad"), "expected a value in (0, 2π]");
    }
  }
  const double extent = CourseExtent(*this);
  if (!std::isfinite(extent)) Fail("WireDef.pieces", "expected a finite extent");
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    if (!(pieces[i].Length() > kMinPieceRel * extent)) {
      Fail(PieceField(i, pieces[i].kind == WirePieceDef::Kind::kSegment ? "p_W1" : "sweep_rad"),
           "zero-length piece (shorter than 1e-12 of the course's extent)");
    }
    if (i > 0 && (pieces[i].StartPoint() - pieces[i - 1].EndPoint()).norm() > kJoinRel * extent) {
      Fail(PieceField(i, pieces[i].kind == WirePieceDef::Kind::kSegment ? "p_W0" : "p_WO"),
           "does not start where piece " + std::to_string(i - 1) + " ends");
    }
  }
}

void LoopDef::Validate() const {
  if (!std::isfinite(radius_m) || !(radius_m > 0)) Fail("LoopDef.radius_m", "expected > 0");
  if (!std::isfinite(wire_radius_m) || !(wire_radius_m > 0)) {
    Fail("LoopDef.wire_radius_m", "expected > 0");
  }
  if (!(wire_radius_m < radius_m)) Fail("LoopDef.wire_radius_m", "expected < radius_m");
}

WireDef MakeWireCourse(const Eigen::Isometry3d& X_WS, const std::vector<WireCourseStepDef>& steps,
                       double wire_radius_m) {
  if (!X_WS.matrix().allFinite() || !IsRotation(X_WS.linear())) {
    Fail("X_WS", "expected a finite rigid pose");
  }
  WireDef wire;
  wire.radius_m = wire_radius_m;
  Eigen::Vector3d p = X_WS.translation();
  Eigen::Vector3d t = X_WS.linear().col(0), n = X_WS.linear().col(1);
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const WireCourseStepDef& s = steps[i];
    const std::string field = "WireCourseStepDef[" + std::to_string(i) + "]";
    if (s.turn_angle_rad == 0) {
      if (!std::isfinite(s.length_m) || !(s.length_m > 0)) {
        Fail(field + ".length_m", "expected > 0 for a straight run");
      }
      const Eigen::Vector3d q = p + s.length_m * t;
      wire.pieces.push_back(WirePieceDef::Segment(p, q));
      p = q;
      continue;
    }
    if (!std::isfinite(s.turn_angle_rad) || !(s.turn_angle_rad > 0) || s.turn_angle_rad > kTwoPi) {
      Fail(field + ".turn_angle_rad", "expected a value in (0, 2π]");
    }
    if (!std::isfinite(s.turn_radius_m) || !(s.turn_radius_m > 0)) {
      Fail(field + ".turn_radius_m", "expected > 0 for a turn");
    }
    if (!std::isfinite(s.turn_plane_rad)) Fail(field + ".turn_plane_rad", "expected finite");
    const Eigen::Vector3d b = t.cross(n);
    const Eigen::Vector3d towards =
        (std::cos(s.turn_plane_rad) * n + std::sin(s.turn_plane_rad) * b).normalized();
    const Eigen::Vector3d axis = t.cross(towards).normalized();
    const Eigen::Vector3d centre = p + s.turn_radius_m * towards;
    wire.pieces.push_back(
        WirePieceDef::Arc(centre, axis, -towards, s.turn_radius_m, s.turn_angle_rad));
    // The frame turns with the path about the turn's axis.
    const Eigen::AngleAxisd turn(s.turn_angle_rad, axis);
    p = wire.pieces.back().EndPoint();
    t = (turn * t).normalized();
    n = turn * n;
    n = (n - n.dot(t) * t).normalized();
  }
  wire.Validate();
  return wire;
}

// ---- Model --------------------------------------------------------------------------------

LoopWireModel::LoopWireModel(const LoopDef& loop, const WireDef& wire)
    : loop_(loop), wire_radius_m_(wire.radius_m) {
  loop.Validate();
  wire.Validate();
  pieces_.reserve(wire.pieces.size());
  double s0 = 0;
  for (const WirePieceDef& d : wire.pieces) {
    Piece p;
    p.kind = d.kind;
    p.p_W0 = d.StartPoint();
    p.p_W1 = d.EndPoint();
    p.length_m = d.Length();
    p.s0_m = s0;
    if (d.kind == WirePieceDef::Kind::kSegment) {
      p.t_W = (d.p_W1 - d.p_W0) / p.length_m;
      p.p_WBall = 0.5 * (d.p_W0 + d.p_W1);
      p.ball_radius_m = 0.5 * p.length_m;
    } else {
      // Re-orthonormalised axes (the Def is unit and orthogonal to 1e-9 only).
      const Eigen::Vector3d axis = d.axis_W.normalized();
      p.u_W = (d.u_W - d.u_W.dot(axis) * axis).normalized();
      p.v_W = axis.cross(p.u_W);
      p.p_WO = d.p_WO;
      p.radius_m = d.radius_m;
      p.sweep_rad = d.sweep_rad;
      const double h = 0.5 * d.sweep_rad;
      p.p_WBall = d.p_WO + d.radius_m * (std::cos(h) * p.u_W + std::sin(h) * p.v_W);
      // The farthest arc point from its midpoint is an end: chord 2ρ sin(S/4).
      p.ball_radius_m = 2 * d.radius_m * std::sin(0.25 * d.sweep_rad);
    }
    p.ball_radius_m += kBallSlackRel * (p.ball_radius_m + loop.radius_m);
    s0 += p.length_m;
    pieces_.push_back(p);
  }
  length_m_ = s0;
}

const char* ToString(LoopWireStatus status) {
  switch (status) {
    case LoopWireStatus::kOk:
      return "ok";
    case LoopWireStatus::kInvalidPose:
      return "invalid pose";
    case LoopWireStatus::kNotConverged:
      return "not converged";
  }
  return "?";
}

// ---- Clearance ----------------------------------------------------------------------------

LoopFrameInR::LoopFrameInR(const LoopWireModel& model, const Eigen::Isometry3d& X_WL)
    : R(model.loop().radius_m),
      inv_R(1 / model.loop().radius_m),
      R_LW(X_WL.linear().transpose()),
      p_WLo(X_WL.translation()) {}

double LoopFrameInR::CentreDistance(const LoopWireModel::Piece& piece) const {
  return CircleDist(ToL(piece.p_WBall));
}

double LoopFrameInR::LowerBound(const LoopWireModel::Piece& piece) const {
  return CentreDistance(piece) - piece.ball_radius_m * inv_R;
}

double LoopFrameInR::UpperBound(const LoopWireModel& model) const {
  double best = std::numeric_limits<double>::infinity();
  for (const LoopWireModel::Piece& p : model.pieces()) best = std::min(best, CentreDistance(p));
  return best;
}

LoopWireClearance CalcLoopWireClearance(const LoopWireModel& model, const Eigen::Isometry3d& X_WL) {
  LoopWireClearance out;
  if (!X_WL.matrix().allFinite() || !IsRotation(X_WL.linear())) {
    out.status = LoopWireStatus::kInvalidPose;
    out.clearance_m = out.distance_m = kNaN;
    return out;
  }
  const LoopFrameInR frame(model, X_WL);
  const double R = frame.R, inv_R = frame.inv_R;
  const Eigen::Matrix3d& R_LW = frame.R_LW;
  const auto to_L = [&frame](const Eigen::Vector3d& p_W) { return frame.ToL(p_W); };
  const std::vector<LoopWireModel::Piece>& pieces = model.pieces();
  // Pass 1: an upper bound of the distance (units of R), from each piece's midpoint.
  const double best_ub = frame.UpperBound(model);
  // Pass 2: the exact distance of every piece whose sphere may come closer.
  double best_sq = std::numeric_limits<double>::infinity();
  LoopWirePieceMin best_min;
  int best_piece = -1;
  bool converged = true;
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const LoopWireModel::Piece& p = pieces[i];
    const double lower = frame.LowerBound(p);
    const double bound = std::min(best_ub, std::sqrt(best_sq));
    if (lower > bound) continue;
    ++out.num_solved;
    LoopWirePieceMin m;
    if (p.kind == WirePieceDef::Kind::kSegment) {
      m = CalcSegmentCircleMin(to_L(p.p_W0), to_L(p.p_W1));
      m.param *= R;  // arc length in metres
    } else {
      const double rho = p.radius_m * inv_R;
      const double rho_sq_minus_one = (p.radius_m - R) * (p.radius_m + R) * inv_R * inv_R;
      m = CalcArcCircleMin(to_L(p.p_WO), R_LW * p.u_W, R_LW * p.v_W, rho, rho_sq_minus_one,
                           p.sweep_rad);
      m.param *= p.radius_m;
    }
    converged = converged && m.converged;
    if (m.dist_sq < best_sq) {
      best_sq = m.dist_sq;
      best_min = m;
      best_piece = static_cast<int>(i);
    }
  }
  const LoopWireModel::Piece& bp = pieces[static_cast<std::size_t>(best_piece)];
  out.status = converged ? LoopWireStatus::kOk : LoopWireStatus::kNotConverged;
  out.distance_m = std::sqrt(best_sq) * R;
  out.clearance_m = out.distance_m - model.loop().wire_radius_m - model.wire_radius_m();
  out.contact = out.clearance_m <= 0;
  out.piece = best_piece;
  out.s_m = bp.s0_m + best_min.param;
  const Eigen::Vector3d p_LA = R * best_min.p;
  out.p_WA = X_WL * p_LA;
  out.p_WC = X_WL * NearestCirclePoint_L(p_LA, R);
  return out;
}

// ---- Progress -----------------------------------------------------------------------------

WireProgress CalcWireProgress(const LoopWireModel& model, const Eigen::Vector3d& p_W) {
  WireProgress out;
  if (!p_W.allFinite()) {
    out.distance_m = out.s_m = kNaN;
    return out;
  }
  out.status = LoopWireStatus::kOk;
  double best = std::numeric_limits<double>::infinity();
  const std::vector<LoopWireModel::Piece>& pieces = model.pieces();
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const LoopWireModel::Piece& p = pieces[i];
    if ((p_W - p.p_WBall).norm() - p.ball_radius_m > best) continue;
    double s_local = 0;
    Eigen::Vector3d q, t;
    if (p.kind == WirePieceDef::Kind::kSegment) {
      s_local = std::clamp((p_W - p.p_W0).dot(p.t_W), 0.0, p.length_m);
      q = p.p_W0 + s_local * p.t_W;
      t = p.t_W;
    } else {
      // The arc point at the azimuth of p's projection on the arc's plane, or the nearer end
      // when that azimuth is outside the sweep (on the arc's axis: every azimuth is as near,
      // and s = 0 is taken).
      const Eigen::Vector3d r = p_W - p.p_WO;
      double s = std::atan2(r.dot(p.v_W), r.dot(p.u_W));
      if (s < 0) s += kTwoPi;
      if (s > p.sweep_rad) {
        const Eigen::Vector3d end = p.p_W1;
        s = (p_W - p.p_W0).norm() <= (p_W - end).norm() ? 0 : p.sweep_rad;
      }
      const double cs = std::cos(s), sn = std::sin(s);
      q = p.p_WO + p.radius_m * (cs * p.u_W + sn * p.v_W);
      t = cs * p.v_W - sn * p.u_W;
      s_local = s * p.radius_m;
    }
    const double d = (p_W - q).norm();
    if (d < best) {
      best = d;
      out.s_m = p.s0_m + s_local;
      out.distance_m = d;
      out.piece = static_cast<int>(i);
      out.p_WA = q;
      out.t_W = t;
    }
  }
  return out;
}

}  // namespace microdex::geometry
