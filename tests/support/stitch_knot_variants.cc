#include "tests/support/stitch_knot_variants.h"

#include <Eigen/Geometry>
#include <cstdio>
#include <numbers>
#include <random>
#include <stdexcept>

namespace microdex::knot::variants {

std::vector<StitchVariant> RandomStitchVariants(StitchKnotType kind, int count, std::uint64_t seed,
                                                double noise_diameters,
                                                double node_spacing_diameters) {
  constexpr double kPi = std::numbers::pi;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto between = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };
  std::vector<StitchVariant> out;
  int attempts = 0;
  while (static_cast<int>(out.size()) < count) {
    if (++attempts > 100 * count) {
      throw std::runtime_error("RandomStitchVariants: too many rejected parameter draws");
    }
    StitchKnotShapeDef def;
    def.kind = kind;
    def.thread_diameter_m = between(2e-5, 2e-4);
    const double d = def.thread_diameter_m;
    def.node_spacing_m = node_spacing_diameters * d;
    def.stitch_width_m = between(8.0, 30.0) * d;
    def.stitch_depth_m = between(1.0, 15.0) * d;
    def.tightness = between(0.0, 1.0);
    def.tail_length_m = between(5.0, 120.0) * d;
    // Tails pulled apart along the stitch, across it, or anywhere.
    const double spread = unit(rng) < 0.5 ? 0.6 : kPi;
    def.tail_first_azimuth_rad = kPi + between(-spread, spread);
    def.tail_last_azimuth_rad = between(-spread, spread);
    def.tail_first_elevation_rad = between(0.0, 1.3);
    def.tail_last_elevation_rad = between(0.0, 1.3);
    def.axis_tilt_rad = between(0.0, 1.1);
    def.axis_azimuth_rad = between(-kPi, kPi);
    def.base_height_diameters = between(1.0, 6.0);
    def.mirror = unit(rng) < 0.5;
    def.slip_same_sense = unit(rng) < 0.5;
    def.post_strand = unit(rng) < 0.5 ? 1 : 2;
    std::vector<Eigen::Vector3d> thread;
    try {
      thread = MakeStitchKnot(def);
    } catch (const std::invalid_argument&) {
      continue;  // tails aimed through the knot, or the knot leaning into the tissue
    }
    const Eigen::AngleAxisd turn(between(-kPi, kPi), Eigen::Vector3d::UnitZ());
    const Eigen::Vector3d shift(between(-0.05, 0.05), between(-0.05, 0.05), 0.0);
    for (auto& p : thread) {
      const Eigen::Vector3d noise(between(-1, 1), between(-1, 1), between(-1, 1));
      p = turn * p + shift + noise_diameters * d * noise;
    }
    out.push_back({def, std::move(thread)});
  }
  return out;
}

std::string FormatConfusion(const ConfusionMatrix& m) {
  std::string s = "generated \\ recognised";
  char cell[64];
  for (int c = 0; c < 7; ++c) {
    std::snprintf(cell, sizeof(cell), " %11s",
                  std::string(StitchKnotName(static_cast<StitchKnotType>(c))).c_str());
    s += cell;
  }
  s += "\n";
  for (std::size_t r = 0; r < m.size(); ++r) {
    std::snprintf(cell, sizeof(cell), "%-22s",
                  std::string(StitchKnotName(kStitchClasses[r])).c_str());
    s += cell;
    for (int c = 0; c < 7; ++c) {
      std::snprintf(cell, sizeof(cell), " %11d", m[r][c]);
      s += cell;
    }
    s += "\n";
  }
  return s;
}

}  // namespace microdex::knot::variants
