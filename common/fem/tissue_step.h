#pragma once
// One haptic step of the soft-tissue model: choose the mesh around the tool, assemble the
// reduced system (3.9)–(3.11) from the precomputed element matrices, solve it, and recover
// the reaction forces at the contact nodes (3.12), their resultant and torque.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <vector>

#include "common/fem/cg_solver.h"
#include "common/fem/cholmod_solver.h"
#include "common/fem/mesh_map.h"
#include "common/fem/multiscale_mesh.h"
#include "common/fem/tissue_model.h"
#include "common/fem/tool_contact.h"
#include "common/fem/tool_points.h"

namespace microdex::fem {

enum class TissueStatus : std::uint8_t {
  kOk,
  kNoContact,            // the tool does not press into the tissue: w = 0, no force
  kBadInput,             // non-finite tool coordinates; last good state kept
  kTooManyContacts,      // more contact nodes than max_contact_nodes; last good state kept
  kNotConverged,         // CG reached cg_max_iterations; last good state kept
  kFactorisationFailed,  // CHOLMOD / IC(0) / Jacobi breakdown; last good state kept
  kNonFinite,            // a NaN or Inf in the solution; last good state kept
};
const char* ToString(TissueStatus status);
inline bool IsGood(TissueStatus s) {
  return s == TissueStatus::kOk || s == TissueStatus::kNoContact;
}

// Cost and error of one step.
struct TissueStepStats {
  int unknowns = 0;       // free nodes of the reduced system
  int contact_nodes = 0;  // prescribed nodes (nearest_nodes) or tool points (penalty_points)
  int active_nodes = 0;
  int triangles = 0;
  int leaves = 0;
  int iterations = 0;                                     // CG iterations (0 for CHOLMOD)
  Preconditioner preconditioner = Preconditioner::kNone;  // the one used (pcg_dic may fall back)
  double relative_residual = 0;  // ‖b − K_ff u_f‖ / ‖b‖, recomputed after the solve
  bool pattern_reused = false;   // the selection's sparsity pattern was in the cache
  bool factor_reused = false;    // ... and its values and factor were reused unchanged
  bool mesh_mapped = false;      // the attached mesh's map is not the identity
  bool mesh_moved = false;       // ... and differs from the last step's (the nodes moved)
  bool mesh_reattached = false;  // the mesh was attached afresh while in contact
  bool force_blended = false;    // the reported force carries part of a re-attachment's step
  double select_us = 0;          // mesh selection and contact detection
  double assemble_us = 0;        // pattern (if new) and values
  double solve_us = 0;           // factorisation (if any) and solve
  double forces_us = 0;          // reactions, resultant, torque, commit
  double total_us = 0;
};

// Plain copyable state of the tissue. Arrays are sized at MakeTissueState; the step only
// writes into them. The field is kept on the last good mesh only (its vertices in the mesh's
// first-use order): nothing else of the grid is ever read again, so the state stays the size
// of the mesh (a few thousand nodes), not of the finest grid.
// A tool's planar pose: its first vertex and the direction to its second.
struct ToolPose {
  double x_m = 0;
  double y_m = 0;
  double angle_rad = 0;
};

struct TissueState {
  std::vector<std::int32_t> field_nodes;  // [max_mesh_nodes] grid nodes of the last good mesh
  std::vector<double> field_w_m;          // [max_mesh_nodes] displacement (z) at each, m
  int num_field_nodes = 0;
  std::uint32_t step = 0;    // count of good steps
  std::vector<Leaf> leaves;  // [max_leaves] mesh of the last good step (display)
  int num_leaves = 0;
  std::vector<std::int32_t> contact_nodes;  // [max_contact_nodes]
  std::vector<double> contact_force_N;      // [max_contact_nodes] tool → tissue, (3.12)
  int num_contacts = 0;
  Eigen::Vector3d f_T_S = Eigen::Vector3d::Zero();    // force of the tissue on the tool, N
  Eigen::Vector3d tau_T_S = Eigen::Vector3d::Zero();  // its torque about tool.p_ST, N·m (z = 0)
  TissueStatus status = TissueStatus::kNoContact;     // of the latest step
  std::uint32_t num_failed_steps = 0;
  // The tool's planar pose when the field was solved: the next step's (P)CG starts from the
  // field carried along with the tool's motion since. State, not cache: two states stepped
  // through one workspace each start from their own field's pose.
  ToolPose field_tool_pose;
  bool field_tool_pose_valid = false;
  // The attached mesh (TissueDef::attached_mesh): where it was attached, and the map of the
  // field's step (its nodes are in the reference plane; the map places them).
  MeshAnchor mesh_anchor;
  MeshMap field_map;
  // The force's step at a re-attachment, spread (TissueDef::reattach_blend_steps, N): the force
  // and torque reported are the solution's plus blend_left / N of these offsets (the last
  // report carried on by its last change, less the new mesh's first solution).
  Eigen::Vector3d f_change_N = Eigen::Vector3d::Zero();  // the last report's change in a step
  Eigen::Vector3d tau_change_Nm = Eigen::Vector3d::Zero();
  Eigen::Vector3d blend_f_N = Eigen::Vector3d::Zero();
  Eigen::Vector3d blend_tau_Nm = Eigen::Vector3d::Zero();
  int blend_left = 0;
};
TissueState MakeTissueState(const TissueModel& model);

// A cached sparsity pattern of K_ff (full CSR, sorted) and where each element entry goes.
struct PatternEntry {
  std::uint64_t key = 0;
  bool valid = false;
  bool values_valid = false;  // vals hold K_ff for this key (values depend only on the key)
  bool factor_valid = false;  // the CHOLMOD slot holds the numeric factor of vals
  std::uint64_t last_used = 0;
  int num_dofs = 0;
  std::vector<int> row_ptr;  // [max_mesh_nodes + 1]
  std::vector<int> cols;     // [kMaxRowEntries · max_mesh_nodes]
  std::vector<int> diag;     // [max_mesh_nodes]
  std::vector<double> vals;  // [kMaxRowEntries · max_mesh_nodes] K_ff of the mesh
  // K_ff plus the tool points' penalty (ToolConstraint::kPenaltyPoints), valid for the points
  // whose hash is tool_hash; the factor then belongs to these values.
  std::vector<double> tool_vals;  // [kMaxRowEntries · max_mesh_nodes]
  std::uint64_t tool_hash = 0;
  bool tool_vals_valid = false;
  std::uint64_t values_map_hash = 0;  // the mesh map the values were assembled on
  std::vector<int> scatter;  // [9 · max_triangles] CSR slot of element entry (a, b), or −1
  std::vector<std::int32_t> dof_order;  // [max_mesh_nodes] grid node of each unknown
};

inline constexpr int kMaxRowEntries = 16;

// Scratch of the step: buffers, pattern cache, solver state. Not copyable; one per model.
struct TissueWorkspace {
  explicit TissueWorkspace(const TissueModel& model);
  MeshSelection mesh;
  std::vector<std::int32_t> node_dof;  // [num_grid_nodes] ≥0 free dof, −1 fixed, −2−c contact c
  std::vector<std::int32_t> dof_node;        // [max_mesh_nodes]
  std::vector<std::uint64_t> order_keys;     // [max_mesh_nodes] (rank, node) sort keys
  std::vector<std::uint64_t> order_scratch;  // [max_mesh_nodes]
  std::vector<std::int32_t> tri_dof;         // [3 · max_triangles] node_dof of each vertex
  // The step's mesh map (attached mesh). When active, triangle e's matrix is
  // tri_coef[e][0] K_xx + tri_coef[e][1] K_yy of its template, or general_k[tri_general[e]]
  // for a triangle whose leaf spans a breakpoint of the map.
  MeshMap map;
  bool mapped = false;
  std::vector<std::array<double, 2>> tri_coef;  // [max_triangles]
  std::vector<std::int32_t> tri_general;        // [max_triangles] −1 or index into general_k
  std::vector<ElementMatrix> general_k;         // [max_triangles]
  std::vector<std::uint32_t> contact_stamp;     // [num_grid_nodes] == mesh.mark: contact node
  std::vector<std::int32_t> contact_nodes;      // [max_contact_nodes]
  std::vector<double> contact_w_m;              // [max_contact_nodes] prescribed displacement U
  std::vector<double> contact_f_N;              // [max_contact_nodes]
  int num_contacts = 0;
  // Penalty points of the tool (ToolConstraint::kPenaltyPoints), [max_contact_nodes / 3]: each
  // reaches three nodes, whose reactions fill contact_nodes / contact_f_N after the solve.
  std::vector<ToolPoint> tool_points;
  int num_tool_points = 0;
  bool use_tool_points = false;             // this step's tool is held by its points
  std::vector<std::int32_t> contact_index;  // [num_grid_nodes] slot in contact_nodes
  std::vector<std::int32_t> row_fill;       // [kMaxRowEntries · max_mesh_nodes] pattern scratch
  std::vector<std::int32_t> row_rank;       // [kMaxRowEntries · max_mesh_nodes] pattern scratch
  std::vector<std::int32_t> slot_twin;      // [kMaxRowEntries · max_mesh_nodes] slot of (v, u)
  std::vector<int> row_count;               // [max_mesh_nodes]
  std::vector<double> rhs, x, residual;     // [max_mesh_nodes]
  std::vector<PatternEntry> patterns;
  std::uint64_t use_clock = 0;
  std::uint64_t ic_key = 0;  // key whose IC(0)/DIC/Jacobi factor is in cg
  bool ic_valid = false;
  Preconditioner ic_kind = Preconditioner::kNone;  // which one it is
  CgWorkspace cg;
  std::unique_ptr<CholmodSolver> cholmod;
  // The state's field scattered on the grid for the warm start (a cache of the state).
  std::vector<double> grid_w_m;           // [num_grid_nodes]
  std::vector<std::uint64_t> grid_stamp;  // [num_grid_nodes] == field_stamp: grid_w_m valid
  std::uint64_t field_stamp = 0;
  // The last step's cost and solver report (wall-clock timings: telemetry, not state).
  TissueStepStats stats;
  // When false every step re-assembles the values and re-factorises even if the pattern is
  // cached (the thesis's per-step assembly); the symbolic analysis is reused either way.
  bool reuse_values = true;
};

// Reads the tool and the state's last good field (warm start); writes the state: displacement
// field, contact forces, f_T_S, tau_T_S, status; and ws.stats. On failure the state keeps the
// last good field and forces and records the status. Allocation-free after the first steps
// of each pattern (CHOLMOD analysis of a new pattern allocates inside CHOLMOD).
void StepTissue(const TissueModel& model, const ToolContact& tool, TissueWorkspace& ws,
                TissueState& state);

// Writes the state's field into `grid_w_m` ([num_grid_nodes]) at the last good mesh's nodes;
// the other entries are left as they were.
void ScatterField(const TissueState& state, std::vector<double>& grid_w_m);

// Displacement of the last good step at the nodes of a uniform grid of `level`
// (out: (2^level + 1)², row-major in y, 0 ≤ level ≤ 12), interpolated on the step's triangles.
// `grid_w_m` is scratch of num_grid_nodes entries (ScatterField); neither vector is resized
// when it has the right size already.
void CalcDisplacementGrid(const TissueModel& model, const TissueState& state, int level,
                          std::vector<double>& grid_w_m, std::vector<double>& out_m);

}  // namespace microdex::fem
