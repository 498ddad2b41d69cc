#include "common/fem/mesh_map.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace microdex::fem {
namespace {

std::uint64_t Mix(std::uint64_t h, double v) {
  h ^= std::bit_cast<std::uint64_t>(v) + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
  return h * 1099511628211ull;
}

// The tool's planar centroid and the radius of the disc about it that holds every vertex.
void Centroid(const ToolContact& tool, double* cx, double* cy, double* radius) {
  double sx = 0, sy = 0;
  for (int k = 0; k < tool.num_points; ++k) {
    sx += tool.p_SP[k].x();
    sy += tool.p_SP[k].y();
  }
  *cx = sx / tool.num_points;
  *cy = sy / tool.num_points;
  double r2 = 0;
  for (int k = 0; k < tool.num_points; ++k) {
    const double dx = tool.p_SP[k].x() - *cx, dy = tool.p_SP[k].y() - *cy;
    r2 = std::max(r2, dx * dx + dy * dy);
  }
  *radius = std::sqrt(r2);
}

// One axis of the map, or nullopt-like false when the shift squeezes or stretches a side of
// the patch beyond kMaxMeshStretch.
bool AxisFor(bool slide, double lo, double hi, double length, double shift, AxisMap* out) {
  *out = AxisMap{};
  if (!slide || shift == 0) return true;
  const double left = (lo + shift) / lo, right = (length - hi - shift) / (length - hi);
  const auto ok = [](double s) { return s >= 1 / kMaxMeshStretch && s <= kMaxMeshStretch; };
  if (!ok(left) || !ok(right)) return false;
  *out = AxisMap{lo, hi, length, shift};
  return true;
}

}  // namespace

std::uint64_t MeshMap::Hash() const {
  std::uint64_t h = 0x51ed270b27c6a1cbull;
  for (const AxisMap* a : {&x, &y}) {
    h = Mix(h, a->lo_m);
    h = Mix(h, a->hi_m);
    h = Mix(h, a->shift_m);
  }
  if (twist.turn_rad != 0) {
    for (double v : {twist.cx_m, twist.cy_m, twist.r1_m, twist.r2_m, twist.turn_rad}) h = Mix(h, v);
  }
  return h;
}

namespace {

// The nearest and the farthest distance from (cx, cy) to the rectangle.
void Distances(double cx, double cy, double x0, double x1, double y0, double y1, double* near,
               double* far) {
  const double nx = std::max({x0 - cx, 0.0, cx - x1}), ny = std::max({y0 - cy, 0.0, cy - y1});
  const double fx = std::max(std::abs(x0 - cx), std::abs(x1 - cx));
  const double fy = std::max(std::abs(y0 - cy), std::abs(y1 - cy));
  *near = std::sqrt(nx * nx + ny * ny);
  *far = std::sqrt(fx * fx + fy * fy);
}

}  // namespace

int TwistMap::Classify(double x0, double x1, double y0, double y1) const {
  if (turn_rad == 0) return 0;
  double near = 0, far = 0;
  Distances(cx_m, cy_m, x0, x1, y0, y1, &near, &far);
  if (near >= r2_m) return 0;
  if (far <= r1_m) return 1;
  return 2;
}

void MeshMap::ImageBox(double x0, double x1, double y0, double y1, double* px0, double* px1,
                       double* py0, double* py1) const {
  if (twist.turn_rad != 0) {
    // A point at distance r ≤ r₂ moves by at most |θ| r (the chord of its turn); beyond r₂ it
    // stays.
    double near = 0, far = 0;
    Distances(twist.cx_m, twist.cy_m, x0, x1, y0, y1, &near, &far);
    if (near < twist.r2_m) {
      const double grow = std::abs(twist.turn_rad) * std::min(far, twist.r2_m);
      x0 -= grow;
      x1 += grow;
      y0 -= grow;
      y1 += grow;
    }
  }
  *px0 = x.ToPhysical(x0);  // each axis is monotone
  *px1 = x.ToPhysical(x1);
  *py0 = y.ToPhysical(y0);
  *py1 = y.ToPhysical(y1);
}

MeshMap AttachMesh(const TissueModel& model, const ToolContact& tool, MeshAnchor& anchor,
                   bool* reattached) {
  const TissueDef& def = model.def;
  const double lx = def.length_x_m, ly = def.length_y_m;
  double cx = 0, cy = 0, radius = 0;
  Centroid(tool, &cx, &cy, &radius);
  // The triangles that hold the tool's points lie within a nominal cell of the tool: with the
  // box that much wider than the tool they move rigidly with it (exact barycentric coordinates).
  const double margin =
      kMeshBoxMarginCells * std::max(model.CellSizeX_m(def.level), model.CellSizeY_m(def.level));
  *reattached = false;
  if (anchor.valid) {
    MeshMap map;
    const double sx = anchor.slide_x ? cx - anchor.cx_m : 0;
    const double sy = anchor.slide_y ? cy - anchor.cy_m : 0;
    // The tool's turn since attaching: the angle that best carries the attached vertices about
    // their centroid onto the present ones about theirs (2-D Procrustes).
    double turn = 0;
    if (anchor.twist_r2_m > 0 && tool.num_points == anchor.num_points) {
      double c = 0, s = 0;
      for (int k = 0; k < tool.num_points; ++k) {
        const double ax = anchor.x_m[k] - anchor.cx_m, ay = anchor.y_m[k] - anchor.cy_m;
        const double px = tool.p_SP[k].x() - cx, py = tool.p_SP[k].y() - cy;
        c += ax * px + ay * py;
        s += ax * py - ay * px;
      }
      turn = std::atan2(s, c);
    }
    const double max_turn =
        anchor.twist_r2_m > 0
            ? std::min(kMaxTwist_rad,
                       kMaxTwistShear * std::log(anchor.twist_r2_m / anchor.twist_r1_m))
            : 0;
    if (turn != 0)
      map.twist = {anchor.cx_m, anchor.cy_m, anchor.twist_r1_m, anchor.twist_r2_m, turn};
    // The tool (moved back by the map) must stay in the box, clear of its sides by half the
    // margin: a tool that changes shape or drifts along a fixed axis attaches afresh.
    const double half = 0.5 * margin;
    bool inside = std::abs(turn) <= max_turn;
    if (inside && AxisFor(anchor.slide_x, anchor.x_lo_m, anchor.x_hi_m, lx, sx, &map.x) &&
        AxisFor(anchor.slide_y, anchor.y_lo_m, anchor.y_hi_m, ly, sy, &map.y)) {
      for (int k = 0; k < tool.num_points; ++k) {
        double rx = 0, ry = 0;
        map.ToReference(tool.p_SP[k].x(), tool.p_SP[k].y(), &rx, &ry);
        inside = inside &&
                 (!anchor.slide_x || (rx >= anchor.x_lo_m + half && rx <= anchor.x_hi_m - half));
        inside = inside &&
                 (!anchor.slide_y || (ry >= anchor.y_lo_m + half && ry <= anchor.y_hi_m - half));
      }
      if (inside) return map;
    }
  }
  // Attach here: the box about the tool, each axis sliding only where the box leaves at least
  // a margin of patch on both sides (room to squeeze).
  *reattached = anchor.valid;
  anchor.valid = true;
  anchor.cx_m = cx;
  anchor.cy_m = cy;
  const double reach = radius + margin;
  anchor.x_lo_m = cx - reach;
  anchor.x_hi_m = cx + reach;
  anchor.y_lo_m = cy - reach;
  anchor.y_hi_m = cy + reach;
  anchor.slide_x = anchor.x_lo_m >= margin && anchor.x_hi_m <= lx - margin;
  anchor.slide_y = anchor.y_lo_m >= margin && anchor.y_hi_m <= ly - margin;
  // The twist reaches from the box's inscribed disc to the nearest edge; a point tool does not
  // turn.
  const double edge = std::min({cx, lx - cx, cy, ly - cy});
  const bool twist = tool.num_points >= 2 && radius > 0 && edge >= kMinTwistReach * reach;
  anchor.twist_r1_m = twist ? reach : 0;
  anchor.twist_r2_m = twist ? edge : 0;
  anchor.num_points = tool.num_points;
  for (int k = 0; k < tool.num_points; ++k) {
    anchor.x_m[k] = tool.p_SP[k].x();
    anchor.y_m[k] = tool.p_SP[k].y();
  }
  return MeshMap{};  // the identity where the mesh attaches
}

ToolContact ToReference(const MeshMap& map, const MeshAnchor& anchor, const ToolContact& tool) {
  ToolContact ref = tool;
  const bool same_count = anchor.num_points == tool.num_points;
  for (int k = 0; k < tool.num_points; ++k) {
    double x = 0, y = 0;
    map.ToReference(tool.p_SP[k].x(), tool.p_SP[k].y(), &x, &y);
    if (same_count && std::abs(x - anchor.x_m[k]) < kReferenceSnap_m) x = anchor.x_m[k];
    if (same_count && std::abs(y - anchor.y_m[k]) < kReferenceSnap_m) y = anchor.y_m[k];
    ref.p_SP[k].x() = x;
    ref.p_SP[k].y() = y;
  }
  map.ToReference(tool.p_ST.x(), tool.p_ST.y(), &ref.p_ST.x(), &ref.p_ST.y());
  return ref;
}

}  // namespace microdex::fem
