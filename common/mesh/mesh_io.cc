#include "common/mesh/mesh_io.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

#include "common/base/input_error.h"

namespace microdex::mesh {
namespace {

constexpr double kGltfUnitsPerMetre = 1024;  // see SaveMesh

Eigen::Matrix4d ToEigen(const aiMatrix4x4& m) {
  Eigen::Matrix4d out;
  out << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3,
      m.d4;
  return out;
}

std::string MeshPlace(const aiMesh& mesh, unsigned index) {
  std::string place = "mesh " + std::to_string(index);
  if (mesh.mName.length > 0) place += " '" + std::string(mesh.mName.C_Str()) + "'";
  return place;
}

// Appends one assimp mesh, placed by X_FM (mesh node in file root frame).
void AppendAssimpMesh(const std::string& path, const aiMesh& am, unsigned index,
                      const Eigen::Matrix4d& X_FM, TriangleMesh& mesh, bool& all_have_normals) {
  const bool has_normals = am.mNormals != nullptr;
  all_have_normals = all_have_normals && has_normals;
  const Eigen::Matrix3d R = X_FM.topLeftCorner<3, 3>();
  const Eigen::Matrix3d normal_map = R.inverse().transpose();
  // Local vertex → merged vertex; bit-equal (position, normal) pairs join.
  std::map<std::array<float, 6>, int> joined;
  std::vector<int> merged_of(am.mNumVertices);
  for (unsigned v = 0; v < am.mNumVertices; ++v) {
    const aiVector3D& p = am.mVertices[v];
    const aiVector3D n = has_normals ? am.mNormals[v] : aiVector3D(0, 0, 0);
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      throw InputError(path, 0, MeshPlace(am, index) + " vertex " + std::to_string(v),
                       "non-finite coordinate");
    }
    const auto [it, inserted] =
        joined.try_emplace({p.x, p.y, p.z, n.x, n.y, n.z}, static_cast<int>(mesh.vertices.size()));
    merged_of[v] = it->second;
    if (!inserted) continue;
    const Eigen::Vector4d p_F = X_FM * Eigen::Vector4d(p.x, p.y, p.z, 1);
    if (!p_F.allFinite()) {
      throw InputError(path, 0, MeshPlace(am, index) + " vertex " + std::to_string(v),
                       "non-finite coordinate after the node transform");
    }
    mesh.vertices.push_back(p_F.head<3>());
    Eigen::Vector3d n_F = normal_map * Eigen::Vector3d(n.x, n.y, n.z);
    const double norm = n_F.norm();
    mesh.normals.push_back(norm > 0 && std::isfinite(norm) ? Eigen::Vector3d(n_F / norm)
                                                           : Eigen::Vector3d::Zero());
  }
  // A mirroring transform turns the winding: flip it back so outside stays outside.
  const bool mirrored = R.determinant() < 0;
  for (unsigned f = 0; f < am.mNumFaces; ++f) {
    const aiFace& face = am.mFaces[f];
    if (face.mNumIndices != 3) continue;  // points and lines carry no area
    Eigen::Vector3i t(merged_of[face.mIndices[0]], merged_of[face.mIndices[1]],
                      merged_of[face.mIndices[2]]);
    if (mirrored) std::swap(t[1], t[2]);
    mesh.triangles.push_back(t);
  }
}

void AppendNode(const std::string& path, const aiScene& scene, const aiNode& node,
                const Eigen::Matrix4d& X_FP, TriangleMesh& mesh, bool& all_have_normals) {
  const Eigen::Matrix4d X_FN = X_FP * ToEigen(node.mTransformation);
  for (unsigned k = 0; k < node.mNumMeshes; ++k) {
    const unsigned index = node.mMeshes[k];
    if (index >= scene.mNumMeshes) {
      throw InputError(path, 0, "node '" + std::string(node.mName.C_Str()) + "'",
                       "mesh index " + std::to_string(index) + " out of range");
    }
    AppendAssimpMesh(path, *scene.mMeshes[index], index, X_FN, mesh, all_have_normals);
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c) {
    AppendNode(path, scene, *node.mChildren[c], X_FN, mesh, all_have_normals);
  }
}

std::string LowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace

TriangleMesh LoadMesh(const std::string& path) {
  if (!std::ifstream(path).is_open() || std::filesystem::is_directory(path)) {
    throw InputError(path, 0, "", "cannot open file");
  }
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate);
  if (scene == nullptr) throw InputError(path, 0, "", importer.GetErrorString());
  if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0 || scene->mRootNode == nullptr) {
    throw InputError(path, 0, "", "no triangles (incomplete scene)");
  }
  TriangleMesh mesh;
  bool all_have_normals = true;
  AppendNode(path, *scene, *scene->mRootNode, Eigen::Matrix4d::Identity(), mesh, all_have_normals);
  if (mesh.triangles.empty()) throw InputError(path, 0, "", "no triangles");
  if (!all_have_normals) mesh.normals.clear();
  // Drop vertices no triangle uses (e.g. those of dropped lines), keeping the order.
  std::vector<int> new_index(mesh.vertices.size(), -1);
  for (const Eigen::Vector3i& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) new_index[t[k]] = 0;
  }
  int next = 0;
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (new_index[v] < 0) continue;
    new_index[v] = next;
    mesh.vertices[next] = mesh.vertices[v];
    if (!mesh.normals.empty()) mesh.normals[next] = mesh.normals[v];
    ++next;
  }
  mesh.vertices.resize(next);
  if (!mesh.normals.empty()) mesh.normals.resize(next);
  for (Eigen::Vector3i& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) t[k] = new_index[t[k]];
  }
  return mesh;
}

void SaveMesh(const TriangleMesh& mesh, const std::string& path) {
  const std::string ext = LowerExtension(path);
  const char* format = ext == ".obj"    ? "objnomtl"
                       : ext == ".ply"  ? "plyb"
                       : ext == ".glb"  ? "glb2"
                       : ext == ".gltf" ? "gltf2"
                                        : nullptr;
  if (format == nullptr) {
    throw std::invalid_argument(path + ": extension: expected .obj, .ply, .glb or .gltf");
  }
  if (mesh.triangles.empty()) throw std::invalid_argument(path + ": mesh: no triangles");
  const int n = static_cast<int>(mesh.vertices.size());
  for (int v = 0; v < n; ++v) {
    if (!mesh.vertices[v].allFinite()) {
      throw std::invalid_argument(path + ": vertex " + std::to_string(v) +
                                  ": non-finite coordinate");
    }
  }
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (mesh.triangles[t].minCoeff() < 0 || mesh.triangles[t].maxCoeff() >= n) {
      throw std::invalid_argument(path + ": triangle " + std::to_string(t) +
                                  ": index out of range");
    }
  }
  // Assimp's OBJ exporter always writes normals, making its own where there are none (and
  // badly, for shared vertices): give it the area-weighted ones.
  const std::vector<Eigen::Vector3d> normals = mesh.normals.size() == mesh.vertices.size()
                                                   ? mesh.normals
                                               : ext == ".obj" ? CalcVertexNormals(mesh)
                                                               : std::vector<Eigen::Vector3d>{};
  const bool with_normals = !normals.empty();
  // Assimp's glTF exporter joins vertices closer than 1e-5 (file units): at the micrometre
  // scale of a needle tip that closes holes and breaks the surface. For glTF the vertices are
  // stored in units of 1/1024 m under a root node scaling them back to metres (a power of two,
  // so both scalings are exact), which moves that threshold to 1e-8 m.
  const bool gltf = ext == ".glb" || ext == ".gltf";
  const double stored_per_m = gltf ? kGltfUnitsPerMetre : 1.0;

  // A one-mesh scene; the aiScene destructor frees what is allocated here.
  aiScene scene;
  scene.mRootNode = new aiNode("root");
  if (gltf) {
    const auto m_per_unit = static_cast<ai_real>(1.0 / kGltfUnitsPerMetre);
    aiMatrix4x4::Scaling(aiVector3D(m_per_unit, m_per_unit, m_per_unit),
                         scene.mRootNode->mTransformation);
  }
  scene.mRootNode->mNumMeshes = 1;
  scene.mRootNode->mMeshes = new unsigned[1]{0};
  scene.mNumMaterials = 1;
  scene.mMaterials = new aiMaterial* [1] { new aiMaterial() };
  scene.mNumMeshes = 1;
  scene.mMeshes = new aiMesh* [1] { new aiMesh() };
  aiMesh& am = *scene.mMeshes[0];
  am.mName = std::filesystem::path(path).stem().string();
  am.mMaterialIndex = 0;
  am.mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  am.mNumVertices = static_cast<unsigned>(n);
  am.mVertices = new aiVector3D[n];
  if (with_normals) am.mNormals = new aiVector3D[n];
  for (int v = 0; v < n; ++v) {
    const Eigen::Vector3d p = stored_per_m * mesh.vertices[v];
    am.mVertices[v] = aiVector3D(static_cast<ai_real>(p.x()), static_cast<ai_real>(p.y()),
                                 static_cast<ai_real>(p.z()));
    if (with_normals) {
      const Eigen::Vector3d& q = normals[v];
      am.mNormals[v] = aiVector3D(static_cast<ai_real>(q.x()), static_cast<ai_real>(q.y()),
                                  static_cast<ai_real>(q.z()));
    }
  }
  am.mNumFaces = static_cast<unsigned>(mesh.triangles.size());
  am.mFaces = new aiFace[am.mNumFaces];
  for (unsigned f = 0; f < am.mNumFaces; ++f) {
    aiFace& face = am.mFaces[f];
    face.mNumIndices = 3;
    face.mIndices = new unsigned[3];
    for (int k = 0; k < 3; ++k) face.mIndices[k] = static_cast<unsigned>(mesh.triangles[f][k]);
  }
  Assimp::Exporter exporter;
  if (exporter.Export(&scene, format, path) != aiReturn_SUCCESS) {
    throw std::runtime_error(path + ": cannot write mesh: " + exporter.GetErrorString());
  }
}

}  // namespace microdex::mesh
