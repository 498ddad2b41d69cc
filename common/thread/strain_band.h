#pragma once
// Direct projection of the thread's link lengths into the strain band (Deul, Kugelstadt,
// Weiler & Bender 2018, "Direct position-based solver for stiff rods", here for the length
// constraints only). The length constraints C_j = |x_{j+1} - x_j| - l_j of a chain couple only
// neighbouring links, so the linearised projection (J W J^T) lambda = -C, dx = W J^T lambda
// (W the inverse node masses, 0 for grasped nodes) is a tridiagonal system in the links,
// solved exactly in O(n) per Newton iteration. A Gauss-Seidel sweep moves a length error one
// link per sweep; the direct solve corrects all held links together (where a taut chain has no
// slack, the held set still grows by one link per side and iteration).

#include <Eigen/Core>

namespace microdex::thread {

struct ThreadModel;

// Pre-sized scratch of ProjectStrainBand (num_links entries each).
struct StrainBandScratch {
  Eigen::Matrix3Xd e;         // unit link directions
  Eigen::VectorXd c;          // constraint value: l - band edge outside the band, else 0
  Eigen::VectorXd diag;       // J W J^T, diagonal
  Eigen::VectorXd off;        // J W J^T, (j, j + 1)
  Eigen::VectorXd lambda;     // solution
  Eigen::VectorXd work;       // Thomas algorithm
  Eigen::VectorXi active;     // 0 free, +1 / -1 held (from above / below the band)
  Eigen::Matrix3Xd dx;        // a Newton step's node moves (num_links + 1 columns)
  Eigen::VectorXd violation;  // per link: violation of the band / rest length (0 inside)
  Eigen::VectorXi nodes;      // the nodes a Newton step moves (num_links + 1)
  Eigen::VectorXi window;     // the links touching them
  Eigen::VectorXi in_window;  // per link: 1 while listed in window (cleared after use)
  Eigen::VectorXi listed;     // the links held or outside the band at some iteration, ascending
  Eigen::VectorXi merged;     // listed merged with a window
  // Tracking across calls on the same chain (false: every call classifies every link). While
  // tracking, a call starts from the last call's classification, valid when num_listed >= 0:
  // it classifies again only the links listed then and the links touching the nodes moved
  // since, which the caller reports with MarkMoved. Each call lists the nodes it moved
  // (moved[0..num_moved), ascending by first move) with their positions before it
  // (x_before); the caller reads and clears them with ClearMoved.
  bool tracking = false;
  int num_listed = -1;
  Eigen::VectorXi dirty;  // nodes moved by the caller since the last call
  int num_dirty = 0;
  Eigen::VectorXi dirty_flag;  // per node: 1 while listed in dirty
  Eigen::VectorXi moved;       // nodes the last call moved
  int num_moved = 0;
  Eigen::VectorXi moved_flag;  // per node: 1 while listed in moved
  Eigen::Matrix3Xd x_before;   // per listed moved node: its position before the call

  // Starts tracking a chain whose positions may have changed anywhere (the next call classifies
  // every link).
  void StartTracking();
  void MarkMoved(int node) {
    if (dirty_flag[node] != 0) return;
    dirty_flag[node] = 1;
    dirty[num_dirty++] = node;
  }
  void ClearMoved();
};
StrainBandScratch MakeStrainBandScratch(int num_links);

struct StrainBandResult {
  double max_violation_m = 0.0;  // largest |l - band| before the projection
  int iterations = 0;            // Newton iterations run (each one tridiagonal solve)
  int corrected_links = 0;       // links outside the band (beyond the tolerance) before it
};

// Projects x's link lengths into [1 - limit, 1 + limit] rest lengths. Newton iterations of
// the tridiagonal solve over an active set: links outside the band are pulled to its nearer
// edge, links pulled in an earlier iteration are held at their current length (they need not
// stay at the edge) unless their multiplier would push them further into the band, the other
// links are free. Each step is at most half the shortest rest length per node and is halved
// (up to 4 times) until the largest violation decreases; stops when every link is within 1e-4
// of its rest length of the band, after max_iterations, or when no step helps. Nodes with
// inverse_mass 0 (grasped) do not move; the moves are mass-weighted, so the centre of mass of
// a free chain stays. No allocation.
StrainBandResult ProjectStrainBand(const ThreadModel& model, const Eigen::VectorXd& inverse_mass,
                                   double limit, int max_iterations, Eigen::Matrix3Xd& x,
                                   StrainBandScratch& s);

}  // namespace microdex::thread
