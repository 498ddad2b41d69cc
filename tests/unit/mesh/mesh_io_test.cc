// LoadMesh / SaveMesh: round trips through every format, node transforms, and bad files.
#include "common/mesh/mesh_io.h"

#include <assimp/scene.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <assimp/Exporter.hpp>
#include <cmath>
#include <fstream>
#include <stdexcept>
#include <string>

#include "common/base/input_error.h"
#include "common/mesh/primitives.h"

namespace microdex::mesh {
namespace {

// Assimp keeps 32-bit floats: a few 1e-10 m at the 5 mm scale of these meshes.
constexpr double kFloatTol_m = 1e-9;

std::string TempPath(const std::string& name) { return ::testing::TempDir() + "/" + name; }

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// The message of the InputError LoadMesh throws (empty when it does not throw one).
std::string LoadError(const std::string& path) {
  try {
    LoadMesh(path);
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    return e.what();
  }
  return "";
}

class MeshIoRoundTrip : public ::testing::TestWithParam<const char*> {};

TEST_P(MeshIoRoundTrip, KeepsTrianglesVerticesNormalsAndTopology) {
  TriangleMesh mesh = MakeTorusTubeMesh({.core_radius_m = 5e-3,
                                         .tube_radius_m = 0.5e-3,
                                         .segment_angle_rad = 2.0,
                                         .n_major = 12,
                                         .n_minor = 8,
                                         .end_caps = true});
  mesh.normals = CalcVertexNormals(mesh);
  const std::string path = TempPath(std::string("round_trip.") + GetParam());
  SaveMesh(mesh, path);
  const TriangleMesh loaded = LoadMesh(path);
  // The per-corner copies a format makes are joined again: the same vertices.
  ASSERT_EQ(loaded.vertices.size(), mesh.vertices.size());
  ASSERT_EQ(loaded.triangles.size(), mesh.triangles.size());
  ASSERT_EQ(loaded.normals.size(), mesh.normals.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.triangles[t][k], b = loaded.triangles[t][k];
      EXPECT_LT((mesh.vertices[a] - loaded.vertices[b]).norm(), kFloatTol_m) << t;
      EXPECT_LT((mesh.normals[a] - loaded.normals[b]).norm(), 1e-6) << t;
    }
  }
  EXPECT_TRUE(CalcEdgeTopology(loaded).closed());
  EXPECT_NEAR(CalcEnclosedVolume(loaded), CalcEnclosedVolume(mesh),
              1e-6 * CalcEnclosedVolume(mesh));
}

INSTANTIATE_TEST_SUITE_P(Formats, MeshIoRoundTrip, ::testing::Values("obj", "ply", "glb", "gltf"));

TEST(MeshIo, WithoutNormalsNoneComeBackButInObj) {
  const TriangleMesh box = MakeBoxMesh({});
  for (const char* ext : {"obj", "ply", "glb"}) {
    const std::string path = TempPath(std::string("no_normals.") + ext);
    SaveMesh(box, path);
    const TriangleMesh loaded = LoadMesh(path);
    EXPECT_EQ(loaded.vertices.size(), 8u) << ext;
    EXPECT_TRUE(CalcEdgeTopology(loaded).closed()) << ext;
    if (std::string(ext) != "obj") {
      EXPECT_TRUE(loaded.normals.empty()) << ext;
      continue;
    }
    // OBJ always has normals (mesh_io.h): the area-weighted ones, pointing out of the corners.
    ASSERT_EQ(loaded.normals.size(), 8u);
    const std::vector<Eigen::Vector3d> expected = CalcVertexNormals(box);
    for (size_t t = 0; t < box.triangles.size(); ++t) {  // the exporter reorders vertices
      for (int k = 0; k < 3; ++k) {
        const int a = box.triangles[t][k], b = loaded.triangles[t][k];
        EXPECT_LT((loaded.normals[b] - expected[a]).norm(), 1e-6) << t;
        EXPECT_GT(loaded.normals[b].dot(loaded.vertices[b].normalized()), 0.5) << t;
      }
    }
  }
}

// Micrometre features (a needle's tip) keep every vertex in every format: no join by distance.
TEST(MeshIo, MicrometreMeshesKeepTheirVertices) {
  const TriangleMesh sphere = MakeSphereMesh({.radius_m = 2e-6, .n_lat = 8, .n_lon = 16});
  for (const char* ext : {"obj", "ply", "glb", "gltf"}) {
    const std::string path = TempPath(std::string("micrometre.") + ext);
    SaveMesh(sphere, path);
    const TriangleMesh loaded = LoadMesh(path);
    ASSERT_EQ(loaded.vertices.size(), sphere.vertices.size()) << ext;
    EXPECT_TRUE(CalcEdgeTopology(loaded).closed()) << ext;
    for (size_t v = 0; v < sphere.vertices.size(); ++v) {
      EXPECT_LT((loaded.vertices[v] - sphere.vertices[v]).norm(), 1e-12) << ext << " " << v;
    }
  }
}

// A file of two meshes under nested nodes, one of them mirrored, written with assimp's own
// exporter: LoadMesh merges them in the root frame and keeps them outward.
TEST(MeshIo, MergesMeshesWithTheirNodeTransforms) {
  const TriangleMesh box = MakeBoxMesh({.size_m = Eigen::Vector3d(1e-3, 2e-3, 3e-3)});
  aiScene scene;
  scene.mNumMaterials = 1;
  scene.mMaterials = new aiMaterial* [1] { new aiMaterial() };
  scene.mNumMeshes = 2;
  scene.mMeshes = new aiMesh*[2];
  for (int m = 0; m < 2; ++m) {
    aiMesh* am = scene.mMeshes[m] = new aiMesh();
    am->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
    am->mNumVertices = 8;
    am->mVertices = new aiVector3D[8];
    for (int v = 0; v < 8; ++v) {
      const Eigen::Vector3f p = box.vertices[v].cast<float>();
      am->mVertices[v] = aiVector3D(p.x(), p.y(), p.z());
    }
    am->mNumFaces = 12;
    am->mFaces = new aiFace[12];
    for (int f = 0; f < 12; ++f) {
      am->mFaces[f].mNumIndices = 3;
      am->mFaces[f].mIndices = new unsigned[3];
      for (int k = 0; k < 3; ++k) am->mFaces[f].mIndices[k] = box.triangles[f][k];
    }
  }
  // root (translated) → child A (rotated) with mesh 0, → child B (mirrored in x) with mesh 1.
  const Eigen::Vector3d p_FR(0.01, -0.02, 0.005);
  const Eigen::Matrix3d R_RA =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).matrix();
  const Eigen::Matrix3d M_RB = Eigen::Vector3d(-1, 1, 1).asDiagonal();
  const Eigen::Vector3d p_RB(0, 0.004, 0);
  const auto to_ai = [](const Eigen::Matrix3d& L, const Eigen::Vector3d& p) {
    aiMatrix4x4 m;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) m[i][j] = static_cast<ai_real>(L(i, j));
      m[i][3] = static_cast<ai_real>(p[i]);
    }
    return m;
  };
  scene.mRootNode = new aiNode("root");
  scene.mRootNode->mTransformation = to_ai(Eigen::Matrix3d::Identity(), p_FR);
  scene.mRootNode->mNumChildren = 2;
  scene.mRootNode->mChildren = new aiNode* [2] { new aiNode("a"), new aiNode("b") };
  aiNode* a = scene.mRootNode->mChildren[0];
  aiNode* b = scene.mRootNode->mChildren[1];
  a->mParent = b->mParent = scene.mRootNode;
  a->mTransformation = to_ai(R_RA, Eigen::Vector3d::Zero());
  b->mTransformation = to_ai(M_RB, p_RB);
  a->mNumMeshes = b->mNumMeshes = 1;
  a->mMeshes = new unsigned[1]{0};
  b->mMeshes = new unsigned[1]{1};
  const std::string path = TempPath("two_nodes.glb");
  Assimp::Exporter exporter;
  ASSERT_EQ(exporter.Export(&scene, "glb2", path), aiReturn_SUCCESS) << exporter.GetErrorString();

  const TriangleMesh loaded = LoadMesh(path);
  ASSERT_EQ(loaded.triangles.size(), 24u);
  ASSERT_EQ(loaded.vertices.size(), 16u);
  for (int v = 0; v < 8; ++v) {
    const Eigen::Vector3d p = box.vertices[v].cast<float>().cast<double>();
    EXPECT_LT((loaded.vertices[v] - (p_FR + R_RA * p)).norm(), 1e-8) << v;
    EXPECT_LT((loaded.vertices[8 + v] - (p_FR + p_RB + M_RB * p)).norm(), 1e-8) << v;
  }
  // Mirrored, but its triangles turned back: both boxes enclose +6e-9 m³.
  EXPECT_TRUE(CalcEdgeTopology(loaded).closed());
  EXPECT_NEAR(CalcEnclosedVolume(loaded), 2 * 6e-9, 1e-14);
}

TEST(MeshIo, MissingFile) {
  const std::string path = TempPath("no_such_mesh.obj");
  EXPECT_EQ(LoadError(path), path + ": cannot open file");
}

TEST(MeshIo, CorruptFiles) {
  // A glTF binary header followed by junk, and a PLY whose header promises more than follows.
  const std::string glb = TempPath("corrupt.glb");
  WriteText(glb, std::string("glTF\x02\0\0\0", 8) + "this is not a glTF container at all");
  const std::string ply = TempPath("truncated.ply");
  WriteText(ply,
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
            "end_header\n0 0 0\n1 0\n");
  const std::string garbage = TempPath("garbage.obj");
  WriteText(garbage, "\x01\x02\x03 binary \xff\xfe junk");
  for (const std::string& path : {glb, ply, garbage}) {
    const std::string error = LoadError(path);
    EXPECT_EQ(error.rfind(path + ": ", 0), 0u) << error;
    EXPECT_GT(error.size(), path.size() + 2) << path;  // with a reason
  }
}

TEST(MeshIo, EmptyAndTriangleFreeFiles) {
  const std::string empty = TempPath("empty.obj");
  WriteText(empty, "");
  const std::string empty_error = LoadError(empty);
  EXPECT_EQ(empty_error.rfind(empty + ": ", 0), 0u) << empty_error;
  // Vertices and a line, no face.
  const std::string lines = TempPath("lines_only.obj");
  WriteText(lines, "v 0 0 0\nv 0.001 0 0\nv 0 0.001 0\nl 1 2 3\n");
  const std::string lines_error = LoadError(lines);
  EXPECT_EQ(lines_error.rfind(lines + ": ", 0), 0u) << lines_error;
  EXPECT_NE(lines_error.find("no triangles"), std::string::npos) << lines_error;
}

TEST(MeshIo, NonFiniteVertex) {
  const std::string path = TempPath("nan_vertex.ply");
  WriteText(path,
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
            "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
            "end_header\n0 0 0\n0.001 nan 0\n0 0.001 0\n3 0 1 2\n");
  const std::string error = LoadError(path);
  EXPECT_EQ(error.rfind(path + ": mesh 0", 0), 0u) << error;
  EXPECT_NE(error.find("vertex 1: non-finite coordinate"), std::string::npos) << error;
}

TEST(MeshIo, SaveRejectsWhatNoFileShouldHold) {
  TriangleMesh box = MakeBoxMesh({});
  EXPECT_THROW(SaveMesh(box, TempPath("box.stl")), std::invalid_argument);
  EXPECT_THROW(SaveMesh(TriangleMesh{}, TempPath("empty.obj")), std::invalid_argument);
  box.vertices[3].y() = std::nan("");
  EXPECT_THROW(SaveMesh(box, TempPath("nan.obj")), std::invalid_argument);
  EXPECT_THROW(SaveMesh(MakeBoxMesh({}), TempPath("no_such_dir/box.obj")), std::runtime_error);
}

}  // namespace
}  // namespace microdex::mesh
