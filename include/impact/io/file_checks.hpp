// SPDX-License-Identifier: MIT
/// \file
/// The checks load_mesh runs on a file before handing it to assimp, for the defects assimp 5.2
/// does not report or cannot survive: headers that declare counts the file cannot hold (assimp
/// allocates by them), headers cut short or holding stray line-end bytes (assimp loops forever or
/// reads past its buffer), empty face index lists (assimp aborts the process), bodies shorter than
/// declared (assimp pads them with made-up items or keeps the part before a cut), out-of-range
/// indices (assimp clamps them) and non-numeric tokens where numbers are due (assimp leaks).
///
/// Which check applies is decided from the bytes as well as the name, because assimp reads files
/// by content when their extension is not one of its own (.txt, .dat, none): bytes starting with
/// "ply" get the PLY check, bytes starting with "off" or a name *.off the OFF check, bytes starting
/// with "solid" or a name *.stl the STL check. Each check is in io/detail/<format>_check.hpp,
/// walks the file without building anything (time and memory linear in its size) and throws
/// InvalidInput with the reason; other formats pass through untouched.
#pragma once

#include "impact/io/detail/off_check.hpp"
#include "impact/io/detail/ply_check.hpp"
#include "impact/io/detail/stl_check.hpp"
#include "impact/io/detail/text_scan.hpp"

#include <fstream>
#include <iterator>
#include <string>

namespace impact::detail::mesh_file {

inline std::string read_all_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "file cannot be opened for reading");
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// The lower-case extension of path without its dot ("" when there is none).
inline std::string extension_of(const std::string& path) {
  const std::size_t slash = path.find_last_of("/\\");
  const std::size_t dot = path.rfind('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return {};
  return lower_ascii(std::string_view(path).substr(dot + 1));
}

/// Runs the check that fits the file (see the file comment): by its extension when it is one of
/// ply, off, stl (assimp then reads it with that reader), else by its first bytes.
inline void check_bytes(const std::string& path, const std::string& data) {
  const std::string ext = extension_of(path);
  if (ext == "ply") {
    if (looks_like_ply(data)) check_ply(path, data);  // else assimp rejects the magic number
  } else if (ext == "off") {
    check_off(path, data, true);
  } else if (ext == "stl") {
    check_stl(path, data);
  } else if (looks_like_ply(data)) {
    check_ply(path, data);
  } else if (starts_with_ci(data, "off")) {
    check_off(path, data, false);
  } else if (looks_like_ascii_stl(data)) {
    check_stl(path, data);
  }
}

/// check_bytes on the file's contents.
inline void check(const std::string& path) { check_bytes(path, read_all_bytes(path)); }

}  // namespace impact::detail::mesh_file
