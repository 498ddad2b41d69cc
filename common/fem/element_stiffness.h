#pragma once
// Element stiffness of the linear triangle (3.4) for the antiplane problem (3.1), and the
// table of template triangles a quadtree cell is cut into.

#include <array>

namespace microdex::fem {

// 3×3 row-major element matrix in N/m.
using ElementMatrix = std::array<double, 9>;

// K_ij = G·t·(b_i b_j + c_i c_j) / (4A), the weak form (3.5) with w = Σ N⁽ⁱ⁾ w⁽ⁱ⁾ (3.4).
// Vertices (x_m, y_m) in counter-clockwise order; returns false for a degenerate triangle.
bool CalcElementMatrix(const std::array<double, 3>& x_m, const std::array<double, 3>& y_m,
                       double shear_modulus_Pa, double thickness_m, ElementMatrix& k_N_per_m);

// The two parts of that matrix, K = K_xx + K_yy: G·t·b_i b_j / (4A) (the x-derivatives) and
// G·t·c_i c_j / (4A). Scaling x by s_x and y by s_y gives (s_y / s_x) K_xx + (s_x / s_y) K_yy.
bool CalcElementMatrixParts(const std::array<double, 3>& x_m, const std::array<double, 3>& y_m,
                            double shear_modulus_Pa, double thickness_m, ElementMatrix& k_xx,
                            ElementMatrix& k_yy);

// Template triangles of a cell, vertices in half-cell units from the cell's lower-left corner
// (u, v ∈ {0, 1, 2}). Shapes 0–1: the two halves of an unrefined cell (diagonal BL–TR).
// Shapes 2–5: fan triangle (centre, side start, side end) for sides bottom, right, top, left.
// Shapes 6–13: half-side fan triangles (centre, start, mid) and (centre, mid, end) where the
// neighbour across that side is refined, so that the side's midpoint is a vertex (conforming).
inline constexpr int kNumShapes = 14;
inline constexpr int kShapeLower = 0;
inline constexpr int kShapeUpper = 1;
inline constexpr int kShapeFanFull = 2;  // + side
inline constexpr int kShapeFanHalf = 6;  // + 2·side + half
struct TemplateVertex {
  int u;
  int v;
};
extern const std::array<std::array<TemplateVertex, 3>, kNumShapes> kTemplateTriangles;

}  // namespace microdex::fem
