#pragma once
// The patch's in-plane (membrane) compliance at a few points: the displacement in the patch's
// plane at point i per newton of in-plane load at point j. The antiplane problem of chapter 3
// moves the patch only along its normal; a suture's pull along the surface (the legs of a knot
// drawing its punctures together) is this second, independent problem of linear elasticity:
// plane stress in the same Lx × Ly patch of thickness t with fixed edges, shear modulus G and
// Poisson's ratio ν (TissueDef::poisson_ratio), on the uniform grid of one level (each cell
// split into two linear triangles, the diagonals alternating cell by cell: the mesh is
// symmetric about the grid lines through even nodes).
//
// A point's load acts as the antiplane point tool does: on a rigid disc of the contact radius
// (the grid nodes within it move together). With every disc's nodes prescribed, translating
// disc j by u (the others held) gives the discs' reactions, a column of their stiffness S
// (2n × 2n, symmetric); the points' compliance is C = S⁻¹: the discs' displacements per newton
// of load, each disc free. One CHOLMOD factorisation, 2n solves; built once, off the haptic
// thread.
// README.md, "In-plane loads".

#include <Eigen/Core>
#include <limits>
#include <span>

#include "common/fem/tissue_def.h"

namespace microdex::fem {

// A rigid disc translated in the patch's plane, and the plane-stress field around it.
struct RigidDiscSolution {
  int level = 0;               // the grid: 2^level cells a side, (2^level + 1)² nodes
  int disc_nodes = 0;          // grid nodes inside the disc (at least the nearest one)
  Eigen::Vector2d reaction_N;  // the force the disc needs for its displacement (S u)
  Eigen::VectorXd u_m;         // nodal (x, y) displacements, node J·(2^level + 1) + I
  Eigen::Vector2d SampleAt(double x_m, double y_m, const TissueDef& def) const;
};

// Translates the disc of `radius_m` around `centre_S` by `u_m`, every node at least
// `clamp_radius_m` from the centre held fixed besides the patch's edges (infinite: the edges
// only; the analytic tests' clamped annulus). Throws std::runtime_error if CHOLMOD fails.
RigidDiscSolution SolveRigidDisc(const TissueDef& def, int level, const Eigen::Vector2d& centre_S,
                                 double radius_m, const Eigen::Vector2d& u_m,
                                 double clamp_radius_m = std::numeric_limits<double>::infinity());

// The analytic reference: a rigid disc of radius a in a plane-stress annulus clamped at R,
// translated by a force F (N) over thickness t. With κ = (3 − ν)/(1 + ν),
//   u / F = (1 + ν) / (8π G t) · [κ ln(R/a) − (R² − a²) / (κ (R² + a²))]
// (Muskhelishvili's potentials φ = α ln z + σ z², ψ = −κ α ln z + η / z²; README.md).
double RigidDiscInAnnulusCompliance_m_per_N(double shear_modulus_Pa, double poisson_ratio,
                                            double thickness_m, double a_m, double r_m);

struct InPlaneCompliance {
  int level = 0;
  // 2n × 2n, m/N: rows and columns (x₀, y₀, x₁, y₁, …) in the patch's frame S. Symmetric
  // (Maxwell–Betti) and positive definite.
  Eigen::MatrixXd c_m_per_N;
};

// points_S: (x, y) in the tissue plane, each at least contact_radius_m inside the patch.
// Throws std::invalid_argument naming the point that is outside, std::runtime_error when a
// solve fails.
InPlaneCompliance CalcInPlaneCompliance(const TissueDef& def, int level,
                                        std::span<const Eigen::Vector2d> points_S,
                                        double contact_radius_m);

}  // namespace microdex::fem
