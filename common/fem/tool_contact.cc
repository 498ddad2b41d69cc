#include "common/fem/tool_contact.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace microdex::fem {
namespace {

// Squared planar distance from (px, py) to the segment a–b; *t gets the closest point's
// parameter. Squared distances (no hypot) keep the per-cell test of the mesh selection cheap;
// the lengths involved are far from overflow.
double PointSegmentDistance2(double px, double py, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b, double* t) {
  const double dx = b.x() - a.x(), dy = b.y() - a.y();
  const double len2 = dx * dx + dy * dy;
  double s = 0;
  if (len2 > 0) s = std::clamp(((px - a.x()) * dx + (py - a.y()) * dy) / len2, 0.0, 1.0);
  *t = s;
  const double ex = px - (a.x() + s * dx), ey = py - (a.y() + s * dy);
  return ex * ex + ey * ey;
}

double PointBoxDistance2(double px, double py, double x0, double y0, double x1, double y1) {
  const double dx = std::max({x0 - px, 0.0, px - x1});
  const double dy = std::max({y0 - py, 0.0, py - y1});
  return dx * dx + dy * dy;
}

double Cross(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }

// True when segments p–q and r–s (planar) intersect, touching included.
bool SegmentsIntersect(double px, double py, double qx, double qy, double rx, double ry, double sx,
                       double sy) {
  const double d1 = Cross(qx - px, qy - py, rx - px, ry - py);
  const double d2 = Cross(qx - px, qy - py, sx - px, sy - py);
  const double d3 = Cross(sx - rx, sy - ry, px - rx, py - ry);
  const double d4 = Cross(sx - rx, sy - ry, qx - rx, qy - ry);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0)))
    return true;
  return false;  // collinear/touching cases are caught by the endpoint distances
}

}  // namespace

ToolContact MakePointTool(const Eigen::Vector3d& p_SP, double contact_radius_m) {
  ToolContact tool;
  tool.num_points = 1;
  tool.p_SP[0] = p_SP;
  tool.contact_radius_m = contact_radius_m;
  tool.p_ST = p_SP;
  return tool;
}

ToolContact MakeBarTool(const Eigen::Vector3d& p_SA, const Eigen::Vector3d& p_SB) {
  ToolContact tool;
  tool.num_points = 2;
  tool.p_SP[0] = p_SA;
  tool.p_SP[1] = p_SB;
  tool.p_ST = 0.5 * (p_SA + p_SB);
  return tool;
}

ToolContact MakePolylineTool(std::span<const Eigen::Vector3d> p_SP, double contact_radius_m) {
  if (p_SP.empty() || p_SP.size() > kMaxToolPoints) {
    throw std::invalid_argument("polyline tool: expected 1 to 16 points, got " +
                                std::to_string(p_SP.size()));
  }
  ToolContact tool;
  tool.num_points = static_cast<int>(p_SP.size());
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int i = 0; i < tool.num_points; ++i) {
    tool.p_SP[i] = p_SP[i];
    sum += p_SP[i];
  }
  tool.p_ST = sum / tool.num_points;
  tool.contact_radius_m = contact_radius_m;
  return tool;
}

double ToolBoxDistance_m(const ToolContact& tool, double x0_m, double y0_m, double x1_m,
                         double y1_m) {
  double best = std::numeric_limits<double>::infinity();
  if (tool.num_points <= 0) return best;
  for (int k = 0; k < tool.num_points; ++k) {
    best = std::min(best,
                    PointBoxDistance2(tool.p_SP[k].x(), tool.p_SP[k].y(), x0_m, y0_m, x1_m, y1_m));
  }
  if (best == 0) return 0.0;
  const double cx[4] = {x0_m, x1_m, x1_m, x0_m};
  const double cy[4] = {y0_m, y0_m, y1_m, y1_m};
  for (int k = 0; k + 1 < tool.num_points; ++k) {
    const Eigen::Vector3d& a = tool.p_SP[k];
    const Eigen::Vector3d& b = tool.p_SP[k + 1];
    // A segment and a convex polygon that do not meet are closest at a vertex of one of them.
    for (int c = 0; c < 4; ++c) {
      double t = 0;
      best = std::min(best, PointSegmentDistance2(cx[c], cy[c], a, b, &t));
      if (SegmentsIntersect(a.x(), a.y(), b.x(), b.y(), cx[c], cy[c], cx[(c + 1) % 4],
                            cy[(c + 1) % 4]))
        return 0.0;
    }
  }
  return std::sqrt(best);
}

double ToolClosestPoint_m(const ToolContact& tool, double x_m, double y_m, double* z_m) {
  double best = std::numeric_limits<double>::infinity();
  *z_m = 0;
  if (tool.num_points == 1) {
    *z_m = tool.p_SP[0].z();
    return std::hypot(x_m - tool.p_SP[0].x(), y_m - tool.p_SP[0].y());
  }
  for (int k = 0; k + 1 < tool.num_points; ++k) {
    double t = 0;
    const double d2 = PointSegmentDistance2(x_m, y_m, tool.p_SP[k], tool.p_SP[k + 1], &t);
    if (d2 < best) {
      best = d2;
      *z_m = (1 - t) * tool.p_SP[k].z() + t * tool.p_SP[k + 1].z();
    }
  }
  return std::sqrt(best);
}

}  // namespace microdex::fem
