#include "common/fem/point_compliance.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "common/fem/navier.h"
#include "common/fem/tissue_step.h"

namespace microdex::fem {
namespace {

// The knot-tying scene's patch (assets/scenes/tissue_skin_patch.yaml) and stitch: 2 x 2 cm,
// G 20 kPa, 2 mm; the punctures 2.5 mm either side of the bite, on the patch's middle line.
TissueDef SkinPatch(int level, double g_Pa = 2e4) {
  TissueDef def;
  def.length_x_m = 0.02;
  def.length_y_m = 0.02;
  def.shear_modulus_Pa = g_Pa;
  def.thickness_m = 0.002;
  def.max_level = 9;
  def.level = level;
  def.solver = SolverKind::kPcgDic;
  return def;
}
const std::vector<Eigen::Vector2d> kStitch = {{7.5e-3, 10e-3}, {10e-3, 10e-3}, {12.5e-3, 10e-3}};
constexpr double kRadius_m = 0.3e-3;

// The Green's function of the rectangle, per newton (fem::NavierPointLoadDisplacement_m_per_N:
// the series shares nothing with the FEM but the equation).
double Green_m_per_N(const TissueDef& d, double x, double y, double xi, double eta) {
  NavierDomain domain;
  domain.length_x_m = d.length_x_m;
  domain.length_y_m = d.length_y_m;
  domain.shear_modulus_Pa = d.shear_modulus_Pa;
  domain.thickness_m = d.thickness_m;
  return NavierPointLoadDisplacement_m_per_N(domain, xi, eta, x, y);
}

// The point load's series (summed over n, in closed form over m) against the line load's (in
// closed form over n, summed over m) for a line 1 um long carrying 1 N: the two expansions run
// in crossed directions.
TEST(NavierPointLoad, IsTheLimitOfAShortLineLoadSummedTheOtherWay) {
  NavierDomain d;
  d.length_x_m = 0.02;
  d.length_y_m = 0.03;
  d.shear_modulus_Pa = 2e4;
  d.thickness_m = 0.002;
  const double eps = 1e-6;
  UniformLineLoad load{7e-3 - eps / 2, 7e-3 + eps / 2, 11e-3, 1.0 / eps};
  for (const Eigen::Vector2d& p : {Eigen::Vector2d(9.5e-3, 11e-3), Eigen::Vector2d(7.3e-3, 14e-3),
                                   Eigen::Vector2d(15e-3, 2e-3)}) {
    const double point = NavierPointLoadDisplacement_m_per_N(d, 7e-3, 11e-3, p.x(), p.y());
    const double line = NavierLineLoadDisplacement_m(d, load, p.x(), p.y());
    EXPECT_NEAR(point / line, 1.0, 1e-6) << p.transpose() << ": " << point << " " << line;
    // Reciprocity of the exact Green's function.
    EXPECT_NEAR(NavierPointLoadDisplacement_m_per_N(d, p.x(), p.y(), 7e-3, 11e-3) / point, 1.0,
                1e-9);
  }
}

TEST(PointCompliance, OffTheLoadItIsTheSeriesGreensFunction) {
  for (const int level : {6, 7}) {
    const TissueDef def = SkinPatch(level);
    const TissueModel model = BuildTissueModel(def);
    const PointCompliance pc = CalcPointCompliance(model, kStitch, kRadius_m, 6);
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        if (i == j) continue;
        const double ref =
            Green_m_per_N(def, kStitch[i].x(), kStitch[i].y(), kStitch[j].x(), kStitch[j].y());
        // The disc's far field is a point load's up to (a / r)^2 ~ 1.4 %, plus the mesh's error.
        EXPECT_NEAR(pc.c_m_per_N(i, j) / ref, 1.0, 0.04)
            << "level " << level << " C(" << i << ", " << j << ") " << pc.c_m_per_N(i, j)
            << " against " << ref;
        // Maxwell-Betti: the FEM's C is symmetric up to its discretisation.
        EXPECT_NEAR(pc.c_m_per_N(i, j) / pc.c_m_per_N(j, i), 1.0, 0.02) << level;
      }
    }
  }
}

TEST(PointCompliance, UnderTheContactDiscItIsTheGreensFunctionOnItsRim) {
  // A disc held at one displacement is a circle of equal potential: in the plane its field is
  // a point load's, whose value on the rim is the disc's (the edges' images change it by
  // (a / L)^2). The mesh must resolve the disc: level 8 puts 4 cells across its radius.
  const TissueDef def = SkinPatch(8);
  const TissueModel model = BuildTissueModel(def);
  const PointCompliance pc = CalcPointCompliance(model, kStitch, kRadius_m, 6);
  for (int j = 0; j < 3; ++j) {
    const double ref = Green_m_per_N(def, kStitch[j].x() + kRadius_m, kStitch[j].y(),
                                     kStitch[j].x(), kStitch[j].y());
    EXPECT_NEAR(pc.c_m_per_N(j, j) / ref, 1.0, 0.06) << j << ": " << pc.c_m_per_N(j, j);
    // The displayed field per newton has that displacement at its point.
    EXPECT_NEAR(SampleGrid(model, pc.grid_m_per_N[j], 6, kStitch[j].x(), kStitch[j].y()) /
                    pc.c_m_per_N(j, j),
                1.0, 0.02)
        << j;
  }
}

TEST(PointCompliance, ScalesAsOneOverTheModulusFromVerySoftToVeryStiff) {
  // Soft fat to cartilage and beyond: the solve is linear in 1 / G, to the solver's tolerance.
  const TissueModel base = BuildTissueModel(SkinPatch(6));
  const Eigen::MatrixXd c0 = CalcPointCompliance(base, kStitch, kRadius_m, 4).c_m_per_N;
  for (const double g_Pa : {1e2, 1e3, 1e5, 1e6, 1e8}) {
    const TissueModel model = BuildTissueModel(SkinPatch(6, g_Pa));
    const Eigen::MatrixXd c = CalcPointCompliance(model, kStitch, kRadius_m, 4).c_m_per_N;
    EXPECT_TRUE(c.allFinite()) << g_Pa;
    EXPECT_LT((c * g_Pa - c0 * 2e4).norm() / (c0 * 2e4).norm(), 1e-6) << g_Pa;
  }
}

TEST(PointCompliance, APointOffThePatchIsNamed) {
  const TissueModel model = BuildTissueModel(SkinPatch(6));
  const std::vector<Eigen::Vector2d> points = {{10e-3, 10e-3}, {19.9e-3, 10e-3}};
  try {
    CalcPointCompliance(model, points, kRadius_m, 4);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("point 1"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace microdex::fem
