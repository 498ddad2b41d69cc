#include "common/geometry/loop_wire_sampled.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "common/geometry/loop_wire_segment.h"

namespace microdex::geometry {

LoopWireClearance CalcLoopWireClearanceSampled(const LoopWireModel& model,
                                               const Eigen::Isometry3d& X_WL, int samples) {
  LoopWireClearance out;
  if (!X_WL.matrix().allFinite()) {
    out.clearance_m = out.distance_m = std::numeric_limits<double>::quiet_NaN();
    return out;
  }
  samples = std::max(2, samples);
  const LoopFrameInR frame(model, X_WL);
  const double R = frame.R;
  const auto to_L = [&frame](const Eigen::Vector3d& p_W) { return frame.ToL(p_W); };
  const std::vector<LoopWireModel::Piece>& pieces = model.pieces();
  const double best_ub = frame.UpperBound(model);
  double best_sq = std::numeric_limits<double>::infinity();
  Eigen::Vector3d best_p = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < pieces.size(); ++i) {
    const LoopWireModel::Piece& p = pieces[i];
    const double lower = frame.LowerBound(p);
    if (lower > std::min(best_ub, std::sqrt(best_sq))) continue;
    ++out.num_solved;
    for (int j = 0; j < samples; ++j) {
      const double u = static_cast<double>(j) / (samples - 1);
      Eigen::Vector3d q_W;
      double s_local = 0;
      if (p.kind == WirePieceDef::Kind::kSegment) {
        q_W = p.p_W0 + u * (p.p_W1 - p.p_W0);
        s_local = u * p.length_m;
      } else {
        const double s = u * p.sweep_rad;
        q_W = p.p_WO + p.radius_m * (std::cos(s) * p.u_W + std::sin(s) * p.v_W);
        s_local = s * p.radius_m;
      }
      const Eigen::Vector3d q_L = to_L(q_W);
      const double f = CircleDistSq(q_L);
      if (f < best_sq) {
        best_sq = f;
        best_p = q_L;
        out.piece = static_cast<int>(i);
        out.s_m = p.s0_m + s_local;
      }
    }
  }
  out.status = LoopWireStatus::kOk;
  out.distance_m = std::sqrt(best_sq) * R;
  out.clearance_m = out.distance_m - model.loop().wire_radius_m - model.wire_radius_m();
  out.contact = out.clearance_m <= 0;
  out.p_WA = X_WL * Eigen::Vector3d(R * best_p);
  const double k = std::hypot(best_p.x(), best_p.y());
  out.p_WC = X_WL * (k > 0 ? Eigen::Vector3d(R * best_p.x() / k, R * best_p.y() / k, 0)
                           : Eigen::Vector3d(R, 0, 0));
  return out;
}

}  // namespace microdex::geometry
