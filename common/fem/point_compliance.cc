#include "common/fem/point_compliance.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/fem/tissue_step.h"
#include "common/fem/tool_contact.h"

namespace microdex::fem {

namespace {

// The depth each point is pressed to (the problem is linear: any depth gives the same C).
constexpr double kProbeDepth_m = 1e-4;
// The grid the other points' displacements are read from (the model's finest up to this).
constexpr int kMaxSampleLevel = 8;

}  // namespace

double SampleGrid(const TissueModel& model, std::span<const double> grid_m, int level, double x_m,
                  double y_m) {
  const int cells = 1 << level;
  const double u = std::clamp(x_m / model.CellSizeX_m(level), 0.0, static_cast<double>(cells));
  const double v = std::clamp(y_m / model.CellSizeY_m(level), 0.0, static_cast<double>(cells));
  const int i = std::min(static_cast<int>(u), cells - 1);
  const int j = std::min(static_cast<int>(v), cells - 1);
  const double a = u - i, b = v - j;
  const auto at = [&](int ii, int jj) {
    return grid_m[static_cast<std::size_t>(jj) * (cells + 1) + static_cast<std::size_t>(ii)];
  };
  return (1 - a) * (1 - b) * at(i, j) + a * (1 - b) * at(i + 1, j) + (1 - a) * b * at(i, j + 1) +
         a * b * at(i + 1, j + 1);
}

PointCompliance CalcPointCompliance(const TissueModel& model,
                                    std::span<const Eigen::Vector2d> points_S,
                                    double contact_radius_m, int display_level) {
  const auto n = static_cast<int>(points_S.size());
  for (int j = 0; j < n; ++j) {
    const Eigen::Vector2d& p = points_S[static_cast<std::size_t>(j)];
    if (!(p.x() >= contact_radius_m && p.x() <= model.def.length_x_m - contact_radius_m &&
          p.y() >= contact_radius_m && p.y() <= model.def.length_y_m - contact_radius_m)) {
      throw std::invalid_argument("point " + std::to_string(j) + " (" + std::to_string(p.x()) +
                                  ", " + std::to_string(p.y()) +
                                  " m): expected inside the patch by the contact radius");
    }
  }
  PointCompliance out;
  out.c_m_per_N.setZero(n, n);
  out.display_level = display_level;
  const int sample_level = std::min(model.def.max_level, kMaxSampleLevel);
  TissueWorkspace ws(model);
  std::vector<double> scratch, sampled;
  for (int j = 0; j < n; ++j) {
    const Eigen::Vector2d& p = points_S[static_cast<std::size_t>(j)];
    TissueState state = MakeTissueState(model);
    StepTissue(model,
               MakePointTool(Eigen::Vector3d(p.x(), p.y(), -kProbeDepth_m), contact_radius_m), ws,
               state);
    const double reaction_N = state.f_T_S.z();  // the tissue pushes the tool out
    if (state.status != TissueStatus::kOk || !(reaction_N > 0)) {
      throw std::runtime_error("point " + std::to_string(j) +
                               ": the tissue's solve failed: " + ToString(state.status));
    }
    // Per newton pulling out of the tissue: the field of the press divided by -R.
    CalcDisplacementGrid(model, state, sample_level, scratch, sampled);
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d& q = points_S[static_cast<std::size_t>(i)];
      out.c_m_per_N(i, j) =
          i == j ? kProbeDepth_m / reaction_N
                 : -SampleGrid(model, sampled, sample_level, q.x(), q.y()) / reaction_N;
    }
    std::vector<double> grid;
    CalcDisplacementGrid(model, state, display_level, scratch, grid);
    for (double& w : grid) w /= -reaction_N;
    out.grid_m_per_N.push_back(std::move(grid));
  }
  return out;
}

}  // namespace microdex::fem
