// SPDX-License-Identifier: MIT
/// \file
/// The OFF check of load_mesh, run before assimp sees a file named *.off or whose bytes start
/// with "off" (assimp reads those by content whatever their name). assimp 5.2 reads the header
/// leniently (a keyword such as "COFF255" is taken as "COFF" followed by the count 255, digits up
/// to the first other byte are a number) and allocates by the declared counts before reading a
/// vertex: a 28-byte file can take gigabytes. It pads a short body, clamps bad indices to the last
/// vertex, drops faces of 0 or more than 9 corners, and throws (leaking) on a non-numeric token.
/// This check tokenises the header the way assimp does, bounds the counts by the file's size, and
/// walks the body line by line as assimp will; it throws InvalidInput on any of the above.
#pragma once

#include "impact/io/detail/text_scan.hpp"

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace impact::detail::mesh_file {

/// The body lines of an OFF file as assimp's OFF reader sees them: split at line ends, empty
/// lines skipped, a '#' starting a comment.
inline std::vector<std::string_view> off_body_lines(const std::string& path, const std::string& data, std::size_t pos) {
  std::vector<std::string_view> lines;
  std::string_view line;
  while (next_line(path, data, pos, line, "the OFF file")) {
    if (line.empty()) continue;
    if (line.size() >= 4095) fail(path, "cannot be parsed: OFF line longer than 4094 bytes (assimp splits it)");
    lines.push_back(line.substr(0, line.find('#')));
  }
  return lines;
}

/// Checks an OFF file (data holds its bytes; by_extension: the file is named *.off, so assimp
/// also reads it without an OFF keyword): keyword [ST][C][N][4][n]OFF or none, the dimension of
/// nOFF in [1, 3], whole-number counts that the file's size can hold, every vertex line with the
/// numbers its keyword asks for (all tokens numeric), every face line with 1 to 9 corners, indices
/// in [0, vertices), and as many vertex and face lines as declared.
inline void check_off(const std::string& path, const std::string& data, bool by_extension) {
  for (std::size_t i = 0; i < data.size(); ++i) {
    const auto c = static_cast<unsigned char>(data[i]);
    if (is_stray_control(c) || (c == '\r' && (i + 1 == data.size() || data[i + 1] != '\n')))
      fail(path, "cannot be parsed: control byte " + quote(data.substr(i, 1)) + " in the OFF file (byte " + std::to_string(i) + ")");
  }
  // Header tokens as assimp's NextToken reads them: blanks and line ends skipped, a '#' at a
  // token's start skips the rest of its line.
  std::size_t pos = 0;
  auto skip_blanks = [&]() {
    for (;;) {
      while (pos < data.size() && (data[pos] == ' ' || data[pos] == '\t' || data[pos] == '\r' || data[pos] == '\n')) ++pos;
      if (pos >= data.size() || data[pos] != '#') return;
      while (pos < data.size() && data[pos] != '\n') ++pos;
    }
  };
  auto next_token = [&]() -> std::string_view {
    skip_blanks();
    const std::size_t b = pos;
    while (pos < data.size() && data[pos] != ' ' && data[pos] != '\t' && data[pos] != '\r' && data[pos] != '\n') ++pos;
    return std::string_view(data).substr(b, pos - b);
  };
  auto count = [&](const char* what) {
    const std::string_view t = next_token();
    std::uint64_t n = 0;
    if (t.empty()) fail(path, std::string("cannot be parsed: truncated OFF header (no ") + what + ")");
    if (!parse_count(t, n))
      fail(path, std::string("cannot be parsed: OFF ") + what + " " + quote(t) + " is not a whole number");
    return n;
  };

  const std::size_t first = pos;
  std::string_view key = next_token();
  bool texcoords = false, colours = false, normals = false, homogeneous = false;
  std::uint64_t dimensions = 3;
  std::string_view k = key;
  auto take = [&k](std::string_view prefix) {
    if (k.substr(0, prefix.size()) != prefix) return false;
    k.remove_prefix(prefix.size());
    return true;
  };
  texcoords = take("ST");
  colours = take("C");
  normals = take("N");
  homogeneous = take("4");
  const bool has_dimension = take("n");
  if (k == "OFF") {
    if (has_dimension) {
      dimensions = count("dimension");
      if (dimensions < 1 || dimensions > 3) fail(path, "cannot be parsed: OFF dimension " + std::to_string(dimensions) + " outside [1, 3]");
    }
  } else {
    std::uint64_t ignored = 0;
    if (!by_extension || !parse_count(key, ignored))
      fail(path, "cannot be parsed: malformed OFF keyword " + quote(key) + " (expected [ST][C][N][4][n]OFF)");
    // No keyword, which OFF allows: the counts come first. assimp reads a leading '4' as the
    // homogeneous flag even there, and so would misread the counts.
    if (key[0] == '4') fail(path, "cannot be parsed: an OFF file without a keyword may not start with the digit 4 (assimp misreads it)");
    pos = first;
    texcoords = colours = normals = homogeneous = false;
  }
  const std::uint64_t nv = count("vertex count");
  const std::uint64_t nf = count("face count");
  count("edge count");
  if (nv == 0) fail(path, "cannot be parsed: OFF file declares no vertices");
  if (nf == 0) fail(path, "cannot be parsed: OFF file declares no faces");
  // assimp's first vertex line starts at the next token after the counts (on their line if more
  // tokens follow them there)
  skip_blanks();

  // every vertex line holds at least two bytes a value, every face line at least two bytes (the
  // last line may lack its line end): the counts must fit in what is left before assimp allocates
  // by them
  const std::uint64_t per_vertex = dimensions + (homogeneous ? 1 : 0) + (normals ? 3 : 0) + (colours ? 1 : 0) + (texcoords ? 2 : 0);
  const std::uint64_t left = data.size() - pos + 1;
  if (nv > left / (2 * per_vertex) || nf > left / 2 || nv * 2 * per_vertex + nf * 2 > left)
    fail(path, "cannot be parsed: truncated or corrupt OFF file: header declares " + std::to_string(nv) + " vertices and " +
                   std::to_string(nf) + " faces, more than the " + std::to_string(left - 1) + " bytes after it can hold");

  const auto lines = off_body_lines(path, data, pos);
  if (lines.size() < nv)
    fail(path, "cannot be parsed: truncated OFF file, " + std::to_string(lines.size()) + " vertex lines of " + std::to_string(nv) +
                   " declared");
  for (std::uint64_t v = 0; v < nv; ++v) {
    const auto tok = split_tokens(lines[v]);
    for (const auto t : tok)
      if (!is_number(t)) fail(path, "cannot be parsed: non-numeric token " + quote(t) + " in OFF vertex " + std::to_string(v));
    if (tok.size() < per_vertex)
      fail(path, "cannot be parsed: OFF vertex " + std::to_string(v) + " has " + std::to_string(tok.size()) + " values, needs " +
                     std::to_string(per_vertex));
  }
  for (std::uint64_t f = 0; f < nf; ++f) {
    if (nv + f >= lines.size())
      fail(path, "cannot be parsed: truncated OFF file, " + std::to_string(f) + " face lines of " + std::to_string(nf) + " declared");
    const auto tok = split_tokens(lines[nv + f]);
    std::uint64_t n = 0;
    if (tok.empty() || !parse_count(tok[0], n)) fail(path, "cannot be parsed: bad OFF face line " + std::to_string(f));
    if (n == 0) fail(path, "cannot be parsed: OFF face " + std::to_string(f) + " has an empty vertex index list");
    if (n > 9) fail(path, "cannot be parsed: OFF face " + std::to_string(f) + " has " + std::to_string(n) + " corners; assimp reads at most 9");
    if (tok.size() - 1 < n) fail(path, "cannot be parsed: OFF face " + std::to_string(f) + " lists fewer indices than its count");
    for (std::size_t c = 1; c < tok.size(); ++c) {
      long long idx = 0;
      if (c > n) {
        if (!is_number(tok[c])) fail(path, "cannot be parsed: non-numeric token " + quote(tok[c]) + " in OFF face " + std::to_string(f));
        continue;
      }
      if (!parse_integer(tok[c], idx))
        fail(path, "cannot be parsed: bad vertex index " + quote(tok[c]) + " in OFF face " + std::to_string(f));
      if (idx < 0 || static_cast<std::uint64_t>(idx) >= nv)
        fail(path, "face " + std::to_string(f) + " has vertex index " + std::to_string(idx) + " outside [0, " + std::to_string(nv) + ")");
    }
  }
}

}  // namespace impact::detail::mesh_file
