// SPDX-License-Identifier: MIT
/// \file
/// load_mesh: reads a mesh file through assimp (by default OBJ with v/vt/vn, STL ASCII and
/// binary, PLY ASCII and binary, OFF; on request every triangle-bearing format assimp reads:
/// glTF, COLLADA, ...) into one TriangleMesh. Part of the
/// separate target impact::io (links assimp); the core never includes it. Every failure (missing
/// or unreadable file, parse error, no triangles, non-finite coordinates, bad indices) is reported
/// as impact::InvalidInput naming the file and the reason.
#pragma once

#include "impact/core/error.hpp"
#include "impact/geometry/triangle_mesh.hpp"
#include "impact/io/file_checks.hpp"

#include <assimp/BaseImporter.h>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace impact {

/// Options of load_mesh.
struct LoadOptions {
  /// true: weld vertices whose final positions (after node transforms, in the scalar S) are
  /// exactly equal, so a closed surface comes out closed even where the file splits vertices at
  /// UV or normal seams. false: keep assimp's vertices, which are joined only where position and
  /// every attribute (UV, normal, ...) agree, and so stay split at seams.
  bool merge_duplicate_vertices = true;
  /// true: place each mesh by the accumulated transform of the scene node(s) that reference it
  /// (a mesh referenced by several nodes appears once per reference; one no node references is
  /// left out). false: use the raw mesh coordinates, one copy per mesh of the file.
  bool apply_node_transforms = true;
  /// false: read only the formats of default_mesh_formats() (PLY, OFF and STL, checked before
  /// assimp sees them, and the readers that survived fuzzing); any other format throws
  /// InvalidInput. true: also every other format assimp reads, for TRUSTED files only: assimp
  /// 5.2's readers of many formats (ASE, X, glTF, ...) crash, hang or allocate without bound on
  /// hostile input (tests/fuzz/fuzz_load_mesh.cpp finds such files within seconds).
  bool allow_unchecked_formats = false;
};

/// The formats (file extensions) load_mesh reads by default: ply, off and stl, checked by
/// io/file_checks.hpp before assimp, and obj. Files named otherwise need
/// LoadOptions::allow_unchecked_formats, except .txt, .dat and unnamed files whose bytes start
/// like PLY, OFF or ASCII STL, which are read as those.
inline const std::vector<std::string>& default_mesh_formats() {
  static const std::vector<std::string> formats = {"obj", "ply", "off", "stl"};
  return formats;
}

namespace detail::loader {

[[noreturn]] inline void fail(const std::string& path, const std::string& why) {
  throw InvalidInput("load_mesh: '" + path + "': " + why);
}

/// Hash of the bit patterns of three scalars (callers normalise -0 to +0 first).
template <class S> struct PositionHash {
  std::size_t operator()(const std::array<S, 3>& p) const {
    std::uint64_t h = 0xcbf29ce484222325ull;
    for (const S x : p) {
      std::uint64_t bits = 0;
      std::memcpy(&bits, &x, sizeof(S));
      h ^= bits + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    }
    return static_cast<std::size_t>(h);
  }
};

inline Eigen::Matrix4d to_eigen(const aiMatrix4x4& m) {
  Eigen::Matrix4d e;
  e << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3, m.d4;
  return e;
}

/// The (mesh index, world transform) pairs to emit, in a depth-first walk of the node tree.
inline std::vector<std::pair<unsigned, Eigen::Matrix4d>> mesh_instances(const aiScene& scene, bool apply_transforms) {
  std::vector<std::pair<unsigned, Eigen::Matrix4d>> out;
  if (!apply_transforms || scene.mRootNode == nullptr) {
    for (unsigned i = 0; i < scene.mNumMeshes; ++i) out.emplace_back(i, Eigen::Matrix4d::Identity());
    return out;
  }
  std::vector<std::pair<const aiNode*, Eigen::Matrix4d>> stack{{scene.mRootNode, to_eigen(scene.mRootNode->mTransformation)}};
  while (!stack.empty()) {
    const auto [node, M] = stack.back();
    stack.pop_back();
    for (unsigned i = 0; i < node->mNumMeshes; ++i)
      if (node->mMeshes[i] < scene.mNumMeshes) out.emplace_back(node->mMeshes[i], M);
    // push children in reverse so they are visited in file order
    for (unsigned c = node->mNumChildren; c-- > 0;) {
      const aiNode* child = node->mChildren[c];
      if (child != nullptr) stack.emplace_back(child, M * to_eigen(child->mTransformation));
    }
  }
  return out;
}

/// Unregisters from `importer` every reader that does not list `format` among its extensions, so
/// that assimp cannot hand the file to another reader by its content (it does so when the
/// extension's readers decline it, or when several readers claim the extension). The removed
/// readers are owned by `removed`.
inline void keep_only_readers_of(Assimp::Importer& importer, const std::string& format,
                                 std::vector<std::unique_ptr<Assimp::BaseImporter>>& removed) {
  for (std::size_t i = importer.GetImporterCount(); i-- > 0;) {
    const aiImporterDesc* desc = importer.GetImporterInfo(i);
    bool keep = false;
    if (desc != nullptr && desc->mFileExtensions != nullptr) {
      std::istringstream words(desc->mFileExtensions);
      for (std::string w; words >> w;) keep = keep || w == format;
    }
    if (keep) continue;
    Assimp::BaseImporter* reader = importer.GetImporter(i);
    if (reader != nullptr && importer.UnregisterLoader(reader) == aiReturn_SUCCESS) removed.emplace_back(reader);
  }
}

}  // namespace detail::loader

/// Loads every triangle of the file at `path` into one mesh of scalar S (float or double): all
/// meshes of the scene, each under its node transform (see LoadOptions), concatenated in a
/// depth-first walk of the scene graph; polygons are triangulated by assimp, point and line
/// primitives are ignored, and vertices no triangle uses are dropped. Zero-area triangles are
/// kept. Winding is the file's. Coordinates pass through assimp's ai_real, which is float in the
/// usual (and Debian's) builds, so a double mesh carries float-rounded values. With
/// merge_duplicate_vertices (the default) exactly equal positions are welded: Keenan Crane's
/// spot.obj gives its 2,930 vertices, where assimp's seam-split vertices number 3,225 (and
/// `assimp info`, with more post-processing, reports 3,441).
///
/// Formats: see LoadOptions::allow_unchecked_formats and default_mesh_formats(). The format is the
/// extension when assimp has a reader for it, else the file's first bytes (PLY, OFF, ASCII STL);
/// only the readers of that format are kept, so assimp cannot divert the file to another reader.
///
/// The result passes validate_mesh. Throws InvalidInput, with the path and the reason in the
/// message, when the format is not read (by default: not OBJ, PLY, OFF or STL), when the file does not exist, is not a regular file, cannot be read, is empty, cannot
/// be parsed (assimp's error text is included), contains no triangles, has a NaN or infinite
/// coordinate (or one that overflows S), has a face index out of range, or holds more than INT_MAX
/// vertices or triangles. PLY, OFF and STL files (recognised by their bytes as well as their name,
/// since assimp reads .txt, .dat or unnamed files by content) are checked before assimp sees them
/// (io/file_checks.hpp): they are rejected when cut short of what their header or syntax declares,
/// when a declared count exceeds what the file's size can hold, when their header is malformed or
/// holds stray control bytes, when a face has an empty index list (or, in OFF, more than 9
/// corners), and when a non-numeric token stands where a number is due; a PLY file read as .ply
/// must start with a line "ply", and assimp reads its header without the comment, obj_info and
/// blank lines (assimp 5.2 misreads properties listed after one). A text file cut at a line
/// boundary that is still a valid file (OBJ declares no counts) cannot be told from a complete
/// one. Never prints. Cost: one pass of the checks and of assimp plus O(triangles) expected time
/// for welding; about 0.1 s for 270k triangles.
template <class S> TriangleMesh<S> load_mesh(const std::string& path, const LoadOptions& options = {}) {
  static_assert(is_supported_scalar_v<S>, "load_mesh: S must be float or double");
  namespace fs = std::filesystem;
  if (path.empty()) detail::loader::fail(path, "empty path");
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) detail::loader::fail(path, "file does not exist");
  if (fs::is_directory(st)) detail::loader::fail(path, "is a directory, not a mesh file");
  if (!std::ifstream(path, std::ios::binary).good()) detail::loader::fail(path, "file cannot be opened for reading");
  if (fs::is_regular_file(st) && fs::file_size(path, ec) == 0 && !ec) detail::loader::fail(path, "file is empty");

  // The format: the extension when assimp has a reader for it, else the first bytes (assimp
  // would guess from them too, among all of its readers).
  Assimp::Importer importer;
  std::string ext = detail::mesh_file::extension_of(path);
  const bool by_extension = !ext.empty() && importer.IsExtensionSupported("." + ext);
  std::string bytes;
  std::string format = ext;
  if (!by_extension || ext == "ply" || ext == "off" || ext == "stl") {
    bytes = detail::mesh_file::read_all_bytes(path);
    if (!by_extension) format = detail::mesh_file::sniff_format(bytes);
  }
  const auto& defaults = default_mesh_formats();
  const bool checked = format == "ply" || format == "off" || format == "stl";
  if (!options.allow_unchecked_formats && std::find(defaults.begin(), defaults.end(), format) == defaults.end()) {
    if (format.empty())
      detail::loader::fail(path, "unknown format: the bytes are not PLY, OFF or ASCII STL and the extension is not a mesh format's");
    detail::loader::fail(path, "format '." + format +
                                   "' is not read by default (assimp's reader of it is not safe on hostile files); set "
                                   "LoadOptions::allow_unchecked_formats for trusted files");
  }
  // PLY, OFF and STL defects assimp would hang, abort or allocate on, or hide
  if (checked) detail::mesh_file::check_format(path, bytes, format, by_extension);
  // only the readers of the format: assimp cannot divert the file to another reader
  std::vector<std::unique_ptr<Assimp::BaseImporter>> removed;
  if (!format.empty()) detail::loader::keep_only_readers_of(importer, format, removed);

  // No JoinIdenticalVertices when welding by position ourselves: it would only cost time.
  unsigned flags = aiProcess_Triangulate | aiProcess_ValidateDataStructure;
  if (!options.merge_duplicate_vertices) flags |= aiProcess_JoinIdenticalVertices;
  const aiScene* scene = nullptr;
  try {
    // checked formats: assimp parses the very bytes that were checked (a PLY header as the check
    // understood it: io/detail/ply_check.hpp)
    scene = checked ? importer.ReadFileFromMemory(bytes.data(), bytes.size(), flags, format.c_str())
                    : importer.ReadFile(path, flags);
  } catch (const std::exception& e) {
    detail::loader::fail(path, std::string("cannot be parsed: ") + e.what());
  } catch (...) {
    detail::loader::fail(path, "cannot be parsed: unknown error inside assimp");
  }
  if (scene == nullptr) {
    const std::string err = importer.GetErrorString();
    detail::loader::fail(path, "cannot be parsed: " + (err.empty() ? std::string("assimp returned no scene") : err));
  }
  if (scene->mNumMeshes == 0 || scene->mMeshes == nullptr)
    detail::loader::fail(path, "contains no triangles (no meshes in the file)");

  std::vector<S> coords;  // x y z per output vertex
  std::vector<int> faces;  // 3 per output triangle
  std::unordered_map<std::array<S, 3>, int, detail::loader::PositionHash<S>> welded;
  std::vector<int> local;  // per-instance map from assimp vertex index to output vertex, -1 = not yet
  const auto instances = detail::loader::mesh_instances(*scene, options.apply_node_transforms);
  std::size_t point_or_line_faces = 0;
  for (std::size_t inst = 0; inst < instances.size(); ++inst) {
    const unsigned mi = instances[inst].first;
    const Eigen::Matrix4d& M = instances[inst].second;
    const aiMesh* mesh = scene->mMeshes[mi];
    if (mesh == nullptr || mesh->mFaces == nullptr || mesh->mVertices == nullptr) continue;
    local.assign(mesh->mNumVertices, -1);
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) {
        ++point_or_line_faces;  // points and lines (polygons were triangulated)
        continue;
      }
      for (unsigned k = 0; k < 3; ++k) {
        const unsigned vi = face.mIndices[k];
        if (vi >= mesh->mNumVertices)
          detail::loader::fail(path, "mesh " + std::to_string(mi) + " face " + std::to_string(f) + " has vertex index " +
                                       std::to_string(vi) + " out of range [0, " + std::to_string(mesh->mNumVertices) + ")");
        int& out = local[vi];
        if (out < 0) {
          const aiVector3D& v = mesh->mVertices[vi];
          const Eigen::Vector4d p = M * Eigen::Vector4d(double(v.x), double(v.y), double(v.z), 1.0);
          const std::array<S, 3> q{static_cast<S>(p[0]) + S(0), static_cast<S>(p[1]) + S(0), static_cast<S>(p[2]) + S(0)};
          if (!all_finite(Vec3<S>(q[0], q[1], q[2])))
            detail::loader::fail(path, "mesh " + std::to_string(mi) + " vertex " + std::to_string(vi) +
                                         " has a NaN or infinite coordinate (or one too large for the scalar type)");
          if (coords.size() / 3 >= static_cast<std::size_t>(INT_MAX)) detail::loader::fail(path, "more than INT_MAX vertices");
          const int next = static_cast<int>(coords.size() / 3);
          if (options.merge_duplicate_vertices) {
            // q holds +0 for -0 (x + 0 == +0 for x == -0), so equal positions hash equally.
            const auto [it, inserted] = welded.emplace(q, next);
            out = it->second;
            if (!inserted) continue;
          } else {
            out = next;
          }
          coords.insert(coords.end(), q.begin(), q.end());
        }
      }
      if (faces.size() / 3 >= static_cast<std::size_t>(INT_MAX)) detail::loader::fail(path, "more than INT_MAX triangles");
      for (unsigned k = 0; k < 3; ++k) faces.push_back(local[face.mIndices[k]]);
    }
  }
  if (faces.empty())
    detail::loader::fail(path, point_or_line_faces ? "contains no triangles (only points or lines)" : "contains no triangles");

  TriangleMesh<S> result;
  result.V = Eigen::Map<const Vertices<S>>(coords.data(), static_cast<Eigen::Index>(coords.size() / 3), 3);
  result.F = Eigen::Map<const Faces>(faces.data(), static_cast<Eigen::Index>(faces.size() / 3), 3);
  validate_mesh(result, "load_mesh: '" + path + "'");
  return result;
}

}  // namespace impact
