#pragma once
// The patch's compliance at a few points of its surface: the displacement along the patch's
// normal at point i per newton of load along the normal at point j (the Green's function of
// the antiplane problem, regularised by a contact radius as the point tool is). Built once, off
// the haptic thread, from one StepTissue per point: a point tool pressing the patch at point j
// to a small depth U gives the reaction R_j = U / C_jj and the field U g_j, so C_ij = g_j(p_i) /
// R_j (linear elasticity). Used where a load, not a displacement, acts on the tissue: the suture's
// pull on the stitch in the knot-tying scene. README.md, "Loads on the tissue".

#include <Eigen/Core>
#include <span>
#include <vector>

#include "common/fem/tissue_model.h"

namespace microdex::fem {

struct PointCompliance {
  // C (n × n), m/N: the normal displacement at point i per newton pulling point j out of the
  // tissue (+z of S). Symmetric up to the discretisation (Maxwell–Betti).
  Eigen::MatrixXd c_m_per_N;
  // The displacement field per newton at each point, sampled on the uniform grid of
  // `display_level` ((2^level + 1)², row-major in y, as CalcDisplacementGrid).
  int display_level = 0;
  std::vector<std::vector<double>> grid_m_per_N;
};

// points_S: (x, y) in the tissue plane, each at least contact_radius_m inside the patch.
// Throws std::invalid_argument naming the point that is outside, and std::runtime_error when
// a solve fails.
PointCompliance CalcPointCompliance(const TissueModel& model,
                                    std::span<const Eigen::Vector2d> points_S,
                                    double contact_radius_m, int display_level);

// Bilinear interpolation of a uniform grid of `level` over the patch at (x, y) (clamped to it).
double SampleGrid(const TissueModel& model, std::span<const double> grid_m, int level, double x_m,
                  double y_m);

}  // namespace microdex::fem
