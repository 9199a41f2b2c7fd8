// SPDX-License-Identifier: MIT
/// \file
/// The STL check of load_mesh, run before assimp sees a file named *.stl or whose bytes start
/// with "solid". A binary STL (its size is 84 + 50 x its facet count, which assimp checks itself)
/// passes. An ASCII STL must follow the grammar (solid, facet normal x y z, outer loop, three
/// vertex x y z, endloop, endfacet, ..., endsolid) with a number wherever one is due: assimp 5.2
/// keeps the facets before a cut (a file cut between facets loads as a smaller mesh), and leaks on
/// a non-numeric token. Throws InvalidInput with the facet and the token.
#pragma once

#include "impact/io/detail/text_scan.hpp"

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace impact::detail::mesh_file {

/// True when data is a binary STL as assimp decides it: 84 + 50 x (facet count at byte 80) bytes.
inline bool is_binary_stl(const std::string& data) {
  if (data.size() < 84) return false;
  std::uint64_t n = 0;
  for (int i = 3; i >= 0; --i) n = (n << 8) | static_cast<unsigned char>(data[80 + static_cast<std::size_t>(i)]);
  return data.size() == 84 + 50 * n;
}

/// True when data starts, after blanks, with "solid" in any case (assimp's ASCII STL mark).
inline bool looks_like_ascii_stl(const std::string& data) {
  std::size_t b = 0;
  while (b < data.size() && std::isspace(static_cast<unsigned char>(data[b]))) ++b;
  return starts_with_ci(std::string_view(data).substr(b), "solid");
}

/// Checks an STL file (data holds its bytes): binary ones pass; ASCII ones follow the grammar in
/// the file comment to a final endsolid line, with numeric coordinates. A file that is neither is
/// left to assimp (which rejects it).
inline void check_stl(const std::string& path, const std::string& data) {
  if (is_binary_stl(data) || !looks_like_ascii_stl(data)) return;
  std::size_t pos = 0;
  std::string_view line;
  std::vector<std::string_view> tok;  // tokens of the current line
  std::size_t ti = 0;
  std::uint64_t facet = 0;
  // next token, crossing lines; empty at the end of the file
  auto next = [&]() -> std::string_view {
    while (ti >= tok.size()) {
      if (!next_line(path, data, pos, line, "the ASCII STL file")) return {};
      tok = split_tokens(line);
      ti = 0;
    }
    return tok[ti++];
  };
  auto truncated = [&]() {
    fail(path, "cannot be parsed: truncated ASCII STL file (ends in facet " + std::to_string(facet) +
                   ", does not end with an endsolid line)");
  };
  auto expect = [&](std::string_view word) {
    const std::string_view t = next();
    if (t.empty()) truncated();
    if (t != word)
      fail(path, "cannot be parsed: ASCII STL facet " + std::to_string(facet) + " has " + quote(t) + " where '" +
                     std::string(word) + "' is due");
  };
  auto numbers = [&](const char* what) {
    for (int d = 0; d < 3; ++d) {
      const std::string_view t = next();
      if (t.empty()) truncated();
      if (!is_number(t))
        fail(path, "cannot be parsed: non-numeric token " + quote(t) + " where a " + what + " coordinate is due in ASCII STL facet " +
                       std::to_string(facet));
    }
  };
  bool in_solid = false;
  for (;;) {
    if (!in_solid) {
      const std::string_view t = next();
      if (t.empty()) break;  // after an endsolid line: the end
      if (lower_ascii(t) != "solid") fail(path, "cannot be parsed: ASCII STL has " + quote(t) + " where 'solid' is due");
      ti = tok.size();  // the rest of the line is the solid's name
      in_solid = true;
      continue;
    }
    const std::string_view t = next();
    if (t.empty()) truncated();
    if (t == "endsolid") {
      ti = tok.size();  // name
      in_solid = false;
      continue;
    }
    if (t != "facet")
      fail(path, "cannot be parsed: ASCII STL has " + quote(t) + " where 'facet' or 'endsolid' is due (after facet " +
                     std::to_string(facet) + ")");
    expect("normal");
    numbers("normal");
    expect("outer");
    expect("loop");
    for (int k = 0; k < 3; ++k) {
      expect("vertex");
      numbers("vertex");
    }
    expect("endloop");
    expect("endfacet");
    ++facet;
  }
}

}  // namespace impact::detail::mesh_file
