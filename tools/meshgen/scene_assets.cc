#include "tools/meshgen/scene_assets.h"

#include <numbers>

#include "common/mesh/primitives.h"

namespace microdex::meshgen {
namespace {

constexpr double kPi = std::numbers::pi;

// Micro forceps: slender jaws; a needle holder: shorter, broader, blunter ones.
const mesh::JawMeshDef kForcepsJaw{
    .length_m = 8e-3, .width_m = 0.8e-3, .height_m = 0.5e-3, .tip_scale = 0.3, .n_back = 8};
const mesh::JawMeshDef kNeedleHolderJaw{
    .length_m = 5e-3, .width_m = 1.2e-3, .height_m = 0.7e-3, .tip_scale = 0.6, .n_back = 8};
constexpr double kPairOpening_rad = 0.3;

std::vector<SceneAsset> MakeTable() {
  return {
      {"vessel_torus_R5mm_r0.5mm.glb",
       "needle along a curved tube: the vessel (view; the physics is the analytic torus), 270° "
       "segment with end caps, as assets/scenes/needle_tube.yaml",
       [] {
         return mesh::MakeTorusTubeMesh({.core_radius_m = 5e-3,
                                         .tube_radius_m = 0.5e-3,
                                         .segment_angle_rad = 1.5 * kPi,
                                         .n_major = 48,
                                         .n_minor = 16,
                                         .end_caps = true});
       }},
      {"vessel_cut_end.glb",
       "knot placement around a vessel's cut end: a 1 mm vessel, 0.1 mm wall, 6 mm long, cut "
       "square at z = 6 mm (view and collision)",
       [] { return mesh::MakeVesselCylinderMesh({}); }},
      {"tissue_patch_20x20mm.obj",
       "needle through tissue, knot tying: a 20 × 20 × 2 mm patch, its top a 1 mm grid a view "
       "deforms (view; collision from the FEM model)",
       [] { return mesh::MakeTissueSlabMesh({}); }},
      {"curved_needle_3_8.obj",
       "needle scenes: a 3/8-circle needle, 5 mm radius, 0.2 mm wire tapering over its last 2 mm "
       "(view; the physics is the analytic arc)",
       [] { return mesh::MakeNeedleMesh({.n_along = 32}); }},
      {"forceps_jaw.glb",
       "grasping, thread control, knot tying: one forceps jaw in its frame J; a view places two "
       "by CalcJawPose(±1, opening) (view and collision)",
       [] { return mesh::MakeJawMesh(kForcepsJaw); }},
      {"forceps_jaws.glb", "the forceps jaw pair in the tool frame T, opened 0.3 rad",
       [] { return mesh::MakeJawPairMesh(kForcepsJaw, kPairOpening_rad); }},
      {"needle_holder_jaw.glb",
       "needle through tissue, knot tying: one needle-holder jaw in its frame J (view and "
       "collision)",
       [] { return mesh::MakeJawMesh(kNeedleHolderJaw); }},
      {"needle_holder_jaws.glb", "the needle-holder jaw pair in the tool frame T, opened 0.3 rad",
       [] { return mesh::MakeJawPairMesh(kNeedleHolderJaw, kPairOpening_rad); }},
      {"wire_course.obj",
       "passing a loop along a wire: a 0.5 mm wire along straight and arc sections (view and "
       "collision)",
       [] {
         mesh::WireMeshDef def;
         def.max_arc_step_rad = kPi / 16;
         return mesh::MakeWireMesh(def);
       }},
      {"loop_ring_R1.5mm.ply",
       "passing a loop along a wire: the loop, a 1.5 mm ring of 0.2 mm wire on a 10 mm handle "
       "(view and collision)",
       [] { return mesh::MakeLoopMesh({}); }},
      {"target_sphere_d1mm.ply", "grasping a small object: a 1 mm sphere (view and collision)",
       [] { return mesh::MakeSphereMesh({}); }},
      {"target_cylinder.obj",
       "grasping a small object: a cylinder, 1 mm across and 1 mm long (view and collision)",
       [] { return mesh::MakeCylinderMesh({}); }},
      {"target_cube.obj", "grasping a small object: a 1 mm cube (view and collision)",
       [] { return mesh::MakeBoxMesh({}); }},
      {"target_ring.ply",
       "tremor hold and targets: a marker ring, 1 mm radius, 0.1 mm thick wire (view only)",
       [] {
         return mesh::MakeTorusTubeMesh(
             {.core_radius_m = 1e-3, .tube_radius_m = 0.1e-3, .n_major = 32, .n_minor = 8});
       }},
  };
}

}  // namespace

const std::vector<SceneAsset>& SceneAssets() {
  static const std::vector<SceneAsset> table = MakeTable();
  return table;
}

}  // namespace microdex::meshgen
