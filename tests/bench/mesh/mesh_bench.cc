// microdex-bench mesh: what the scene meshes cost at load and as collision geometry.
//
//   1. Per scene asset (assets/meshes/, tools/meshgen/scene_assets.cc): file size, triangles,
//      LoadMesh time and FCL BVH build time (medians of --repeats).
//   2. Sphere meshes as collision geometry: FCL's mesh–mesh distance between two target spheres
//      (0.5 mm and 0.8 mm radius, centres 3 mm apart, random orientations) against the analytic
//      distance, per resolution: the worst error and the median query time, with the BVHs built
//      in millimetres (length_scale 1e3, as mesh_fcl.h advises) and in metres (1).

#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "bench_registry.h"
#include "bench_util.h"
#include "common/mesh/mesh_fcl.h"
#include "common/mesh/mesh_io.h"
#include "common/mesh/primitives.h"
#include "fcl/narrowphase/distance.h"
#include "tools/meshgen/scene_assets.h"

namespace microdex::bench {
namespace {

double NowNs() {
  return static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                 std::chrono::steady_clock::now().time_since_epoch())
                                 .count());
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

struct AssetResult {
  std::string file;
  std::uintmax_t bytes = 0;
  std::size_t triangles = 0;
  double load_ns = 0, bvh_ns = 0;
};

struct SphereResult {
  int n_lat = 0, n_lon = 0;
  std::size_t triangles = 0;  // of both meshes
  double scale = 1;
  double max_error_m = 0;  // FCL mesh distance − analytic distance, worst over the poses
  double query_ns = 0;     // median
};

AssetResult MeasureAsset(const std::string& dir, const meshgen::SceneAsset& asset, int repeats) {
  AssetResult r;
  r.file = asset.file;
  const std::string path = dir + "/" + asset.file;
  r.bytes = std::filesystem::file_size(path);
  std::vector<double> load, bvh;
  for (int k = 0; k < repeats; ++k) {
    const double t0 = NowNs();
    const mesh::TriangleMesh m = mesh::LoadMesh(path);
    const double t1 = NowNs();
    const auto model = mesh::MakeFclMesh(m, 1e3);
    const double t2 = NowNs();
    r.triangles = m.triangles.size();
    load.push_back(t1 - t0);
    bvh.push_back(t2 - t1);
  }
  r.load_ns = Median(load);
  r.bvh_ns = Median(bvh);
  return r;
}

SphereResult MeasureSpheres(int k, double scale, int poses) {
  constexpr double kR1 = 0.5e-3, kR2 = 0.8e-3, kCentres_m = 3e-3;
  SphereResult r;
  r.n_lat = 6 * k;
  r.n_lon = 12 * k;
  r.scale = scale;
  const mesh::TriangleMesh a =
      mesh::MakeSphereMesh({.radius_m = kR1, .n_lat = r.n_lat, .n_lon = r.n_lon});
  const mesh::TriangleMesh b =
      mesh::MakeSphereMesh({.radius_m = kR2, .n_lat = r.n_lat, .n_lon = r.n_lon});
  r.triangles = a.triangles.size() + b.triangles.size();
  const auto fa = mesh::MakeFclMesh(a, scale), fb = mesh::MakeFclMesh(b, scale);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g;
  std::vector<double> times;
  for (int i = 0; i < poses; ++i) {
    const Eigen::Vector3d u = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    // Uniform rotations from the seeded generator (a normalised 4-D Gaussian), so that every
    // resolution and scale sees the same poses.
    const Eigen::Quaterniond qa = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized();
    const Eigen::Quaterniond qb = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized();
    fcl::Transform3d X_WA = fcl::Transform3d::Identity(), X_WB = fcl::Transform3d::Identity();
    X_WA.linear() = qa.toRotationMatrix();
    X_WB.linear() = qb.toRotationMatrix();
    X_WB.translation() = scale * kCentres_m * u;
    fcl::DistanceRequestd request;
    fcl::DistanceResultd result;
    const double t0 = NowNs();
    const double d = fcl::distance(fa.get(), X_WA, fb.get(), X_WB, request, result) / scale;
    times.push_back(NowNs() - t0);
    r.max_error_m = std::max(r.max_error_m, std::abs(d - (kCentres_m - kR1 - kR2)));
  }
  r.query_ns = Median(times);
  return r;
}

int RunMesh(int argc, char** argv) {
  CLI::App app{"scene meshes: load and BVH cost per asset; sphere mesh distance error vs time"};
  std::string json_path, dir;
  bool quick = false;
  int repeats = 20, poses = 2000;
  app.add_option("--json", json_path, "write the results as JSON");
  app.add_option("--dir", dir, "the asset folder (default: the source tree's assets/meshes)");
  app.add_option("--repeats", repeats, "loads per asset")->check(CLI::Range(1, 10000));
  app.add_option("--poses", poses, "sphere pairs per resolution")->check(CLI::Range(1, 1000000));
  app.add_flag("--quick", quick, "a short run: 2 loads per asset, 100 poses, coarse spheres");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (quick) {
    repeats = 2;
    poses = 100;
  }
  if (dir.empty()) {
    const char* src = std::getenv("MICRODEX_SOURCE_DIR");
    dir = std::string(src ? src : MICRODEX_BENCH_SOURCE_DIR) + "/assets/meshes";
  }
  const auto& assets = meshgen::SceneAssets();
  const std::vector<int> resolutions =
      quick ? std::vector<int>{1, 2} : std::vector<int>{1, 2, 4, 8, 16};
  const std::vector<double> scales = {1e3, 1.0};
  std::vector<AssetResult> asset_results;
  std::vector<SphereResult> sphere_results;
  try {
    ProgressLine progress(static_cast<int>(assets.size() + resolutions.size() * scales.size()));
    for (const meshgen::SceneAsset& asset : assets) {
      asset_results.push_back(MeasureAsset(dir, asset, repeats));
      progress.Step(asset.file);
    }
    for (const int k : resolutions) {
      for (const double scale : scales) {
        sphere_results.push_back(MeasureSpheres(k, scale, poses));
        progress.Step("spheres x" + std::to_string(k));
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "microdex-bench mesh: %s\n", e.what());
    return 2;
  }
  std::printf("%-30s %9s %9s %10s %10s\n", "asset", "bytes", "triangles", "load ms", "bvh ms");
  for (const AssetResult& r : asset_results) {
    std::printf("%-30s %9ju %9zu %10.3f %10.3f\n", r.file.c_str(), r.bytes, r.triangles,
                r.load_ns * 1e-6, r.bvh_ns * 1e-6);
  }
  std::printf("\nsphere meshes (0.5 mm, 0.8 mm; centres 3 mm apart), FCL distance vs analytic\n");
  std::printf("%6s %6s %9s %8s %14s %12s\n", "n_lat", "n_lon", "triangles", "scale", "max error m",
              "query us");
  for (const SphereResult& r : sphere_results) {
    std::printf("%6d %6d %9zu %8g %14.3e %12.2f\n", r.n_lat, r.n_lon, r.triangles, r.scale,
                r.max_error_m, r.query_ns * 1e-3);
  }
  if (!json_path.empty()) {
    std::ofstream f(json_path);
    if (!f) {
      std::fprintf(stderr, "microdex-bench mesh: --json %s: cannot write\n", json_path.c_str());
      return 2;
    }
    f << "{\n  \"repeats\": " << repeats << ", \"poses\": " << poses << ",\n  \"assets\": [";
    for (std::size_t i = 0; i < asset_results.size(); ++i) {
      const AssetResult& r = asset_results[i];
      f << (i ? ",\n" : "\n") << "    {\"file\": \"" << r.file << "\", \"bytes\": " << r.bytes
        << ", \"triangles\": " << r.triangles << ", \"load_ns\": " << r.load_ns
        << ", \"bvh_ns\": " << r.bvh_ns << "}";
    }
    f << "\n  ],\n  \"spheres\": [";
    for (std::size_t i = 0; i < sphere_results.size(); ++i) {
      const SphereResult& r = sphere_results[i];
      f << (i ? ",\n" : "\n") << "    {\"n_lat\": " << r.n_lat << ", \"n_lon\": " << r.n_lon
        << ", \"triangles\": " << r.triangles << ", \"length_scale\": " << r.scale
        << ", \"max_error_m\": " << r.max_error_m << ", \"query_ns\": " << r.query_ns << "}";
    }
    f << "\n  ]\n}\n";
  }
  return 0;
}

}  // namespace

MICRODEX_REGISTER_BENCH(mesh, "mesh",
                        "scene meshes: load and BVH cost per asset; sphere mesh distance error vs "
                        "time",
                        RunMesh);

}  // namespace microdex::bench
