// SPDX-License-Identifier: MIT
// Fuzz target: load_mesh over every format assimp reads. The first input byte picks the file's
// extension (kExtensions, index modulo its size: every extension of assimp 5.2, then .txt, .dat
// and none, which assimp reads by content); the rest is written to a temporary file and loaded.
// Allowed outcomes: a mesh that passes validate_mesh, or impact::InvalidInput (which is what the
// formats load_mesh does not read by default give at once). Anything else (a crash, hang, abort,
// huge allocation, another exception type) is a finding.
#include "fuzz_input.hpp"
#include "impact/io/load_mesh.hpp"

#include <assimp/Importer.hpp>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <unistd.h>

#include "support/sanitizer.hpp"
#if IMPACT_TEST_SANITIZED
// assimp 5.2 leaks on some of its own error paths; LeakSanitizer ignores leaks inside libassimp
// (leaks in impact are still reported).
extern "C" __attribute__((used)) const char* __lsan_default_suppressions() { return "leak:libassimp.so\n"; }
#endif

namespace {

// Fixed order: committed inputs keep their meaning. Extensions a newer assimp adds are appended
// at run time.
const char* const kExtensions[] = {
    "obj", "stl", "ply", "off", "gltf", "glb", "dae", "fbx", "3ds", "x", "ase", "md2", "md3", "md5mesh", "mdl", "ms3d",
    "smd", "nff", "enff", "raw", "ac", "ac3d", "acc", "amf", "ask", "assbin", "b3d", "blend", "bsp", "bvh", "cob", "csm",
    "dxf", "hmp", "ifc", "ifczip", "iqm", "irr", "irrmesh", "lwo", "lws", "lxo", "md5anim", "md5camera", "mdc", "mesh",
    "mesh.xml", "mot", "ndo", "ogex", "pk3", "pmx", "prj", "q3o", "q3s", "scn", "sib", "step", "stp", "ter", "uc", "vta",
    "x3d", "x3db", "xgl", "xml", "zae", "zgl", "3d", "3mf", "txt", "dat", ""};

const std::vector<std::string>& extensions() {
  static const std::vector<std::string> all = [] {
    std::vector<std::string> v(std::begin(kExtensions), std::end(kExtensions));
    const std::set<std::string> known(v.begin(), v.end());
    std::string list;
    Assimp::Importer().GetExtensionList(list);  // "*.3d;*.3ds;..."
    std::size_t b = 0;
    while (b < list.size()) {
      std::size_t e = list.find(';', b);
      if (e == std::string::npos) e = list.size();
      std::string ext = list.substr(b, e - b);
      if (ext.rfind("*.", 0) == 0) ext = ext.substr(2);
      if (!ext.empty() && !known.count(ext)) v.push_back(ext);
      b = e + 1;
    }
    return v;
  }();
  return all;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const auto& exts = extensions();
  // IMPACT_FUZZ_EXT=obj pins the extension (to fuzz one reader); the first byte is still consumed
  static const char* const pinned = std::getenv("IMPACT_FUZZ_EXT");
  const std::string ext = pinned ? std::string(pinned) : exts[data[0] % exts.size()];
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("impact-fuzz-load-" + std::to_string(::getpid()) + (ext.empty() ? "" : "." + ext)))
                               .string();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
  }
  impact::TriangleMesh<double> m;
  bool loaded = false;
  // IMPACT_FUZZ_UNCHECKED=1 sets LoadOptions::allow_unchecked_formats (to fuzz the readers load_mesh
  // does not use by default, when deciding which are safe); CI fuzzes the defaults
  static const bool unchecked = std::getenv("IMPACT_FUZZ_UNCHECKED") != nullptr;
  impact::LoadOptions options;
  options.allow_unchecked_formats = unchecked;
  try {
    m = impact::load_mesh<double>(path, options);
    loaded = true;
  } catch (const impact::InvalidInput&) {
    // the one allowed failure
  } catch (const std::exception& e) {
    impact::fuzz::fail("load_mesh (." + ext + ") threw something other than InvalidInput: " + e.what());
  }
  if (loaded) {
    try {
      impact::validate_mesh(m);
    } catch (const std::exception& e) {
      impact::fuzz::fail("load_mesh (." + ext + ") returned a mesh that fails validate_mesh: " + e.what());
    }
    if (m.num_triangles() == 0) impact::fuzz::fail("load_mesh (." + ext + ") returned an empty mesh");
  }
  std::error_code ec;
  std::filesystem::remove(path, ec);
  return 0;
}
