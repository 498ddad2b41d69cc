#pragma once
// microdex-bench fem, the tool contact part: the resultant of bars at random positions against
// the Navier reference, tilted bars and a polyline against a Richardson reference, and the
// continuity of the force under a moving tool (translation at 20 mm/s, rotation at 1 rad/s,
// stepped at 1 kHz), each for the penalty-point constraint and the nearest-node one.

#include <string>

namespace microdex::fem {

struct ContactReportOptions {
  int max_level = 8;     // multi-scale levels 5..max_level
  bool quick = false;    // fewer positions, no fine-mesh reference
  std::string plot_dir;  // the continuity force trace (PNG via gnuplot) when not empty
};

// JSON values (no trailing comma) for the report's keys.
struct ContactReport {
  std::string off_grid;    // [{case, level, x1_m, x2_m, y1_m, resultant_force_error, ...}]
  std::string tilted;      // [{case, level, resultant_force_error, reference_N, ...}]
  std::string continuity;  // {max_jump_over_reference, positions_tested, ...}
  bool off_grid_within_2pct = false;
  bool continuity_met = false;
};

ContactReport RunContactReport(const ContactReportOptions& options);

}  // namespace microdex::fem
