// SPDX-License-Identifier: MIT
/// \file
/// Structural checks load_mesh runs on PLY and OFF files before handing them to assimp, for the
/// failures assimp 5.2 does not report: a PLY header cut short (assimp can loop forever on it), an
/// ASCII PLY or OFF body with fewer items than its header declares (assimp pads with made-up
/// faces), OFF face indices out of range (assimp clamps them), and an ASCII STL file cut short
/// (assimp keeps the facets before the cut). Each check reads the header
/// and walks the body without building anything; it throws InvalidInput on a definite defect and
/// returns quietly on anything it does not understand, leaving that to assimp.
#pragma once

#include "impact/core/error.hpp"

#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace impact::detail::mesh_file {

[[noreturn]] inline void fail(const std::string& path, const std::string& why) {
  throw InvalidInput("load_mesh: '" + path + "': " + why);
}

inline std::string read_all_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "file cannot be opened for reading");
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

inline std::string lower_ascii(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

/// Whitespace-separated tokens of one line.
inline std::vector<std::string> split_tokens(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream ss(line);
  std::string t;
  while (ss >> t) out.push_back(t);
  return out;
}

/// Parses a whole token as a signed integer; false when it is not one.
inline bool parse_integer(const std::string& token, long long& value) {
  if (token.empty()) return false;
  char* end = nullptr;
  value = std::strtoll(token.c_str(), &end, 10);
  return end == token.c_str() + token.size();
}

// ---------------------------------------------------------------------------------------------
// PLY

struct PlyType {
  int size = 0;  // bytes; 0 = unknown type
  bool is_signed = false;
  bool is_float = false;
};

inline PlyType ply_type(const std::string& name) {
  if (name == "char" || name == "int8") return {1, true, false};
  if (name == "uchar" || name == "uint8") return {1, false, false};
  if (name == "short" || name == "int16") return {2, true, false};
  if (name == "ushort" || name == "uint16") return {2, false, false};
  if (name == "int" || name == "int32") return {4, true, false};
  if (name == "uint" || name == "uint32") return {4, false, false};
  if (name == "float" || name == "float32") return {4, true, true};
  if (name == "double" || name == "float64") return {8, true, true};
  return {};
}

struct PlyProperty {
  bool is_list = false;
  PlyType count_type;  // lists only
  PlyType value_type;
  std::string name;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

/// Reads an integer of type t at p (size checked by the caller) in the given byte order.
inline long long ply_read_integer(const unsigned char* p, const PlyType& t, bool big_endian) {
  std::uint64_t u = 0;
  for (int i = 0; i < t.size; ++i) {
    const unsigned char byte = big_endian ? p[i] : p[t.size - 1 - i];
    u = (u << 8) | byte;
  }
  if (t.is_signed && t.size < 8 && (u >> (8 * t.size - 1)) != 0) u |= ~std::uint64_t(0) << (8 * t.size);
  return static_cast<long long>(u);
}

inline bool is_face_index_list(const PlyElement& e, const PlyProperty& p) {
  return e.name == "face" && p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index");
}

/// Checks a PLY file (data holds its bytes): complete header, body long enough for every declared
/// element, face indices in [0, number of vertices).
inline void check_ply(const std::string& path, const std::string& data) {
  // header: lines up to "end_header"
  std::size_t pos = 0;
  std::vector<std::string> header;
  bool ended = false;
  while (pos < data.size()) {
    std::size_t nl = data.find('\n', pos);
    if (nl == std::string::npos) break;
    std::string line = data.substr(pos, nl - pos);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = nl + 1;
    if (split_tokens(line) == std::vector<std::string>{"end_header"}) {
      ended = true;
      break;
    }
    header.push_back(line);
  }
  if (!ended) fail(path, "cannot be parsed: truncated or malformed PLY header (no end_header line)");

  enum class Format { unknown, ascii, little, big } format = Format::unknown;
  std::vector<PlyElement> elements;
  for (std::size_t i = 1; i < header.size(); ++i) {
    const auto tok = split_tokens(header[i]);
    if (tok.empty() || tok[0] == "comment" || tok[0] == "obj_info") continue;
    if (tok[0] == "format" && tok.size() >= 2) {
      if (tok[1] == "ascii") format = Format::ascii;
      else if (tok[1] == "binary_little_endian") format = Format::little;
      else if (tok[1] == "binary_big_endian") format = Format::big;
      else fail(path, "cannot be parsed: unknown PLY format '" + tok[1] + "'");
    } else if (tok[0] == "element" && tok.size() == 3) {
      long long n = 0;
      if (!parse_integer(tok[2], n) || n < 0) fail(path, "cannot be parsed: bad PLY element count '" + tok[2] + "'");
      elements.push_back({tok[1], static_cast<std::uint64_t>(n), {}});
    } else if (tok[0] == "property" && !elements.empty()) {
      PlyProperty p;
      if (tok.size() == 5 && tok[1] == "list") {
        p.is_list = true;
        p.count_type = ply_type(tok[2]);
        p.value_type = ply_type(tok[3]);
        p.name = tok[4];
        if (p.count_type.size == 0 || p.count_type.is_float || p.value_type.size == 0)
          fail(path, "cannot be parsed: bad PLY list property '" + header[i] + "'");
      } else if (tok.size() == 3) {
        p.value_type = ply_type(tok[1]);
        p.name = tok[2];
        if (p.value_type.size == 0) fail(path, "cannot be parsed: unknown PLY property type '" + tok[1] + "'");
      } else {
        fail(path, "cannot be parsed: malformed PLY property line '" + header[i] + "'");
      }
      elements.back().properties.push_back(p);
    } else {
      return;  // something this check does not know: leave it to assimp
    }
  }
  if (format == Format::unknown) fail(path, "cannot be parsed: PLY header has no format line");

  std::uint64_t num_vertices = 0;
  for (const auto& e : elements)
    if (e.name == "vertex") num_vertices = e.count;
  auto truncated = [&](const PlyElement& e, std::uint64_t item) {
    fail(path, "cannot be parsed: truncated PLY file, data ends in element '" + e.name + "' (item " +
                               std::to_string(item) + " of " + std::to_string(e.count) + ")");
  };
  auto check_index = [&](long long idx, std::uint64_t face) {
    if (idx < 0 || static_cast<std::uint64_t>(idx) >= num_vertices)
      fail(path, "face " + std::to_string(face) + " has vertex index " + std::to_string(idx) + " outside [0, " +
                                 std::to_string(num_vertices) + ")");
  };

  if (format == Format::ascii) {
    // tokens of the body, consumed in declaration order
    const char* p = data.c_str() + pos;
    const char* const end = data.c_str() + data.size();
    auto next_token = [&](std::string& out) {
      while (p < end && std::isspace(static_cast<unsigned char>(*p))) ++p;
      const char* b = p;
      while (p < end && !std::isspace(static_cast<unsigned char>(*p))) ++p;
      out.assign(b, p);
      return !out.empty();
    };
    std::string tok;
    for (const auto& e : elements) {
      for (std::uint64_t i = 0; i < e.count; ++i) {
        for (const auto& prop : e.properties) {
          if (!next_token(tok)) truncated(e, i);
          if (!prop.is_list) continue;
          long long n = 0;
          if (!parse_integer(tok, n) || n < 0)
            fail(path, "cannot be parsed: bad list length '" + tok + "' in PLY element '" + e.name + "'");
          const bool indices = is_face_index_list(e, prop);
          for (long long k = 0; k < n; ++k) {
            if (!next_token(tok)) truncated(e, i);
            if (indices) {
              long long idx = 0;
              if (!parse_integer(tok, idx)) fail(path, "cannot be parsed: bad vertex index '" + tok + "' in face " + std::to_string(i));
              check_index(idx, i);
            }
          }
        }
      }
    }
    return;
  }

  const bool big = format == Format::big;
  const auto* bytes = reinterpret_cast<const unsigned char*>(data.data());
  const std::uint64_t size = data.size();
  for (const auto& e : elements) {
    bool fixed = true;
    std::uint64_t stride = 0;
    for (const auto& prop : e.properties) {
      fixed = fixed && !prop.is_list;
      stride += static_cast<std::uint64_t>(prop.value_type.size);
    }
    if (fixed) {
      if (stride != 0 && e.count > (size - pos) / stride) truncated(e, (size - pos) / stride);
      pos += e.count * stride;
      continue;
    }
    for (std::uint64_t i = 0; i < e.count; ++i) {
      for (const auto& prop : e.properties) {
        if (!prop.is_list) {
          if (size - pos < static_cast<std::uint64_t>(prop.value_type.size)) truncated(e, i);
          pos += static_cast<std::uint64_t>(prop.value_type.size);
          continue;
        }
        if (size - pos < static_cast<std::uint64_t>(prop.count_type.size)) truncated(e, i);
        const long long n = ply_read_integer(bytes + pos, prop.count_type, big);
        pos += static_cast<std::uint64_t>(prop.count_type.size);
        if (n < 0) fail(path, "cannot be parsed: negative list length in PLY element '" + e.name + "'");
        const auto vsize = static_cast<std::uint64_t>(prop.value_type.size);
        if (static_cast<std::uint64_t>(n) > (size - pos) / vsize) truncated(e, i);
        if (is_face_index_list(e, prop)) {
          if (prop.value_type.is_float) fail(path, "cannot be parsed: PLY face indices of a floating-point type");
          for (long long k = 0; k < n; ++k) check_index(ply_read_integer(bytes + pos + static_cast<std::uint64_t>(k) * vsize, prop.value_type, big), i);
        }
        pos += static_cast<std::uint64_t>(n) * vsize;
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// OFF

/// Checks an ASCII OFF file (data holds its bytes): declared numbers of vertex and face lines
/// present, face indices in [0, number of vertices). Binary OFF and the 4D / n-D variants are
/// left to assimp.
inline void check_off(const std::string& path, const std::string& data) {
  // meaningful lines: comments stripped, blank lines dropped
  std::vector<std::vector<std::string>> lines;
  std::istringstream in(data);
  std::string line;
  while (std::getline(in, line)) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    auto tok = split_tokens(line);
    if (!tok.empty()) lines.push_back(std::move(tok));
  }
  if (lines.empty()) return;
  const std::string key = lines[0][0];
  if (key.size() < 3 || key.compare(key.size() - 3, 3, "OFF") != 0) return;
  const std::string prefix = key.substr(0, key.size() - 3);
  if (prefix.find_first_not_of("STCN") != std::string::npos) return;  // 4OFF, nOFF: not checked
  std::size_t li = 1;
  std::vector<std::string> counts(lines[0].begin() + 1, lines[0].end());
  if (!counts.empty() && counts[0] == "BINARY") return;
  if (counts.empty()) {
    if (li >= lines.size()) fail(path, "cannot be parsed: truncated OFF file (no counts line)");
    counts = lines[li++];
  }
  long long nv = 0, nf = 0;
  if (counts.size() < 2 || !parse_integer(counts[0], nv) || !parse_integer(counts[1], nf)) return;
  if (nv < 0 || nf < 0) fail(path, "cannot be parsed: negative OFF vertex or face count");
  if (static_cast<long long>(lines.size() - li) < nv)
    fail(path, "cannot be parsed: truncated OFF file, " + std::to_string(lines.size() - li) + " vertex lines of " +
                               std::to_string(nv) + " declared");
  li += static_cast<std::size_t>(nv);
  for (long long f = 0; f < nf; ++f, ++li) {
    if (li >= lines.size())
      fail(path, "cannot be parsed: truncated OFF file, " + std::to_string(f) + " face lines of " + std::to_string(nf) +
                                 " declared");
    const auto& tok = lines[li];
    long long n = 0;
    if (!parse_integer(tok[0], n) || n < 0) fail(path, "cannot be parsed: bad OFF face line " + std::to_string(f));
    if (static_cast<long long>(tok.size()) - 1 < n)
      fail(path, "cannot be parsed: OFF face " + std::to_string(f) + " lists fewer indices than its count");
    for (long long k = 1; k <= n; ++k) {
      long long idx = 0;
      if (!parse_integer(tok[static_cast<std::size_t>(k)], idx))
        fail(path, "cannot be parsed: bad vertex index '" + tok[static_cast<std::size_t>(k)] + "' in OFF face " + std::to_string(f));
      if (idx < 0 || idx >= nv)
        fail(path, "face " + std::to_string(f) + " has vertex index " + std::to_string(idx) + " outside [0, " +
                                   std::to_string(nv) + ")");
    }
  }
}

// ---------------------------------------------------------------------------------------------
// STL

/// Checks that an ASCII STL file (data holds its bytes) ends with its `endsolid` line, which
/// assimp does not require: without it a file cut between facets loads as a smaller mesh. A file
/// that starts with "solid" but has exactly the size a binary STL with its facet count would have
/// is binary (binary headers may start with "solid") and is left alone.
inline void check_stl(const std::string& path, const std::string& data) {
  std::size_t b = 0;
  while (b < data.size() && std::isspace(static_cast<unsigned char>(data[b]))) ++b;
  if (lower_ascii(data.substr(b, 5)) != "solid") return;
  if (data.size() >= 84) {
    std::uint64_t n = 0;
    for (int i = 3; i >= 0; --i) n = (n << 8) | static_cast<unsigned char>(data[80 + static_cast<std::size_t>(i)]);
    if (data.size() == 84 + 50 * n) return;
  }
  std::size_t e = data.size();
  while (e > 0 && std::isspace(static_cast<unsigned char>(data[e - 1]))) --e;
  const std::size_t line_start = data.find_last_of("\r\n", e == 0 ? 0 : e - 1);
  const std::string last = lower_ascii(data.substr(line_start == std::string::npos ? 0 : line_start + 1, e));
  if (split_tokens(last).empty() || split_tokens(last)[0] != "endsolid")
    fail(path, "cannot be parsed: truncated ASCII STL file (does not end with an endsolid line)");
}

/// Runs the check that fits the file, chosen by its first bytes (PLY magic) or its extension and
/// (OFF, STL). Other formats pass through untouched.
inline void check(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[4] = {0, 0, 0, 0};
  in.read(head, 4);
  const std::string magic(head, static_cast<std::size_t>(in.gcount()));
  const std::string ext = lower_ascii(path.size() >= 4 ? path.substr(path.size() - 4) : path);
  const bool ply = magic.size() == 4 && lower_ascii(magic.substr(0, 3)) == "ply" && (magic[3] == '\n' || magic[3] == '\r');
  if (ply) {
    check_ply(path, read_all_bytes(path));
  } else if (ext == ".off") {
    check_off(path, read_all_bytes(path));
  } else if (ext == ".stl") {
    check_stl(path, read_all_bytes(path));
  }
}

}  // namespace impact::detail::mesh_file
