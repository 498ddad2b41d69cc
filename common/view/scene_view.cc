#include "common/view/scene_view.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>

#include "common/base/json_text.h"
#include "common/geometry/loop_wire.h"
#include "common/knot/stitch_knot_shapes.h"

namespace microdex::view {
namespace {

std::string Num(double v) { return JsonNumber(v); }

std::string Vec(const Eigen::Vector3d& v) {
  std::string out = "[";
  out.append(Num(v.x())).append(",").append(Num(v.y())).append(",").append(Num(v.z()));
  return out.append("]");
}

std::string Pose(const Eigen::Isometry3d& X) {
  const Eigen::Quaterniond q(X.linear());
  std::string out = "{\"p\":";
  out.append(Vec(X.translation())).append(",\"q\":[").append(Num(q.w())).append(",");
  out.append(Num(q.x())).append(",").append(Num(q.y())).append(",").append(Num(q.z()));
  return out.append("]}");
}

// The wire's axis as a polyline: segments by their ends, arcs every 5° at most.
std::string WirePolyline(const geometry::WireDef& wire) {
  std::string out = "[";
  bool first = true;
  auto add = [&](const Eigen::Vector3d& p) {
    if (!first) out += ',';
    out += Vec(p);
    first = false;
  };
  for (const geometry::WirePieceDef& piece : wire.pieces) {
    if (first) add(piece.StartPoint());
    if (piece.kind == geometry::WirePieceDef::Kind::kSegment) {
      add(piece.p_W1);
      continue;
    }
    const Eigen::Vector3d v = piece.axis_W.cross(piece.u_W);
    const int n =
        std::max(2, static_cast<int>(std::ceil(piece.sweep_rad / (std::numbers::pi / 36))));
    for (int i = 1; i <= n; ++i) {
      const double s = piece.sweep_rad * i / n;
      add(piece.p_WO + piece.radius_m * (std::cos(s) * piece.u_W + std::sin(s) * v));
    }
  }
  return out + "]";
}

// The ideal tool path (the task's), sampled: drawn faintly as the course to follow.
std::string IdealPath(const scene::SceneModel& s) {
  if (s.task.kind == scene::TaskKind::kTremorHold || s.task.kind == scene::TaskKind::kKnotTying ||
      s.task.kind == scene::TaskKind::kKnotTopology ||
      s.task.kind == scene::TaskKind::kKnotPlacement || s.task.kind == scene::TaskKind::kGrasp) {
    return "[]";
  }
  const double t_end = std::max(s.task.pass_duration_s, 1e-3);
  std::string out = "[";
  constexpr int kSamples = 96;
  for (int i = 0; i <= kSamples; ++i) {
    const Eigen::Isometry3d X = s.CalcIdealToolPose(t_end * i / kSamples);
    if (i > 0) out += ',';
    out += Vec(X.translation());
  }
  return out + "]";
}

// The knot-topology quiz's knots (the station's shapes, KnotQuizSceneDef::ItemShape), each
// resampled to at most kKnotPoints points: [[x, y, z, x, y, z, ...], ...].
std::string KnotItems(const scene::KnotQuizSceneDef& k) {
  constexpr int kKnotPoints = 240;
  std::string out = "[";
  for (std::size_t i = 0; i < k.items.size(); ++i) {
    std::vector<Eigen::Vector3d> p = k.ItemShape(i);
    if (p.size() > kKnotPoints) p = knot::ResampleByArcLength(p, kKnotPoints - 1);
    out += i ? ",[" : "[";
    for (std::size_t j = 0; j < p.size(); ++j) {
      if (j) out += ',';
      out.append(Num(p[j].x())).append(",").append(Num(p[j].y())).append(",").append(Num(p[j].z()));
    }
    out += "]";
  }
  return out + "]";
}

}  // namespace

std::string SceneViewJson(const scene::SceneModel& s) {
  std::ostringstream j;
  j << "{\"name\":" << JsonQuote(s.name)
    << ",\"task\":" << JsonQuote(scene::TaskKindName(s.task.kind)) << ",\"modules\":[";
  for (std::size_t i = 0; i < s.modules.size(); ++i) {
    j << (i ? "," : "") << JsonQuote(s.modules[i]);
  }
  j << "],\"microscope\":{\"magnification\":" << Num(s.microscope.magnification)
    << ",\"look_at\":" << Vec(s.microscope.look_at_m)
    << ",\"view_dir\":" << Vec(s.microscope.view_dir_W) << "}";
  j << ",\"tolerance\":" << Num(s.task.tolerance_m);
  j << ",\"path\":" << IdealPath(s);
  j << ",\"tool_start\":" << Pose(s.CalcIdealToolPose(0));
  if (s.hands() == 2) j << ",\"second_tool_start\":" << Pose(s.CalcIdealSecondToolPose(0));
  if (s.HasModule("needle")) {
    j << ",\"vessel\":{\"core_radius\":" << Num(s.vessel.core_radius_m)
      << ",\"tube_radius\":" << Num(s.vessel.tube_radius_m)
      << ",\"segment_angle\":" << Num(s.vessel.segment_angle_rad)
      << ",\"pose\":" << Pose(s.vessel.X_WV) << "}";
    j << ",\"needle\":{\"radius\":" << Num(s.needle.radius_m)
      << ",\"sweep\":" << Num(s.needle.sweep_rad) << ",\"X_TN\":" << Pose(s.X_TN()) << "}";
  }
  if (s.task.kind == scene::TaskKind::kTremorHold) {
    j << ",\"target\":{\"p\":" << Vec(s.task.target_m) << ",\"radius\":" << Num(s.task.tolerance_m)
      << "}";
  }
  if (s.thread) {
    j << ",\"thread\":{\"anchor\":" << Vec(s.thread->p_W_anchor)
      << ",\"radius\":" << Num(s.thread->def.diameter_m / 2) << "}";
  }
  if (s.tissue) {
    j << ",\"tissue\":{\"lx\":" << Num(s.tissue->def.length_x_m)
      << ",\"ly\":" << Num(s.tissue->def.length_y_m) << ",\"pose\":" << Pose(s.tissue->X_WS)
      << ",\"bar\":"
      << (s.tissue->tool == scene::TissueToolKind::kBar ? Num(s.tissue->bar_length_m) : "0") << "}";
  }
  if (s.loop) {
    j << ",\"wire\":{\"radius\":" << Num(s.loop->wire.radius_m)
      << ",\"points\":" << WirePolyline(s.loop->wire) << "}";
    j << ",\"loop\":{\"radius\":" << Num(s.loop->loop.radius_m)
      << ",\"wire_radius\":" << Num(s.loop->loop.wire_radius_m) << "}";
  }
  if (s.grasp) {
    const grasp::ShapeDef& sh = s.grasp->def.shape;
    j << ",\"grasp\":{\"shape\":" << JsonQuote(grasp::ShapeKindName(sh.kind))
      << ",\"size\":" << Vec(sh.box_size_m) << ",\"radius\":" << Num(sh.radius_m)
      << ",\"length\":" << Num(sh.length_m) << ",\"p\":" << Vec(s.grasp->p_W_object)
      << ",\"yaw\":" << Num(s.grasp->yaw_rad) << ",\"jaw_width\":" << Num(s.grasp->def.jaws.width_m)
      << ",\"jaw_length\":" << Num(s.grasp->def.jaws.length_m)
      << ",\"jaw_thickness\":" << Num(s.grasp->def.jaws.thickness_m)
      << ",\"open_gap\":" << Num(s.grasp->def.jaws.open_gap_m) << "}";
  }
  if (s.placement) {
    j << ",\"placement\":{\"vessel_radius\":" << Num(s.placement->vessel_radius_m)
      << ",\"end_height\":" << Num(s.placement->end_height_m)
      << ",\"stitches\":" << s.placement->stitches << ",\"bite\":" << Num(s.placement->bite_m)
      << "}";
  }
  if (s.knot_tying && s.thread) {
    // The stitch's rods (a, b, radius each) and the tissue surface (the plane y = surface_y).
    j << ",\"stitch\":{\"rods\":[";
    const std::vector<thread::Collider> rods =
        s.knot_tying->stitch.Colliders(s.thread->def.diameter_m / 2);
    for (std::size_t i = 0; i < rods.size(); ++i) {
      j << (i ? "," : "") << "{\"a\":" << Vec(rods[i].a_W) << ",\"b\":" << Vec(rods[i].b_W)
        << ",\"radius\":" << Num(rods[i].radius_m) << "}";
    }
    j << "],\"surface_y\":" << Num(s.knot_tying->surface_y_m) << "}";
  }
  if (s.knots) {
    // The thread as drawn: each item's (a tied knot's diameter at its drawing scale, else the
    // parametric shapes'), and the largest.
    std::string radii = "[";
    double diameter_m = 0;
    for (std::size_t i = 0; i < s.knots->items.size(); ++i) {
      double item_m = s.knots->ItemThreadDiameter(i);
      if (!(item_m > 0)) item_m = s.knots->thread_diameter_m;
      diameter_m = std::max(diameter_m, item_m);
      if (i > 0) radii += ',';
      radii += Num(item_m / 2);
    }
    if (!(diameter_m > 0)) diameter_m = s.knots->thread_diameter_m;
    j << ",\"knots\":{\"radius\":" << Num(diameter_m / 2) << ",\"radii\":" << radii << "]"
      << ",\"items\":" << KnotItems(*s.knots) << "}";
  }
  j << "}";
  return j.str();
}

}  // namespace microdex::view
