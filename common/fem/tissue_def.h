#pragma once
// Description of a soft-tissue patch: the antiplane (out-of-plane) elasticity problem of
// thesis chapter 3 on an Lx × Ly rectangle with fixed edges, discretised on a hierarchy of
// nested uniform grids. SI units throughout; the thesis's cm and N/cm² are converted at the
// boundary with the constants below.

#include <cstdint>
#include <string>

namespace microdex::fem {

inline constexpr double kMetrePerCm = 0.01;
inline constexpr double kPascalPerNewtonPerCm2 = 1e4;  // 1 N/cm² = 1e4 N/m²

enum class MeshKind : std::uint8_t {
  kFine,        // every cell at the run's level (the thesis's "fine mesh")
  kMultiscale,  // fine cells near the tool, coarser further away (figures 3.1–3.2)
};

enum class SolverKind : std::uint8_t {
  kCg,         // the thesis's conjugate gradient: no preconditioner, cold start
  kPcgJacobi,  // diagonal preconditioner, warm-started from the previous step
  kPcgIc,      // incomplete Cholesky IC(0) preconditioner, warm-started
  // diagonal incomplete Cholesky, CG through Eisenstat's trick (no product with K per
  // iteration), warm-started; falls back to IC(0) on a pattern whose DIC breaks down
  kPcgDic,
  kCholmod,  // sparse direct LDLᵀ (SuiteSparse CHOLMOD), symbolic analysis cached
};

// Fill-reducing ordering of the free unknowns for CHOLMOD.
enum class Ordering : std::uint8_t {
  // Geometric nested dissection of the finest grid, ranked once at model build; the step only
  // sorts its free nodes by rank and CHOLMOD keeps that order (no ordering work per pattern).
  kNestedDissection,
  kAmd,  // CHOLMOD's AMD on every new pattern (the reference)
};

// How the tool's prescribed displacement enters the system.
enum class ToolConstraint : std::uint8_t {
  // Penalty springs at points attached to the tool, through the shape functions of the
  // triangles that hold them (tool_points.h): the force is a continuous function of the pose.
  kPenaltyPoints,
  // The thesis's (3.7): the nearest grid nodes of the tool are prescribed (the tool snaps to
  // the grid; the reaction moves in steps as it slides). Kept as the reference of the study.
  kNearestNodes,
};

const char* ToString(MeshKind kind);
const char* ToString(SolverKind kind);
const char* ToString(Ordering ordering);
const char* ToString(ToolConstraint constraint);
// Parses "fine"/"multiscale", "cg"/"pcg_jacobi"/"pcg_ic"/"pcg_dic"/"cholmod" and
// "nested_dissection"/"amd"; throws std::invalid_argument naming the text otherwise.
MeshKind ParseMeshKind(const std::string& text);
SolverKind ParseSolverKind(const std::string& text);
Ordering ParseOrdering(const std::string& text);
// "penalty_points" / "nearest_nodes".
ToolConstraint ParseToolConstraint(const std::string& text);

struct TissueDef {
  double length_x_m = 0.20;  // domain [0, Lx] × [0, Ly] in the tissue frame S
  double length_y_m = 0.20;
  double shear_modulus_Pa = 1.0e4;  // G; the thesis's 1 N/cm²
  // Thickness of the slab. The 2-D problem's stiffness is G·t ∫∇Nᵢ·∇Nⱼ dA, so forces come
  // out in newtons; 1 cm makes the thesis's study (G in N/cm², w in cm) read in newtons.
  double thickness_m = 0.01;
  // Poisson's ratio of the in-plane (plane-stress) problem only (in_plane_compliance.h): the
  // antiplane problem has none. Soft tissues are nearly incompressible: 0.45-0.5.
  double poisson_ratio = 0.45;
  int max_level = 9;  // finest level of the hierarchy: level l has 2^l × 2^l cells
  // Level of the step's mesh: every cell the tool touches is at this level (kFine: every
  // cell; the multi-scale mesh goes finer only in the end zones, see end_resolution).
  int level = 7;
  MeshKind mesh = MeshKind::kMultiscale;
  // A level-l cell is refined when (distance to the tool − contact radius) < grading · h_l.
  // grading ≥ 1.5 keeps neighbouring leaves within one level of each other (see README).
  double grading = 2.0;
  // Multi-scale mesh only, "end grading": around every pressed vertex of a bar or polyline
  // tool, where the prescribed displacement ends and w ~ r^½, the mesh goes on to the end
  // level: the first level whose cells are no larger than (tool length) / end_resolution,
  // at most end_levels beyond `level` and at most max_level (no effect when it is not finer
  // than `level`). The force error of
  // the end singularity is O(h_end / length), so this fixes it relative to the tool. A cell
  // at level l ∈ [level, end level) is refined when its distance to such a vertex is below
  // grading · h_l. Not applied to a point tool nor to a tool with contact_radius_m > 0 (its
  // ends are rounded). 0 disables.
  double end_resolution = 64;
  int end_levels = 2;
  // Multi-scale mesh with penalty points only, "edge grading": where the tool runs within
  // edge_resolution · h_l of a clamped edge, the level-l cells within grading · h_l of that part
  // of the tool are refined (l from `level` on, at most edge_levels beyond it and up to
  // max_level), so the strip between the tool and the edge, where w falls from U to 0, is at
  // least about edge_resolution cells wide. 0 disables. edge_max_leaves bounds the leaves the
  // rule may add (the model's capacity): a level whose refinement would exceed it is skipped.
  double edge_resolution = 3;
  int edge_levels = 3;
  int edge_max_leaves = 6144;
  // Bars and polylines of zero contact radius; a point tool and a tool with a contact radius
  // are always held at their nodes (kNearestNodes).
  ToolConstraint tool_constraint = ToolConstraint::kPenaltyPoints;
  // Each tool point's spring is the one consistent with the kink of the field across the tool
  // line (tool_points.h: 2 G t · share / Σ λ|d|) times tool_kink_factor, capped at
  // tool_penalty · G t (N/m) where the line runs on the mesh's edges. The factor was measured
  // (README, "Tool constraint"): 1 (the 1-D model) leaves the force of a centred bar 1.2 %
  // lower mid-cell than on a grid line; 1.2 keeps random bars within 0.5–1.5 % of Navier at
  // levels 5–8 (1.6 flattens the centred bar but short bars by an edge err 4 %).
  double tool_kink_factor = 1.2;
  double tool_penalty = 1e3;
  // Tool points per cell along the tool: spacing in units of the local cell size (nominal
  // level; end level in the end zones). 1 constrains about one value per cell column, as
  // many as the mesh has beside the line; denser points lock the mesh (README).
  double tool_point_spacing = 1.0;
  // The default is the one a station can run: CHOLMOD's analysis and factorisation allocate
  // whenever the mesh selection changes (almost every tick under a moving tool), IC(0) CG
  // allocates nothing. Benches and reference studies choose cholmod explicitly.
  SolverKind solver = SolverKind::kPcgDic;
  Ordering ordering = Ordering::kNestedDissection;
  double cg_relative_tolerance = 1e-8;  // ‖b − K u‖ / ‖b‖ at which CG stops
  // pcg_dic: the DIC pivots scaled by this factor (1: plain DIC). Measured on the moving bar
  // (common/fem/README.md): 0.8 takes 19 / 20 iterations at levels 7 / 8 against 24 / 26.
  double dic_relaxation = 0.8;
  int cg_max_iterations = 20000;
  // The mesh attached to the tissue under the tool (mesh_map.h): while the tool presses, its
  // planar translation since contact began moves the mesh's nodes instead of the tool over
  // the grid, so the force is a smooth function of the motion (README, "Attached mesh").
  bool attached_mesh = true;
  // Attaching the mesh afresh changes the discretisation, and the force steps by the change of
  // its error (a few 1e-3 of F at most, README "Attached mesh"). The step is spread over this
  // many steps (0.1 s at 1 kHz): the reported force goes on from the last report and reaches
  // the new mesh's solution linearly. 0: not spread.
  int reattach_blend_steps = 100;
  int max_contact_nodes = 4096;   // capacity of the contact list (pre-sized)
  int pattern_cache_entries = 2;  // sparsity patterns (and CHOLMOD analyses) kept
  // Throws std::invalid_argument for the first bad field, whose message starts with the field
  // name followed by ': ' (e.g. `shear_modulus_Pa: expected a positive modulus in Pa`).
  void Validate() const;
};

// Reads a tissue parameter file (assets/scenes/tissue_*.yaml: a map `tissue:` whose keys are
// the TissueDef fields, SI units; absent keys keep their defaults) and validates it. Throws
// microdex::InputError "FILE:LINE: tissue.FIELD: reason" (common/base/input_error.h).
TissueDef LoadTissueDef(const std::string& path);

}  // namespace microdex::fem
