#include "common/mesh/primitives.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace microdex::mesh {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2 * std::numbers::pi;
constexpr int kMaxResolution = 100000;  // per direction: beyond it a Def is a typo

void Require(bool ok, const char* field, const char* expected) {
  if (!ok) throw std::invalid_argument(std::string(field) + ": expected " + expected);
}
void RequireLength(double v, const char* field) {
  Require(std::isfinite(v) && v > 0, field, "a finite length > 0 (m)");
}
void RequireCount(int n, int min, const char* field) {
  Require(
      n >= min && n <= kMaxResolution, field,
      ("a count in [" + std::to_string(min) + ", " + std::to_string(kMaxResolution) + "]").c_str());
}

// A ring of points added to the mesh; one point for a ring of radius 0 (a tip or a pole).
using Ring = std::vector<int>;

Ring AddRing(const std::vector<Eigen::Vector3d>& points, TriangleMesh& mesh) {
  Ring ring;
  for (const Eigen::Vector3d& p : points) {
    ring.push_back(static_cast<int>(mesh.vertices.size()));
    mesh.vertices.push_back(p);
  }
  return ring;
}

// The points c + r (cos ψ_j N + sin ψ_j B), ψ_j = 2π j / n, B = N × T: with rings in the order of
// T, the strip between them faces N (outwards). Radius 0: the centre only.
std::vector<Eigen::Vector3d> CirclePoints(const Eigen::Vector3d& c, const Eigen::Vector3d& T,
                                          const Eigen::Vector3d& N, double r, int n) {
  if (r == 0) return {c};
  const Eigen::Vector3d B = N.cross(T);
  std::vector<Eigen::Vector3d> points;
  for (int j = 0; j < n; ++j) {
    const double psi = kTwoPi * j / n;
    points.push_back(c + r * (std::cos(psi) * N + std::sin(psi) * B));
  }
  return points;
}

void AddTriangle(int a, int b, int c, TriangleMesh& mesh) {
  if (a != b && b != c && c != a) mesh.triangles.emplace_back(a, b, c);
}

// Quads (a_j, b_j, b_j+1, a_j+1) around two rings of the same count (or one of a single point),
// as the triangles (a_j, b_j, b_j+1), (a_j, b_j+1, a_j+1); `flip` reverses them.
void AddStrip(const Ring& a, const Ring& b, bool flip, TriangleMesh& mesh) {
  const int n = static_cast<int>(std::max(a.size(), b.size()));
  const auto at = [](const Ring& ring, int j) { return ring[j % ring.size()]; };
  for (int j = 0; j < n; ++j) {
    const int a0 = at(a, j), a1 = at(a, j + 1), b0 = at(b, j), b1 = at(b, j + 1);
    if (flip) {
      AddTriangle(a0, b1, b0, mesh);
      AddTriangle(a0, a1, b1, mesh);
    } else {
      AddTriangle(a0, b0, b1, mesh);
      AddTriangle(a0, b1, a1, mesh);
    }
  }
}

// A flat cap: a fan around the ring's centroid, facing against the ring order's T (the start of
// a tube) or along it (`end`).
void AddCap(const Ring& ring, bool end, TriangleMesh& mesh) {
  if (ring.size() < 3) return;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int v : ring) c += mesh.vertices[v];
  c /= static_cast<double>(ring.size());
  const int center = static_cast<int>(mesh.vertices.size());
  mesh.vertices.push_back(c);
  AddStrip(Ring{center}, ring, end, mesh);
}

// Strips between consecutive rings (and the last to the first when `loop`), caps at the ends.
void AddTube(const std::vector<Ring>& rings, bool loop, bool caps, TriangleMesh& mesh) {
  for (size_t i = 0; i + 1 < rings.size(); ++i) AddStrip(rings[i], rings[i + 1], false, mesh);
  if (loop) AddStrip(rings.back(), rings.front(), false, mesh);
  if (caps && !loop) {
    AddCap(rings.front(), false, mesh);
    AddCap(rings.back(), true, mesh);
  }
}

}  // namespace

void TorusTubeMeshDef::Validate() const {
  RequireLength(core_radius_m, "TorusTubeMeshDef.core_radius_m");
  RequireLength(tube_radius_m, "TorusTubeMeshDef.tube_radius_m");
  Require(tube_radius_m < core_radius_m, "TorusTubeMeshDef.tube_radius_m", "< core_radius_m");
  Require(segment_angle_rad > 0 && segment_angle_rad <= kTwoPi,
          "TorusTubeMeshDef.segment_angle_rad", "an angle in (0, 2π] (rad)");
  RequireCount(n_major, 1, "TorusTubeMeshDef.n_major");
  RequireCount(n_minor, 3, "TorusTubeMeshDef.n_minor");
}

TriangleMesh MakeTorusTubeMesh(const TorusTubeMeshDef& def) {
  def.Validate();
  const bool full_turn = def.segment_angle_rad >= kTwoPi;
  const int n_rings = full_turn ? def.n_major : def.n_major + 1;
  const double R = def.core_radius_m, r = def.tube_radius_m;
  TriangleMesh mesh;
  std::vector<Ring> rings;
  for (int i = 0; i < n_rings; ++i) {
    const double phi = def.segment_angle_rad * i / def.n_major;
    std::vector<Eigen::Vector3d> points;
    for (int j = 0; j < def.n_minor; ++j) {
      const double psi = kTwoPi * j / def.n_minor;
      const double w = R + r * std::cos(psi);
      points.emplace_back(w * std::cos(phi), w * std::sin(phi), r * std::sin(psi));
    }
    rings.push_back(AddRing(points, mesh));
  }
  AddTube(rings, full_turn, def.end_caps, mesh);
  return mesh;
}

void VesselCylinderMeshDef::Validate() const {
  RequireLength(outer_radius_m, "VesselCylinderMeshDef.outer_radius_m");
  RequireLength(wall_thickness_m, "VesselCylinderMeshDef.wall_thickness_m");
  Require(wall_thickness_m < outer_radius_m, "VesselCylinderMeshDef.wall_thickness_m",
          "< outer_radius_m");
  Require(std::abs(cut_angle_rad) < kPi / 2, "VesselCylinderMeshDef.cut_angle_rad",
          "an angle in (−π/2, π/2) (rad)");
  RequireLength(length_m, "VesselCylinderMeshDef.length_m");
  Require(length_m > outer_radius_m * std::abs(std::tan(cut_angle_rad)),
          "VesselCylinderMeshDef.length_m", "> outer_radius_m |tan(cut_angle_rad)|");
  RequireCount(n_around, 3, "VesselCylinderMeshDef.n_around");
  RequireCount(n_along, 1, "VesselCylinderMeshDef.n_along");
}

TriangleMesh MakeVesselCylinderMesh(const VesselCylinderMeshDef& def) {
  def.Validate();
  const double tan_cut = std::tan(def.cut_angle_rad);
  TriangleMesh mesh;
  std::vector<Ring> outer, inner;
  for (double radius : {def.outer_radius_m, def.outer_radius_m - def.wall_thickness_m}) {
    std::vector<Ring>& rings = radius == def.outer_radius_m ? outer : inner;
    for (int i = 0; i <= def.n_along; ++i) {
      const double t = static_cast<double>(i) / def.n_along;
      std::vector<Eigen::Vector3d> points =
          CirclePoints(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(),
                       radius, def.n_around);
      // Each point moves along the axis to its share of the way to the cut plane.
      for (Eigen::Vector3d& p : points) p.z() = t * (def.length_m + p.x() * tan_cut);
      rings.push_back(AddRing(points, mesh));
    }
  }
  for (int i = 0; i < def.n_along; ++i) {
    AddStrip(outer[i], outer[i + 1], false, mesh);
    AddStrip(inner[i], inner[i + 1], true, mesh);  // the lumen's wall faces the axis
  }
  AddStrip(inner.front(), outer.front(), false, mesh);  // the end in z = 0, facing −z
  AddStrip(outer.back(), inner.back(), false, mesh);    // the cut end
  return mesh;
}

WireMeshDef::WireMeshDef() {
  // An S-shaped course in the xy-plane with a rise out of it: straight, left turn, straight,
  // right turn, upward bend, straight.
  sections = {
      {.length_m = 8e-3},
      {.length_m = 6e-3 * kPi / 2, .bend_radius_m = 6e-3, .bend_direction_rad = 0},
      {.length_m = 6e-3},
      {.length_m = 4e-3 * kPi, .bend_radius_m = 4e-3, .bend_direction_rad = kPi},
      {.length_m = 5e-3 * kPi / 4, .bend_radius_m = 5e-3, .bend_direction_rad = kPi / 2},
      {.length_m = 6e-3},
  };
}

void WireMeshDef::Validate() const {
  RequireLength(wire_radius_m, "WireMeshDef.wire_radius_m");
  Require(!sections.empty(), "WireMeshDef.sections", "at least one section");
  for (size_t k = 0; k < sections.size(); ++k) {
    const WireSectionDef& s = sections[k];
    const std::string at = "WireMeshDef.sections[" + std::to_string(k) + "]";
    RequireLength(s.length_m, (at + ".length_m").c_str());
    Require(
        s.bend_radius_m == 0 || (std::isfinite(s.bend_radius_m) && s.bend_radius_m > wire_radius_m),
        (at + ".bend_radius_m").c_str(), "0 (straight) or a finite radius > wire_radius_m (m)");
    Require(std::isfinite(s.bend_direction_rad), (at + ".bend_direction_rad").c_str(),
            "a finite angle (rad)");
  }
  Require(std::isfinite(max_arc_step_rad) && max_arc_step_rad > 0, "WireMeshDef.max_arc_step_rad",
          "a finite angle > 0 (rad)");
  RequireCount(n_around, 3, "WireMeshDef.n_around");
}

namespace {

// Walks the wire's centre line: calls visit(X_PF) at the start and after every step, where F is
// the frame (T, N, B) at that point of the line.
template <typename Visit>
void WalkWire(const WireMeshDef& def, Visit&& visit) {
  Eigen::Isometry3d X_PF = Eigen::Isometry3d::Identity();
  visit(X_PF);
  for (const WireSectionDef& s : def.sections) {
    if (s.bend_radius_m == 0) {
      X_PF.translation() += s.length_m * X_PF.linear().col(0);
      visit(X_PF);
      continue;
    }
    // In F at the section start: the arc bends towards n = cos(θ) N + sin(θ) B about the axis
    // T × n, around the centre ρ n.
    const Eigen::Isometry3d X_PS = X_PF;
    const double angle = s.length_m / s.bend_radius_m;
    const Eigen::Vector3d n_S(0, std::cos(s.bend_direction_rad), std::sin(s.bend_direction_rad));
    const Eigen::Vector3d axis_S = Eigen::Vector3d::UnitX().cross(n_S);
    const int steps = std::max(1, static_cast<int>(std::ceil(angle / def.max_arc_step_rad)));
    for (int k = 1; k <= steps; ++k) {
      const double a = angle * k / steps;
      Eigen::Isometry3d X_SF = Eigen::Isometry3d::Identity();
      X_SF.linear() = Eigen::AngleAxisd(a, axis_S).toRotationMatrix();
      X_SF.translation() =
          s.bend_radius_m * (std::sin(a) * Eigen::Vector3d::UnitX() + (1 - std::cos(a)) * n_S);
      X_PF = X_PS * X_SF;
      visit(X_PF);
    }
  }
}

}  // namespace

TriangleMesh MakeWireMesh(const WireMeshDef& def) {
  def.Validate();
  TriangleMesh mesh;
  std::vector<Ring> rings;
  WalkWire(def, [&](const Eigen::Isometry3d& X_PF) {
    rings.push_back(AddRing(CirclePoints(X_PF.translation(), X_PF.linear().col(0),
                                         X_PF.linear().col(1), def.wire_radius_m, def.n_around),
                            mesh));
  });
  AddTube(rings, false, true, mesh);
  return mesh;
}

Eigen::Isometry3d CalcWireEndPose(const WireMeshDef& def) {
  def.Validate();
  Eigen::Isometry3d end = Eigen::Isometry3d::Identity();
  WalkWire(def, [&](const Eigen::Isometry3d& X_PF) { end = X_PF; });
  return end;
}

void LoopMeshDef::Validate() const {
  RequireLength(ring_radius_m, "LoopMeshDef.ring_radius_m");
  RequireLength(wire_radius_m, "LoopMeshDef.wire_radius_m");
  Require(wire_radius_m < ring_radius_m, "LoopMeshDef.wire_radius_m", "< ring_radius_m");
  RequireLength(handle_length_m, "LoopMeshDef.handle_length_m");
  RequireLength(handle_radius_m, "LoopMeshDef.handle_radius_m");
  RequireCount(n_major, 3, "LoopMeshDef.n_major");
  RequireCount(n_minor, 3, "LoopMeshDef.n_minor");
}

TriangleMesh MakeLoopMesh(const LoopMeshDef& def) {
  def.Validate();
  TriangleMesh mesh = MakeTorusTubeMesh({.core_radius_m = def.ring_radius_m,
                                         .tube_radius_m = def.wire_radius_m,
                                         .segment_angle_rad = kTwoPi,
                                         .n_major = def.n_major,
                                         .n_minor = def.n_minor});
  const Eigen::Vector3d T = -Eigen::Vector3d::UnitX(), N = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d start(-def.ring_radius_m, 0, 0);
  const std::vector<Ring> rings = {
      AddRing(CirclePoints(start, T, N, def.handle_radius_m, def.n_minor), mesh),
      AddRing(CirclePoints(start + def.handle_length_m * T, T, N, def.handle_radius_m, def.n_minor),
              mesh)};
  AddTube(rings, false, true, mesh);
  return mesh;
}

void NeedleMeshDef::Validate() const {
  RequireLength(arc_radius_m, "NeedleMeshDef.arc_radius_m");
  RequireLength(wire_radius_m, "NeedleMeshDef.wire_radius_m");
  Require(wire_radius_m < arc_radius_m, "NeedleMeshDef.wire_radius_m", "< arc_radius_m");
  Require(sweep_rad > 0 && sweep_rad < kTwoPi, "NeedleMeshDef.sweep_rad",
          "an angle in (0, 2π) (rad)");
  RequireLength(taper_length_m, "NeedleMeshDef.taper_length_m");
  Require(taper_length_m <= arc_radius_m * sweep_rad, "NeedleMeshDef.taper_length_m",
          "≤ the needle's length arc_radius_m · sweep_rad");
  RequireCount(n_along, 2, "NeedleMeshDef.n_along");
  RequireCount(n_around, 3, "NeedleMeshDef.n_around");
}

TriangleMesh MakeNeedleMesh(const NeedleMeshDef& def) {
  def.Validate();
  const double rho = def.arc_radius_m, S = def.sweep_rad;
  const double s_taper = S - def.taper_length_m / rho;  // where the taper starts
  // Rings spread over the arc in proportion, with one where the taper starts (when it does
  // not start at the tail).
  const int n_taper =
      s_taper <= 0 ? def.n_along
                   : std::clamp(static_cast<int>(std::lround(def.n_along * (S - s_taper) / S)), 1,
                                def.n_along - 1);
  const int n_body = def.n_along - n_taper;
  TriangleMesh mesh;
  std::vector<Ring> rings;
  for (int i = 0; i <= def.n_along; ++i) {
    const double s = i <= n_body ? (n_body == 0 ? 0 : s_taper * i / n_body)
                                 : s_taper + (S - s_taper) * (i - n_body) / n_taper;
    const double r = i <= n_body ? def.wire_radius_m
                     : i == def.n_along
                         ? 0
                         : def.wire_radius_m * (S - s) / (S - std::max(s_taper, 0.0));
    const Eigen::Vector3d N(std::cos(s), std::sin(s), 0), T(-std::sin(s), std::cos(s), 0);
    rings.push_back(AddRing(CirclePoints(rho * N, T, N, r, def.n_around), mesh));
  }
  AddTube(rings, false, true, mesh);  // the tip is a point: only the tail gets a cap
  return mesh;
}

void JawMeshDef::Validate() const {
  RequireLength(length_m, "JawMeshDef.length_m");
  RequireLength(width_m, "JawMeshDef.width_m");
  RequireLength(height_m, "JawMeshDef.height_m");
  Require(tip_scale > 0 && tip_scale <= 1, "JawMeshDef.tip_scale", "a ratio in (0, 1]");
  RequireCount(n_back, 2, "JawMeshDef.n_back");
}

TriangleMesh MakeJawMesh(const JawMeshDef& def) {
  def.Validate();
  TriangleMesh mesh;
  std::vector<Ring> rings;
  for (int end = 0; end < 2; ++end) {
    const double x = end * def.length_m, scale = end == 0 ? 1 : def.tip_scale;
    // Around the cross-section from (0, +w/2) over the back to (0, −w/2); the inner face closes
    // it. Seen from −x the order is counter-clockwise, as CirclePoints' about +x.
    std::vector<Eigen::Vector3d> points;
    for (int j = 0; j <= def.n_back; ++j) {
      const double alpha = kPi * j / def.n_back;
      points.emplace_back(x, scale * def.height_m * std::sin(alpha),
                          scale * 0.5 * def.width_m * std::cos(alpha));
    }
    rings.push_back(AddRing(points, mesh));
  }
  AddTube(rings, false, true, mesh);
  return mesh;
}

Eigen::Isometry3d CalcJawPose(int side, double opening_angle_rad) {
  Require(side == 1 || side == -1, "side", "+1 (upper jaw) or −1 (lower jaw)");
  Eigen::Isometry3d X_TJ = Eigen::Isometry3d::Identity();
  X_TJ.linear() = Eigen::AngleAxisd(side * 0.5 * opening_angle_rad, Eigen::Vector3d::UnitZ())
                      .toRotationMatrix();
  if (side < 0)
    X_TJ.linear() *= Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitX()).toRotationMatrix();
  return X_TJ;
}

TriangleMesh MakeJawPairMesh(const JawMeshDef& def, double opening_angle_rad) {
  Require(opening_angle_rad >= 0 && opening_angle_rad < kPi, "opening_angle_rad",
          "an angle in [0, π) (rad)");
  const TriangleMesh jaw = MakeJawMesh(def);
  TriangleMesh pair;
  for (int side : {1, -1}) {
    TriangleMesh placed = jaw;
    const Eigen::Isometry3d X_TJ = CalcJawPose(side, opening_angle_rad);
    for (Eigen::Vector3d& p : placed.vertices) p = X_TJ * p;
    AppendMesh(placed, pair);
  }
  return pair;
}

void TissueSlabMeshDef::Validate() const {
  RequireLength(size_x_m, "TissueSlabMeshDef.size_x_m");
  RequireLength(size_y_m, "TissueSlabMeshDef.size_y_m");
  RequireLength(thickness_m, "TissueSlabMeshDef.thickness_m");
  RequireCount(nx, 1, "TissueSlabMeshDef.nx");
  RequireCount(ny, 1, "TissueSlabMeshDef.ny");
}

TriangleMesh MakeTissueSlabMesh(const TissueSlabMeshDef& def) {
  def.Validate();
  TriangleMesh mesh;
  const int per_grid = (def.nx + 1) * (def.ny + 1);
  const auto index = [&](int grid, int i, int j) { return grid * per_grid + i + (def.nx + 1) * j; };
  for (double z : {0.0, -def.thickness_m}) {
    for (int j = 0; j <= def.ny; ++j) {
      for (int i = 0; i <= def.nx; ++i) {
        mesh.vertices.emplace_back(def.size_x_m * (static_cast<double>(i) / def.nx - 0.5),
                                   def.size_y_m * (static_cast<double>(j) / def.ny - 0.5), z);
      }
    }
  }
  for (int grid = 0; grid < 2; ++grid) {
    for (int j = 0; j < def.ny; ++j) {
      for (int i = 0; i < def.nx; ++i) {
        const int a = index(grid, i, j), b = index(grid, i + 1, j), c = index(grid, i + 1, j + 1),
                  d = index(grid, i, j + 1);
        if (grid == 0) {  // the top faces +z
          mesh.triangles.emplace_back(a, b, c);
          mesh.triangles.emplace_back(a, c, d);
        } else {
          mesh.triangles.emplace_back(a, c, b);
          mesh.triangles.emplace_back(a, d, c);
        }
      }
    }
  }
  // The sides: the boundary loops of both grids, counter-clockwise seen from +z.
  Ring top, bottom;
  const auto add = [&](int i, int j) {
    top.push_back(index(0, i, j));
    bottom.push_back(index(1, i, j));
  };
  for (int i = 0; i < def.nx; ++i) add(i, 0);
  for (int j = 0; j < def.ny; ++j) add(def.nx, j);
  for (int i = def.nx; i > 0; --i) add(i, def.ny);
  for (int j = def.ny; j > 0; --j) add(0, j);
  AddStrip(top, bottom, false, mesh);
  return mesh;
}

void SphereMeshDef::Validate() const {
  RequireLength(radius_m, "SphereMeshDef.radius_m");
  RequireCount(n_lat, 2, "SphereMeshDef.n_lat");
  RequireCount(n_lon, 3, "SphereMeshDef.n_lon");
}

TriangleMesh MakeSphereMesh(const SphereMeshDef& def) {
  def.Validate();
  TriangleMesh mesh;
  std::vector<Ring> rings;
  // A tube from the pole at +z to the one at −z (T = −z), its rings the parallels.
  for (int k = 0; k <= def.n_lat; ++k) {
    const double theta = kPi * k / def.n_lat;
    const double r = (k == 0 || k == def.n_lat) ? 0 : def.radius_m * std::sin(theta);
    const Eigen::Vector3d c(0, 0, def.radius_m * std::cos(theta));
    rings.push_back(AddRing(
        CirclePoints(c, -Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), r, def.n_lon), mesh));
  }
  AddTube(rings, false, false, mesh);
  return mesh;
}

void CylinderMeshDef::Validate() const {
  RequireLength(radius_m, "CylinderMeshDef.radius_m");
  RequireLength(length_m, "CylinderMeshDef.length_m");
  RequireCount(n_around, 3, "CylinderMeshDef.n_around");
}

TriangleMesh MakeCylinderMesh(const CylinderMeshDef& def) {
  def.Validate();
  TriangleMesh mesh;
  std::vector<Ring> rings;
  for (double z : {-0.5 * def.length_m, 0.5 * def.length_m}) {
    rings.push_back(AddRing(CirclePoints(Eigen::Vector3d(0, 0, z), Eigen::Vector3d::UnitZ(),
                                         Eigen::Vector3d::UnitX(), def.radius_m, def.n_around),
                            mesh));
  }
  AddTube(rings, false, true, mesh);
  return mesh;
}

void BoxMeshDef::Validate() const {
  for (int k = 0; k < 3; ++k) RequireLength(size_m[k], "BoxMeshDef.size_m");
}

TriangleMesh MakeBoxMesh(const BoxMeshDef& def) {
  def.Validate();
  TriangleMesh mesh;
  // Vertex k at the corner (±x, ±y, ±z) with bit 0, 1, 2 of k set for +.
  for (int k = 0; k < 8; ++k) {
    mesh.vertices.push_back(0.5 * def.size_m.cwiseProduct(Eigen::Vector3d(
                                      (k & 1) ? 1 : -1, (k & 2) ? 1 : -1, (k & 4) ? 1 : -1)));
  }
  // Each face as a quad counter-clockwise from outside.
  const int faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
  for (const auto& f : faces) {
    mesh.triangles.emplace_back(f[0], f[1], f[2]);
    mesh.triangles.emplace_back(f[0], f[2], f[3]);
  }
  return mesh;
}

}  // namespace microdex::mesh
