// SPDX-License-Identifier: MIT
// load_mesh: every mesh of the data folder with its triangle and welded vertex counts (and the
// closed ones closed and outward after welding); files the test writes itself (OBJ with v/vt/vn
// and polygons, STL ASCII and binary, PLY ASCII and binary, OFF, glTF with node transforms) give
// back exactly the triangles written; vertex welding; write_obj round trips; and bad files
// (missing, directory, empty, garbage, truncated, NaN/Inf, bad indices, points or lines only)
// throw InvalidInput whose message names the file and the reason.
#include "impact/geometry/mesh_generators.hpp"
#include "impact/io/load_mesh.hpp"
#include "impact/io/write_obj.hpp"
#include "support/data.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include <unistd.h>

using namespace impact;
namespace fs = std::filesystem;

#include "support/sanitizer.hpp"
#if IMPACT_TEST_SANITIZED
// assimp 5.2 leaks memory on some of its own error paths (the mutated files below reach them).
// The leaks are inside libassimp, not in impact: LeakSanitizer is told to ignore that module.
extern "C" __attribute__((used)) const char* __lsan_default_suppressions() { return "leak:libassimp.so\n"; }
#endif

namespace {

/// Loads `path`: either a valid mesh (counted in loaded) or InvalidInput whose message names the
/// path (counted in rejected); any other outcome fails the test.
template <class S> void load_or_reject(const std::string& path, int& loaded, int& rejected) {
  try {
    const auto m = load_mesh<S>(path);
    EXPECT_NO_THROW(validate_mesh(m)) << path;
    ++loaded;
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    ++rejected;
  } catch (const std::exception& e) {
    ADD_FAILURE() << path << ": unexpected exception type: " << e.what();
  }
}


// ---------------------------------------------------------------------------------------------
// helpers

/// A fresh folder under the system temp dir, removed with the object.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string("impact-io-") + std::to_string(::getpid()) + "-" + info->test_suite_name() + "-" + info->name();
    std::replace(name.begin(), name.end(), '/', '_');
    dir_ = fs::temp_directory_path() / name;
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string path(const std::string& file) const { return (dir_ / file).string(); }
  std::string write(const std::string& file, const std::string& bytes) const {
    std::ofstream(path(file), std::ios::binary) << bytes;
    return path(file);
  }

 private:
  fs::path dir_;
};

void append_u32(std::string& s, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) s.push_back(static_cast<char>((v >> (8 * i)) & 0xffu));
}
void append_f32(std::string& s, float f) {
  std::uint32_t u = 0;
  std::memcpy(&u, &f, 4);
  append_u32(s, u);
}

std::string base64(const std::string& in) {
  static const char* abc = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const std::uint32_t n = (std::uint32_t(std::uint8_t(in[i])) << 16) | (std::uint32_t(std::uint8_t(in[i + 1])) << 8) | std::uint8_t(in[i + 2]);
    for (int k = 3; k >= 0; --k) out.push_back(abc[(n >> (6 * k)) & 63u]);
  }
  if (i < in.size()) {
    std::uint32_t n = std::uint32_t(std::uint8_t(in[i])) << 16;
    if (i + 1 < in.size()) n |= std::uint32_t(std::uint8_t(in[i + 1])) << 8;
    out.push_back(abc[(n >> 18) & 63u]);
    out.push_back(abc[(n >> 12) & 63u]);
    out.push_back(i + 1 < in.size() ? abc[(n >> 6) & 63u] : '=');
    out.push_back('=');
  }
  return out;
}

using Tri = std::array<std::array<double, 3>, 3>;

/// Triangles as coordinate triples, each rotated to start at its smallest corner (winding kept),
/// sorted: equal sets mean the same triangles with the same orientation.
template <class S> std::vector<Tri> triangle_set(const TriangleMesh<S>& m) {
  std::vector<Tri> out;
  for (int t = 0; t < m.num_triangles(); ++t) {
    Tri tri;
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) tri[k][d] = double(m.V(m.F(t, k), d));
    std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
    out.push_back(tri);
  }
  std::sort(out.begin(), out.end());
  return out;
}

template <class S> double signed_volume(const TriangleMesh<S>& m) {
  double v = 0;
  for (int t = 0; t < m.num_triangles(); ++t) {
    const auto tri = m.triangle(t).template cast<double>();
    v += tri.a.dot(tri.b.cross(tri.c)) / 6.0;
  }
  return v;
}

/// Every directed edge used once and its reverse once: closed and consistently oriented.
bool closed_and_oriented(const Faces& F) {
  std::map<std::pair<int, int>, int> directed;
  for (Eigen::Index t = 0; t < F.rows(); ++t)
    for (int k = 0; k < 3; ++k) ++directed[{F(t, k), F(t, (k + 1) % 3)}];
  for (const auto& [e, n] : directed) {
    const auto rev = directed.find({e.second, e.first});
    if (n != 1 || rev == directed.end() || rev->second != 1) return false;
  }
  return true;
}

/// Expects load_mesh<S>(path) to throw InvalidInput naming the path and containing `reason`.
template <class S = double> void expect_invalid(const std::string& path, const std::string& reason) {
  SCOPED_TRACE(path);
  try {
    const auto m = load_mesh<S>(path);
    ADD_FAILURE() << "no exception; loaded " << m.num_vertices() << " vertices, " << m.num_triangles() << " triangles";
  } catch (const InvalidInput& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << "message does not name the file: " << msg;
    EXPECT_NE(msg.find(reason), std::string::npos) << "message lacks '" << reason << "': " << msg;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
  }
}

// The reference mesh the format tests write: a box with distinct corners (12 triangles).
TriangleMesh<double> reference_box() { return make_box<double>(Eigen::Vector3d(1.0, 2.0, 0.5)); }

std::string as_obj(const TriangleMesh<double>& m) {
  std::string s = "# box\n";
  for (int i = 0; i < m.num_vertices(); ++i)
    s += "v " + std::to_string(m.V(i, 0)) + " " + std::to_string(m.V(i, 1)) + " " + std::to_string(m.V(i, 2)) + "\n";
  for (int t = 0; t < m.num_triangles(); ++t)
    s += "f " + std::to_string(m.F(t, 0) + 1) + " " + std::to_string(m.F(t, 1) + 1) + " " + std::to_string(m.F(t, 2) + 1) + "\n";
  return s;
}

std::string as_stl_ascii(const TriangleMesh<double>& m) {
  std::string s = "solid box\n";
  for (int t = 0; t < m.num_triangles(); ++t) {
    const Eigen::Vector3d n = m.triangle(t).normal();
    s += "  facet normal " + std::to_string(n.x()) + " " + std::to_string(n.y()) + " " + std::to_string(n.z()) + "\n    outer loop\n";
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d v = m.vertex(m.F(t, k));
      s += "      vertex " + std::to_string(v.x()) + " " + std::to_string(v.y()) + " " + std::to_string(v.z()) + "\n";
    }
    s += "    endloop\n  endfacet\n";
  }
  return s + "endsolid box\n";
}

std::string as_stl_binary(const TriangleMesh<double>& m) {
  std::string s(80, ' ');
  append_u32(s, static_cast<std::uint32_t>(m.num_triangles()));
  for (int t = 0; t < m.num_triangles(); ++t) {
    const Eigen::Vector3d n = m.triangle(t).normal();
    for (int d = 0; d < 3; ++d) append_f32(s, float(n[d]));
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 3; ++d) append_f32(s, float(m.V(m.F(t, k), d)));
    s += std::string(2, '\0');
  }
  return s;
}

std::string ply_header(const std::string& format, int nv, int nf) {
  return "ply\nformat " + format + " 1.0\ncomment written by test_load_mesh\nelement vertex " + std::to_string(nv) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " + std::to_string(nf) +
         "\nproperty list uchar int vertex_indices\nend_header\n";
}

std::string as_ply_ascii(const TriangleMesh<double>& m) {
  std::string s = ply_header("ascii", m.num_vertices(), m.num_triangles());
  for (int i = 0; i < m.num_vertices(); ++i)
    s += std::to_string(m.V(i, 0)) + " " + std::to_string(m.V(i, 1)) + " " + std::to_string(m.V(i, 2)) + "\n";
  for (int t = 0; t < m.num_triangles(); ++t)
    s += "3 " + std::to_string(m.F(t, 0)) + " " + std::to_string(m.F(t, 1)) + " " + std::to_string(m.F(t, 2)) + "\n";
  return s;
}

std::string as_ply_binary(const TriangleMesh<double>& m) {
  std::string s = ply_header("binary_little_endian", m.num_vertices(), m.num_triangles());
  for (int i = 0; i < m.num_vertices(); ++i)
    for (int d = 0; d < 3; ++d) append_f32(s, float(m.V(i, d)));
  for (int t = 0; t < m.num_triangles(); ++t) {
    s.push_back(3);
    for (int k = 0; k < 3; ++k) append_u32(s, static_cast<std::uint32_t>(m.F(t, k)));
  }
  return s;
}

std::string as_off(const TriangleMesh<double>& m) {
  std::string s = "OFF\n# a comment\n" + std::to_string(m.num_vertices()) + " " + std::to_string(m.num_triangles()) + " 0\n";
  for (int i = 0; i < m.num_vertices(); ++i)
    s += std::to_string(m.V(i, 0)) + " " + std::to_string(m.V(i, 1)) + " " + std::to_string(m.V(i, 2)) + "\n";
  for (int t = 0; t < m.num_triangles(); ++t)
    s += "3 " + std::to_string(m.F(t, 0)) + " " + std::to_string(m.F(t, 1)) + " " + std::to_string(m.F(t, 2)) + "\n";
  return s;
}

// ---------------------------------------------------------------------------------------------
// the data folder

struct DataMesh {
  const char* file;
  int triangles;
  int welded_vertices;  // exactly equal positions merged, unreferenced vertices dropped
  bool closed;          // closed, manifold and outward-oriented after welding
};

void PrintTo(const DataMesh& d, std::ostream* os) { *os << d.file; }

// Counts from the data folder's README (stanford-bunny: 34,834 referenced of 35,947 vertices;
// ogre: 62,194 vertices with 9 duplicate positions).
const DataMesh kDataMeshes[] = {
    {"knight.off", 1000, 502, true},           {"spot.obj", 5856, 2930, true},
    {"teapot.obj", 6320, 3241, false},         {"stanford-bunny.obj", 69451, 34834, false},
    {"armadillo.obj", 99994, 49999, true},     {"ogre.obj", 124008, 62185, false},
    {"igea.ply", 268686, 134345, true},        {"env.obj", 2180, 2072, false},
    {"rob.obj", 216, 141, false},
};

class DataMeshes : public ::testing::TestWithParam<DataMesh> {};

TEST_P(DataMeshes, LoadsWithTheExpectedCounts) {
  const DataMesh& d = GetParam();
  IMPACT_REQUIRE_DATA(path, std::string("meshes/") + d.file);
  const auto m = load_mesh<double>(path);
  EXPECT_EQ(m.num_triangles(), d.triangles);
  EXPECT_EQ(m.num_vertices(), d.welded_vertices);
  EXPECT_NO_THROW(validate_mesh(m));
  // every vertex is used, and no two vertices share a position
  std::vector<char> used(static_cast<std::size_t>(m.num_vertices()), 0);
  for (Eigen::Index t = 0; t < m.F.rows(); ++t)
    for (int k = 0; k < 3; ++k) used[static_cast<std::size_t>(m.F(t, k))] = 1;
  EXPECT_EQ(std::count(used.begin(), used.end(), 1), m.num_vertices());
  std::set<std::array<double, 3>> positions;
  for (int i = 0; i < m.num_vertices(); ++i) positions.insert({m.V(i, 0), m.V(i, 1), m.V(i, 2)});
  EXPECT_EQ(static_cast<int>(positions.size()), m.num_vertices());
  if (d.closed) {
    EXPECT_TRUE(closed_and_oriented(m.F));
    EXPECT_GT(signed_volume(m), 0.0);
  }
  // float gives the same topology and the same (float-precision) coordinates
  const auto mf = load_mesh<float>(path);
  EXPECT_EQ(mf.F, m.F);
  EXPECT_EQ(mf.V.cast<double>(), m.V);
}

INSTANTIATE_TEST_SUITE_P(Meshes, DataMeshes, ::testing::ValuesIn(kDataMeshes), [](const ::testing::TestParamInfo<DataMesh>& param_info) {
  std::string name = param_info.param.file;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
});

TEST(LoadMesh, SpotWithoutMergingKeepsAssimpsSeamSplits) {
  IMPACT_REQUIRE_DATA(path, "meshes/spot.obj");
  LoadOptions raw;
  raw.merge_duplicate_vertices = false;
  const auto split = load_mesh<double>(path, raw);
  const auto welded = load_mesh<double>(path);
  EXPECT_EQ(split.num_triangles(), 5856);
  EXPECT_GT(split.num_vertices(), 2930);  // split at UV seams
  EXPECT_EQ(welded.num_vertices(), 2930);
  EXPECT_FALSE(closed_and_oriented(split.F));  // the seams open the surface
  EXPECT_TRUE(closed_and_oriented(welded.F));
  EXPECT_EQ(triangle_set(split), triangle_set(welded));
}

// ---------------------------------------------------------------------------------------------
// files written here

template <class S> void expect_same_triangles(const TriangleMesh<S>& got, const TriangleMesh<double>& want) {
  ASSERT_EQ(got.num_triangles(), want.num_triangles());
  EXPECT_EQ(got.num_vertices(), want.num_vertices());
  EXPECT_NO_THROW(validate_mesh(got));
  const auto a = triangle_set(got), b = triangle_set(want.cast<float>());  // files carry float values
  EXPECT_EQ(a, b);
  EXPECT_TRUE(closed_and_oriented(got.F));
  EXPECT_NEAR(signed_volume(got), signed_volume(want), 1e-5);
}

template <class S> class WrittenFiles : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(WrittenFiles, Scalars);

TYPED_TEST(WrittenFiles, EveryFormatGivesBackTheBox) {
  using S = TypeParam;
  TempDir tmp;
  const auto box = reference_box();
  const std::pair<std::string, std::string> files[] = {
      {"box.obj", as_obj(box)},          {"box.stl", as_stl_ascii(box)},       {"box_binary.stl", as_stl_binary(box)},
      {"box.ply", as_ply_ascii(box)},    {"box_binary.ply", as_ply_binary(box)}, {"box.off", as_off(box)},
  };
  for (const auto& [name, bytes] : files) {
    SCOPED_TRACE(name);
    expect_same_triangles(load_mesh<S>(tmp.write(name, bytes)), box);
  }
}

TYPED_TEST(WrittenFiles, ObjWithUvNormalsAndPolygons) {
  using S = TypeParam;
  TempDir tmp;
  // a unit cube as six quads with per-corner UVs and normals (v/vt/vn), one face as v//vn and one
  // as v/vt: assimp splits vertices by attribute, welding brings back the 8 corners
  std::string obj = "o cube\n";
  for (int k = 0; k < 8; ++k)
    obj += "v " + std::to_string(k & 1) + " " + std::to_string((k >> 1) & 1) + " " + std::to_string((k >> 2) & 1) + "\n";
  obj += "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
  obj += "vn -1 0 0\nvn 1 0 0\nvn 0 -1 0\nvn 0 1 0\nvn 0 0 -1\nvn 0 0 1\n";
  obj += "f 1/1/1 5/2/1 7/3/1 3/4/1\n"   // -x
         "f 2/1/2 4/2/2 8/3/2 6/4/2\n"   // +x
         "f 1/1/3 2/2/3 6/3/3 5/4/3\n"   // -y
         "f 3/1/4 7/2/4 8/3/4 4/4/4\n"   // +y
         "f 1//5 3//5 4//5 2//5\n"       // -z
         "f 5/1 6/2 8/3 7/4\n";          // +z
  const std::string path = tmp.write("cube.obj", obj);
  const auto m = load_mesh<S>(path);
  EXPECT_EQ(m.num_triangles(), 12);
  EXPECT_EQ(m.num_vertices(), 8);
  EXPECT_TRUE(closed_and_oriented(m.F));
  EXPECT_NEAR(signed_volume(m), 1.0, 1e-6);
  LoadOptions raw;
  raw.merge_duplicate_vertices = false;
  const auto split = load_mesh<S>(path, raw);
  EXPECT_EQ(split.num_triangles(), 12);
  EXPECT_GT(split.num_vertices(), 8);
  EXPECT_EQ(triangle_set(split), triangle_set(m));
}

TYPED_TEST(WrittenFiles, SeveralObjectsAreConcatenated) {
  using S = TypeParam;
  TempDir tmp;
  const std::string path = tmp.write("two.obj",
                                     "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
                                     "o b\nv 0 0 5\nv 1 0 5\nv 0 1 5\nv 1 1 5\nf 4 5 7\nf 5 6 7\n"
                                     "o c\nv 0 0 0\nv 0 0 9\nl 1 8\n");  // a line-only object: ignored
  const auto m = load_mesh<S>(path);
  EXPECT_EQ(m.num_triangles(), 3);
  EXPECT_EQ(m.num_vertices(), 7);
  EXPECT_EQ(m.V.col(2).maxCoeff(), S(5));  // the line's (0, 0, 9) is dropped
}

TYPED_TEST(WrittenFiles, GltfNodeTransformsAreApplied) {
  using S = TypeParam;
  TempDir tmp;
  // one triangle mesh used by two nodes: translated by (10, 0, 0), and scaled by 2 around a child
  // translated by (0, 5, 0) (world = 2 * (p + (0, 5, 0)))
  std::string buffer;
  for (std::uint16_t i : {0, 1, 2, 0}) {
    buffer.push_back(static_cast<char>(i & 0xff));
    buffer.push_back(static_cast<char>(i >> 8));
  }
  for (float f : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) append_f32(buffer, f);
  const std::string gltf = R"({
  "asset": {"version": "2.0"},
  "scene": 0,
  "scenes": [{"nodes": [0, 1]}],
  "nodes": [{"mesh": 0, "translation": [10, 0, 0]}, {"scale": [2, 2, 2], "children": [2]},
            {"mesh": 0, "translation": [0, 5, 0]}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 1}, "indices": 0}]}],
  "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,)" +
                           base64(buffer) + R"("}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 6}, {"buffer": 0, "byteOffset": 8, "byteLength": 36}],
  "accessors": [{"bufferView": 0, "componentType": 5123, "count": 3, "type": "SCALAR"},
                {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}]
})";
  const std::string path = tmp.write("two_instances.gltf", gltf);
  // glTF is not read by default (assimp's reader is not safe on hostile files); this file is ours
  expect_invalid<S>(path, "not read by default");
  LoadOptions trusted;
  trusted.allow_unchecked_formats = true;
  const auto m = load_mesh<S>(path, trusted);
  ASSERT_EQ(m.num_triangles(), 2);
  TriangleMesh<double> want;
  want.V.resize(6, 3);
  want.V << 10, 0, 0, 11, 0, 0, 10, 1, 0, 0, 10, 0, 2, 10, 0, 0, 12, 0;
  want.F.resize(2, 3);
  want.F << 0, 1, 2, 3, 4, 5;
  EXPECT_EQ(triangle_set(m), triangle_set(want));

  LoadOptions raw = trusted;
  raw.apply_node_transforms = false;
  const auto local = load_mesh<S>(path, raw);
  ASSERT_EQ(local.num_triangles(), 1);
  EXPECT_EQ(local.V.cwiseAbs().maxCoeff(), S(1));
}

TYPED_TEST(WrittenFiles, WeldingMergesExactlyEqualPositionsOnly) {
  using S = TypeParam;
  TempDir tmp;
  // two triangles of a quad with their own copies of the shared corners (one written as -0), and
  // a third triangle 1e-6 away from sharing: only exact equality welds
  const std::string path = tmp.write("soup.obj",
                                     "v 0 0 0\nv 1 0 0\nv 1 1 0\n"
                                     "v -0 0 0\nv 1 1 0\nv 0 1 0\n"
                                     "v 0.000001 1 0\nv 0 2 0\nv 0 1 1\n"
                                     "vt 0 0\nvt 1 0\nvt 1 1\nvt 0.5 0.5\n"
                                     "f 1/1 2/2 3/3\nf 4/4 5/4 6/4\nf 7 8 9\n");
  const auto m = load_mesh<S>(path);
  EXPECT_EQ(m.num_triangles(), 3);
  EXPECT_EQ(m.num_vertices(), 7);
  EXPECT_EQ(m.F(1, 0), m.F(0, 0));  // -0 welded with +0
  EXPECT_EQ(m.F(1, 1), m.F(0, 2));
  LoadOptions raw;
  raw.merge_duplicate_vertices = false;
  EXPECT_EQ(load_mesh<S>(path, raw).num_vertices(), 9);  // different UVs keep the copies apart
}

TYPED_TEST(WrittenFiles, ZeroAreaTrianglesAreKept) {
  using S = TypeParam;
  TempDir tmp;
  const auto m = load_mesh<S>(tmp.write("degenerate.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 1 4\nf 1 2 4\n"));
  EXPECT_EQ(m.num_triangles(), 3);
  EXPECT_EQ(m.num_vertices(), 4);
  EXPECT_EQ(m.triangle(0).area(), S(0));
}

TYPED_TEST(WrittenFiles, WriteObjRoundTrip) {
  using S = TypeParam;
  TempDir tmp;
  const auto torus = make_torus<S>(S(1), S(0.25), 40, 16);
  const std::string path = tmp.path("torus.obj");
  write_obj(path, torus);
  const auto back = load_mesh<S>(path);
  ASSERT_EQ(back.num_triangles(), torus.num_triangles());
  EXPECT_EQ(back.num_vertices(), torus.num_vertices());
  // triangles keep their order and corners; vertices are renumbered by first use; assimp's text
  // parser is not correctly rounded for tiny values (1e-17 comes back slightly off), hence the tolerance
  for (int t = 0; t < torus.num_triangles(); ++t)
    for (int k = 0; k < 3; ++k)
      EXPECT_LE(double((back.vertex(back.F(t, k)) - torus.vertex(torus.F(t, k))).norm()), 1e-6) << t;  // assimp parses to float
  EXPECT_THROW(write_obj(tmp.path("no/such/dir/x.obj"), torus), InvalidInput);
  EXPECT_THROW(write_obj(tmp.path("empty.obj"), TriangleMesh<S>{}), InvalidInput);
}

// ---------------------------------------------------------------------------------------------
// bad files

TEST(LoadMeshErrors, MissingFileAndDirectory) {
  TempDir tmp;
  expect_invalid(tmp.path("does-not-exist.obj"), "does not exist");
  expect_invalid<float>(tmp.path("does-not-exist.ply"), "does not exist");
  fs::create_directories(tmp.path("a_dir.obj"));
  expect_invalid(tmp.path("a_dir.obj"), "directory");
  EXPECT_THROW(load_mesh<double>(""), InvalidInput);
}

TEST(LoadMeshErrors, EmptyFiles) {
  TempDir tmp;
  for (const char* name : {"empty.obj", "empty.stl", "empty.ply", "empty.off", "empty"}) expect_invalid(tmp.write(name, ""), "empty");
}

TEST(LoadMeshErrors, GarbageBytes) {
  TempDir tmp;
  std::string garbage;
  std::uint64_t x = 12345;
  for (int i = 0; i < 4096; ++i) {
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    garbage.push_back(static_cast<char>(x >> 56));
  }
  for (const char* name : {"garbage.obj", "garbage.stl", "garbage.ply", "garbage.off", "garbage.bin", "garbage.gltf", "garbage"}) {
    const std::string path = tmp.write(name, garbage);
    // either assimp finds no reader or its reader fails, or nothing usable comes out
    try {
      const auto m = load_mesh<double>(path);
      ADD_FAILURE() << name << ": loaded " << m.num_triangles() << " triangles from garbage";
    } catch (const InvalidInput& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(path), std::string::npos) << msg;
      EXPECT_TRUE(msg.find("cannot be parsed") != std::string::npos || msg.find("no triangles") != std::string::npos ||
                  msg.find("not read by default") != std::string::npos || msg.find("unknown format") != std::string::npos)
          << msg;
    }
  }
  // plain text that is no mesh, under a name assimp reads by content
  expect_invalid(tmp.write("notes.txt", "hello\nworld\n"), "unknown format");
}

TEST(LoadMeshErrors, TruncatedFiles) {
  TempDir tmp;
  const auto box = reference_box();
  const std::string ply_bin = as_ply_binary(box), ply_ascii = as_ply_ascii(box), off = as_off(box), obj = as_obj(box),
                    stl = as_stl_ascii(box), stl_bin = as_stl_binary(box);
  // binary PLY cut inside the faces, inside the vertices, and inside the header
  expect_invalid(tmp.write("cut_faces.ply", ply_bin.substr(0, ply_bin.size() - 7)), "truncated");
  expect_invalid(tmp.write("cut_vertices.ply", ply_bin.substr(0, ply_header("binary_little_endian", 8, 12).size() + 40)), "truncated");
  expect_invalid(tmp.write("cut_header.ply", ply_bin.substr(0, 60)), "truncated");
  // ASCII PLY and OFF missing their last face line (still well-formed text)
  auto without_last_line = [](const std::string& s) { return s.substr(0, s.rfind('\n', s.size() - 2) + 1); };
  expect_invalid(tmp.write("cut.ply", without_last_line(ply_ascii)), "truncated");
  expect_invalid(tmp.write("cut.off", without_last_line(off)), "truncated");
  expect_invalid(tmp.write("cut_vertices.off", off.substr(0, 40)), "truncated");
  // OBJ cut inside a face line, STL inside a facet, binary STL short of its declared facets
  expect_invalid(tmp.write("cut.obj", obj.substr(0, obj.size() - 4)), "cannot be parsed");
  expect_invalid(tmp.write("cut.stl", stl.substr(0, stl.size() / 2)), "cannot be parsed");
  expect_invalid(tmp.write("cut_between_facets.stl", stl.substr(0, stl.rfind("endfacet") + 9)), "truncated");
  expect_invalid(tmp.write("cut_binary.stl", stl_bin.substr(0, stl_bin.size() - 30)), "cannot be parsed");
}

TEST(LoadMeshErrors, NonFiniteCoordinates) {
  TempDir tmp;
  expect_invalid(tmp.write("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"), "NaN");
  expect_invalid(tmp.write("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 -inf 0\nf 1 2 3\n"), "infinite");
  expect_invalid(tmp.write("huge.obj", "v 0 0 0\nv 1e300 0 0\nv 0 1 0\nf 1 2 3\n"), "infinite");  // overflows float
  expect_invalid(tmp.write("nan.off", "OFF\n3 1 0\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n"), "NaN");
  std::string ply = ply_header("ascii", 3, 1) + "0 0 0\n1 0 0\n0 0 nan\n3 0 1 2\n";
  expect_invalid(tmp.write("nan.ply", ply), "NaN");
  std::string ply_bin = ply_header("binary_little_endian", 3, 1);
  for (float f : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) append_f32(ply_bin, f);
  std::memset(&ply_bin[ply_bin.size() - 4], 0xff, 4);  // a NaN bit pattern
  ply_bin.push_back(3);
  for (std::uint32_t i : {0u, 1u, 2u}) append_u32(ply_bin, i);
  expect_invalid(tmp.write("nan_binary.ply", ply_bin), "NaN");
  expect_invalid(tmp.write("nan.stl", "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex nan 1 0\n"
                                      "endloop\nendfacet\nendsolid s\n"),
                 "NaN");
}

TEST(LoadMeshErrors, FaceIndicesOutOfRange) {
  TempDir tmp;
  const std::string v3 = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  expect_invalid(tmp.write("high.obj", v3 + "f 1 2 4\n"), "out of range");
  expect_invalid(tmp.write("negative.obj", v3 + "f 1 2 -4\n"), "out of range");
  expect_invalid(tmp.write("zero.obj", v3 + "f 0 1 2\n"), "cannot be parsed");
  expect_invalid(tmp.write("high.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"), "outside [0, 3)");
  expect_invalid(tmp.write("negative.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n"), "outside [0, 3)");
  expect_invalid(tmp.write("high.ply", ply_header("ascii", 3, 1) + "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"), "outside [0, 3)");
  std::string ply_bin = ply_header("binary_little_endian", 3, 1);
  for (float f : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) append_f32(ply_bin, f);
  ply_bin.push_back(3);
  for (std::uint32_t i : {0u, 1u, 3u}) append_u32(ply_bin, i);
  expect_invalid(tmp.write("high_binary.ply", ply_bin), "outside [0, 3)");
}

TEST(LoadMeshErrors, NoTriangles) {
  TempDir tmp;
  const std::string v3 = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  expect_invalid(tmp.write("points.obj", v3 + "p 1 2 3\n"), "no triangles");
  expect_invalid(tmp.write("lines.obj", v3 + "l 1 2 3\n"), "no triangles");
  // vertices without faces: assimp's validation or ours rejects it
  try {
    load_mesh<double>(tmp.write("vertices_only.obj", v3));
    ADD_FAILURE() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("vertices_only.obj"), std::string::npos) << e.what();
  }
  expect_invalid(tmp.write("no_faces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"), "");
  expect_invalid(tmp.write("no_faces.ply", ply_header("ascii", 3, 0) + "0 0 0\n1 0 0\n0 1 0\n"), "");
  expect_invalid(tmp.write("empty_solid.stl", "solid s\nendsolid s\n"), "");
}

TEST(LoadMeshErrors, MutatedFilesLoadOrThrowInvalidInput) {
  // Deterministic byte-level mutations (overwrite, delete, duplicate, cut) of each written format:
  // every outcome must be a mesh that passes validate_mesh or an InvalidInput naming the file;
  // nothing else may escape, crash or hang.
  TempDir tmp;
  const auto box = reference_box();
  const std::pair<std::string, std::string> seeds[] = {
      {"obj", as_obj(box)},         {"stl", as_stl_ascii(box)}, {"stl", as_stl_binary(box)},
      {"ply", as_ply_ascii(box)},   {"ply", as_ply_binary(box)}, {"off", as_off(box)},
  };
  detail::SplitMix64 rng(2024);
  auto below = [&rng](std::size_t n) { return static_cast<std::size_t>(rng.next() % (n == 0 ? 1 : n)); };
  int loaded = 0, rejected = 0, file = 0;
  for (const auto& [ext, original] : seeds) {
    for (int trial = 0; trial < 60; ++trial) {
      std::string bytes = original;
      const std::size_t edits = 1 + below(6);
      for (std::size_t e = 0; e < edits && !bytes.empty(); ++e) {
        const std::size_t at = below(bytes.size());
        switch (below(4)) {
          case 0: bytes[at] = static_cast<char>(below(256)); break;
          case 1: bytes[at] = "0123456789-+.e \n"[below(16)]; break;
          case 2: bytes.erase(at, 1 + below(20)); break;
          default: bytes.insert(at, bytes.substr(below(bytes.size()), 1 + below(30))); break;
        }
      }
      if (below(4) == 0) bytes.resize(below(bytes.size()));
      const std::string path = tmp.write("mutant" + std::to_string(file++) + "." + ext, bytes);
      load_or_reject<double>(path, loaded, rejected);
    }
  }
  EXPECT_GT(rejected, 0);
  EXPECT_EQ(loaded + rejected, 360);
}

TEST(LoadMesh, AssimpTestModelsLoadOrThrowInvalidInput) {
  // Debian's assimp-testmodels package: assimp's own sample files, some deliberately broken
  // (invalid/, truncated, NaN/Inf, point clouds). Each must load into a valid mesh or throw
  // InvalidInput naming the file.
  const fs::path root = "/usr/share/assimp/models";
  std::error_code ec;
  if (!fs::is_directory(root, ec) && test::in_ci()) FAIL() << "CI=true: " << root << " missing (Debian package assimp-testmodels)";
  if (!fs::is_directory(root, ec)) GTEST_SKIP() << root << " missing (Debian package assimp-testmodels)";
  const std::set<std::string> exts = {".obj", ".stl", ".ply", ".off", ".gltf", ".glb", ".dae"};
  int loaded = 0, rejected = 0;
  for (const auto& entry : fs::recursive_directory_iterator(root, ec)) {
    if (!entry.is_regular_file()) continue;
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (!exts.count(ext)) continue;
    const std::string path = entry.path().string();
    // by default: formats other than OBJ, PLY, OFF and STL are refused at once
    if (ext != ".obj" && ext != ".ply" && ext != ".off" && ext != ".stl") {
      try {
        load_mesh<float>(path);
        ADD_FAILURE() << path << ": loaded with the default options";
      } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("not read by default"), std::string::npos) << e.what();
      }
    }
    // these are trusted files: every format assimp reads
    LoadOptions trusted;
    trusted.allow_unchecked_formats = true;
    try {
      const auto m = load_mesh<float>(path, trusted);
      EXPECT_NO_THROW(validate_mesh(m)) << path;
      ++loaded;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      ++rejected;
    }
  }
  EXPECT_GT(loaded, 50) << rejected << " rejected";
}

}  // namespace
