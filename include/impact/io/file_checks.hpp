// SPDX-License-Identifier: MIT
/// \file
/// The checks load_mesh runs on a file before handing it to assimp, for the defects assimp 5.2
/// does not report or cannot survive: headers that declare counts the file cannot hold (assimp
/// allocates by them), headers cut short or holding stray line-end bytes (assimp loops forever or
/// reads past its buffer), empty face index lists (assimp aborts the process), bodies shorter than
/// declared (assimp pads them with made-up items or keeps the part before a cut), out-of-range
/// indices (assimp clamps them) and non-numeric tokens where numbers are due (assimp leaks).
///
/// load_mesh decides the format (by the extension, or by the first bytes when assimp does not
/// claim the extension: .txt, .dat, none) and hands assimp the very bytes checked here. Each check
/// is in io/detail/<format>_check.hpp, walks the file without building anything (time and memory
/// linear in its size) and throws InvalidInput with the reason.
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

/// The format of a file named with an extension assimp does not claim (.txt, .dat, none), from
/// its first bytes: "ply", "off" or "stl" (ASCII, starting with "solid"), else "" (unknown).
inline std::string sniff_format(const std::string& data) {
  if (looks_like_ply(data)) return "ply";
  if (starts_with_ci(data, "off")) return "off";
  if (looks_like_ascii_stl(data)) return "stl";
  return {};
}

/// Runs the check of `format` ("ply", "off" or "stl"; other formats are not checked) on the file's
/// bytes, `data`, and turns them into the bytes assimp is to read: a PLY header is replaced by
/// the one the check understood (PlyHeaderText). by_extension: the file is named with that
/// extension (a headerless OFF file is then allowed, as assimp reads one only by name).
inline void check_format(const std::string& path, std::string& data, const std::string& format, bool by_extension) {
  if (format == "ply") {
    // also when the bytes do not start with "ply": assimp's reader does not always reject them
    // (one fuzz input, "\0\nply" and a garbled header, made it loop forever)
    const PlyHeaderText header = check_ply(path, data);
    if (data.compare(0, header.body, header.canonical) != 0) data.replace(0, header.body, header.canonical);
  } else if (format == "off") {
    check_off(path, data, by_extension);
  } else if (format == "stl") {
    check_stl(path, data);
  }
}

}  // namespace impact::detail::mesh_file
