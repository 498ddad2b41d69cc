#include "common/fem/element_stiffness.h"

#include <cmath>

namespace microdex::fem {

// Corners BL(0,0) BR(2,0) TR(2,2) TL(0,2), centre C(1,1), side midpoints (1,0) (2,1) (1,2)
// (0,1); every triangle counter-clockwise.
const std::array<std::array<TemplateVertex, 3>, kNumShapes> kTemplateTriangles = {{
    {{{0, 0}, {2, 0}, {2, 2}}},  // lower half
    {{{0, 0}, {2, 2}, {0, 2}}},  // upper half
    {{{1, 1}, {0, 0}, {2, 0}}},  // fan, bottom side
    {{{1, 1}, {2, 0}, {2, 2}}},  // fan, right side
    {{{1, 1}, {2, 2}, {0, 2}}},  // fan, top side
    {{{1, 1}, {0, 2}, {0, 0}}},  // fan, left side
    {{{1, 1}, {0, 0}, {1, 0}}},  // bottom, first half
    {{{1, 1}, {1, 0}, {2, 0}}},  // bottom, second half
    {{{1, 1}, {2, 0}, {2, 1}}},  // right
    {{{1, 1}, {2, 1}, {2, 2}}},
    {{{1, 1}, {2, 2}, {1, 2}}},  // top
    {{{1, 1}, {1, 2}, {0, 2}}},
    {{{1, 1}, {0, 2}, {0, 1}}},  // left
    {{{1, 1}, {0, 1}, {0, 0}}},
}};

bool CalcElementMatrix(const std::array<double, 3>& x_m, const std::array<double, 3>& y_m,
                       double shear_modulus_Pa, double thickness_m, ElementMatrix& k_N_per_m) {
  ElementMatrix k_xx{}, k_yy{};
  if (!CalcElementMatrixParts(x_m, y_m, shear_modulus_Pa, thickness_m, k_xx, k_yy)) return false;
  for (int ij = 0; ij < 9; ++ij) k_N_per_m[ij] = k_xx[ij] + k_yy[ij];
  return true;
}

bool CalcElementMatrixParts(const std::array<double, 3>& x_m, const std::array<double, 3>& y_m,
                            double shear_modulus_Pa, double thickness_m, ElementMatrix& k_xx,
                            ElementMatrix& k_yy) {
  std::array<double, 3> b{}, c{};
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    b[i] = y_m[j] - y_m[k];
    c[i] = x_m[k] - x_m[j];
  }
  const double twice_area_m2 = x_m[0] * b[0] + x_m[1] * b[1] + x_m[2] * b[2];
  if (!(twice_area_m2 > 0)) return false;
  const double scale = shear_modulus_Pa * thickness_m / (2.0 * twice_area_m2);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      k_xx[3 * i + j] = scale * b[i] * b[j];
      k_yy[3 * i + j] = scale * c[i] * c[j];
    }
  }
  return true;
}

}  // namespace microdex::fem
