#include "common/fem/element_stiffness.h"

#include <gtest/gtest.h>

#include <cmath>

#include "common/fem/tissue_model.h"

namespace microdex::fem {
namespace {

constexpr double kMatrixTol_N_per_m = 1e-12;

// Laplacian P1 element by the cotangent formula: K_ij = −(G t / 2) cot θ_k for the angle θ_k
// opposite edge ij, K_ii = −Σ_j K_ij. An independent derivation of the same matrix.
ElementMatrix CotangentMatrix(const std::array<double, 3>& x, const std::array<double, 3>& y,
                              double gt) {
  ElementMatrix k{};
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, o = (i + 2) % 3;
    const double ux = x[i] - x[o], uy = y[i] - y[o], vx = x[j] - x[o], vy = y[j] - y[o];
    const double cot = (ux * vx + uy * vy) / std::abs(ux * vy - uy * vx);
    k[3 * i + j] = k[3 * j + i] = -0.5 * gt * cot;
  }
  for (int i = 0; i < 3; ++i) k[4 * i] = -(k[3 * i + (i + 1) % 3] + k[3 * i + (i + 2) % 3]);
  return k;
}

TEST(ElementStiffness, MatchesCotangentFormula) {
  const std::array<double, 3> x = {0.01, 0.05, 0.02}, y = {0.0, 0.013, 0.04};
  ElementMatrix k;
  ASSERT_TRUE(CalcElementMatrix(x, y, 3e3, 0.02, k));
  const ElementMatrix ref = CotangentMatrix(x, y, 3e3 * 0.02);
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(k[i], ref[i], kMatrixTol_N_per_m);
}

TEST(ElementStiffness, RejectsDegenerateAndClockwise) {
  ElementMatrix k;
  EXPECT_FALSE(CalcElementMatrix({0, 1, 2}, {0, 1, 2}, 1, 1, k));
  EXPECT_FALSE(CalcElementMatrix({0, 0, 1}, {0, 1, 0}, 1, 1, k));
}

// Every template of every level is a right isosceles triangle on a square grid; the Laplacian
// element matrix is scale-invariant in 2-D, so all levels share the same entries:
// G t · [[1, −½, −½], [−½, ½, 0], [−½, 0, ½]] with the right angle first.
TEST(ElementStiffness, LevelTablesAreScaleInvariantOnSquareCells) {
  TissueDef def;
  def.max_level = 6;
  def.level = 4;
  const TissueModel model = BuildTissueModel(def);
  const double gt = def.shear_modulus_Pa * def.thickness_m;
  for (int level = 0; level <= def.max_level; ++level) {
    for (int shape = 0; shape < kNumShapes; ++shape) {
      const ElementMatrix& k = model.element_matrices[level][shape];
      double sum_diag = 0;
      for (int i = 0; i < 3; ++i) {
        double row = 0;
        for (int j = 0; j < 3; ++j) row += k[3 * i + j];
        EXPECT_NEAR(row, 0.0, kMatrixTol_N_per_m);  // constants have no energy
        sum_diag += k[4 * i];
      }
      EXPECT_NEAR(sum_diag, 2 * gt, 1e-9 * gt) << "level " << level << " shape " << shape;
      EXPECT_TRUE(model.element_matrices[level][shape] == model.element_matrices[0][shape] ||
                  std::abs(k[0] - model.element_matrices[0][shape][0]) < 1e-9 * gt);
    }
  }
}

}  // namespace
}  // namespace microdex::fem
