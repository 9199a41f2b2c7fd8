// SPDX-License-Identifier: MIT
/// \file
/// The PLY check of load_mesh, run before assimp sees a file read as PLY (named .ply, or unnamed,
/// .txt or .dat with bytes that start with "ply"): assimp 5.2 trusts the header's counts (it
/// allocates by them), loops or reads past its buffer on a header cut short or holding stray
/// line-end bytes, aborts the process on a face with an empty index list, pads a short body with
/// made-up items and leaks on a non-numeric token. This check reads the header and walks the body
/// without building anything, and throws InvalidInput on any of those. Its work and memory are
/// linear in the file size whatever the header declares.
///
/// It also gives back the header as it understood it, with the comment, obj_info and blank lines
/// left out and the format line first: assimp 5.2 ends an element's property list at any line
/// that is not a property (a comment or a blank line included) and ignores the properties after
/// it, so it would read the body with another layout than the one checked here. Two fuzz inputs
/// made it abort that way; a comment between two vertex properties made it drop y and z and
/// return flattened triangles. load_mesh hands assimp this header in place of the file's.
#pragma once

#include "impact/io/detail/text_scan.hpp"

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace impact::detail::mesh_file {

struct PlyType {
  int size = 0;  // bytes; 0 = unknown type
  bool is_signed = false;
  bool is_float = false;
};

inline PlyType ply_type(std::string_view name) {
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

/// The vertex index list of a face or triangle-strip element (the property names assimp reads).
inline bool ply_is_index_list(const PlyElement& e, const PlyProperty& p) {
  return (e.name == "face" || e.name == "tristrips") && (p.name == "vertex_indices" || p.name == "vertex_index");
}

/// True when data starts like a PLY file: "ply" in any case, after at most line-end bytes (assimp
/// skips them). Used to recognise unnamed files; check_ply then demands a first line "ply".
inline bool looks_like_ply(const std::string& data) {
  std::size_t b = 0;
  while (b < data.size() && (data[b] == '\r' || data[b] == '\n')) ++b;
  return starts_with_ci(std::string_view(data).substr(b), "ply");
}

/// The header of a checked PLY file: where its body starts in the file, and the header that says
/// the same without comment, obj_info and blank lines, format line first (the one assimp is given).
struct PlyHeaderText {
  std::size_t body = 0;
  std::string canonical;
};

/// Checks a PLY file (data holds its bytes): a first line of exactly "ply", a complete header of
/// known keywords only (format, element, property, comment, obj_info, end_header; other lines
/// only before the first element line, read as comments there), known types,
/// counts that the file's size can hold, one item per line in ASCII bodies with exactly the
/// declared values, every value a number of its type, no empty face index list, face indices in
/// [0, vertices) (-1 also allowed in triangle strips), and no item cut off. Returns the header
/// as understood (PlyHeaderText).
inline PlyHeaderText check_ply(const std::string& path, const std::string& data) {
  std::size_t pos = 0;
  std::string_view line;
  if (!next_line(path, data, pos, line, "the PLY header") || lower_ascii(line) != "ply")
    fail(path, "cannot be parsed: a PLY file must start with a line 'ply' (found " +
                   quote(data.substr(0, data.find('\n'))) + ")");

  enum class Format { unknown, ascii, little, big } format = Format::unknown;
  std::vector<PlyElement> elements;
  bool ended = false;
  std::string format_line, element_lines;  // of the canonical header
  auto joined = [](const std::vector<std::string_view>& tokens) {
    std::string out;
    for (const auto& t : tokens) out.append(out.empty() ? "" : " ").append(t);
    return out + "\n";
  };
  while (next_line(path, data, pos, line, "the PLY header")) {
    const auto tok = split_tokens(line);
    if (tok.empty()) continue;
    if (tok[0] == "end_header") {
      ended = true;
      break;
    }
    if (tok[0] == "comment" || tok[0] == "obj_info") continue;
    if (tok[0] == "format") {
      if (!format_line.empty()) fail(path, "cannot be parsed: two PLY format lines");
      format_line = joined(tok);
    } else {
      element_lines += joined(tok);
    }
    if (tok[0] == "format") {
      if (tok.size() < 2) fail(path, "cannot be parsed: PLY format line without a format");
      if (tok[1] == "ascii") format = Format::ascii;
      else if (tok[1] == "binary_little_endian") format = Format::little;
      else if (tok[1] == "binary_big_endian") format = Format::big;
      else fail(path, "cannot be parsed: unknown PLY format " + quote(tok[1]));
    } else if (tok[0] == "element") {
      std::uint64_t n = 0;
      if (tok.size() != 3 || !parse_count(tok[2], n))
        fail(path, "cannot be parsed: malformed PLY element line " + quote(line) + " (expected 'element NAME COUNT')");
      for (const auto& e : elements)
        if (e.name == tok[1]) fail(path, "cannot be parsed: PLY element '" + e.name + "' declared twice");
      elements.push_back({std::string(tok[1]), n, {}});
    } else if (tok[0] == "property") {
      if (elements.empty()) fail(path, "cannot be parsed: PLY property line before any element line");
      PlyProperty p;
      if (tok.size() == 5 && tok[1] == "list") {
        p.is_list = true;
        p.count_type = ply_type(tok[2]);
        p.value_type = ply_type(tok[3]);
        p.name = std::string(tok[4]);
        if (p.count_type.size == 0 || p.count_type.is_float || p.value_type.size == 0)
          fail(path, "cannot be parsed: bad PLY list property " + quote(line));
      } else if (tok.size() == 3) {
        p.value_type = ply_type(tok[1]);
        p.name = std::string(tok[2]);
        if (p.value_type.size == 0) fail(path, "cannot be parsed: unknown PLY property type " + quote(tok[1]));
      } else {
        fail(path, "cannot be parsed: malformed PLY property line " + quote(line));
      }
      if (ply_is_index_list(elements.back(), p) && (!p.is_list || p.value_type.is_float))
        fail(path, "cannot be parsed: PLY face indices must be a list of an integer type");
      elements.back().properties.push_back(p);
    } else if (elements.empty()) {
      // free text before the first element line describes no layout, so it is read as a comment
      // (and left out of the header handed to assimp): Blender 2.4x wrote its "Created by
      // Blender3D ..." line there without the comment keyword
      continue;
    } else {
      // assimp ends an element's property list at any other line, so the body would be read
      // with another layout than the one checked here (one fuzz input: a stray line between two
      // vertex properties made assimp read a face with an empty index list, and abort)
      fail(path, "cannot be parsed: unknown PLY header line " + quote(line));
    }
  }
  if (!ended) fail(path, "cannot be parsed: truncated or malformed PLY header (no end_header line)");
  if (format == Format::unknown) fail(path, "cannot be parsed: PLY header has no format line");
  const PlyHeaderText header{pos, "ply\n" + format_line + element_lines + "end_header\n"};

  // Every declared count bounded by the bytes left before anything is walked (or allocated by
  // assimp): an ASCII item takes a line of at least 2 bytes, a binary one its fixed bytes.
  const std::uint64_t body = data.size() - pos;
  const bool ascii = format == Format::ascii;
  std::uint64_t num_vertices = 0;
  for (const auto& e : elements) {
    if (e.name == "vertex") num_vertices = e.count;
    if (e.count == 0) continue;
    if (e.properties.empty())
      fail(path, "cannot be parsed: PLY element '" + e.name + "' declares " + std::to_string(e.count) +
                     " items but no properties");
    std::uint64_t min_bytes = 0;
    for (const auto& p : e.properties) min_bytes += static_cast<std::uint64_t>(p.is_list ? p.count_type.size : p.value_type.size);
    if (ascii) min_bytes = 2;
    if (e.count > body / min_bytes)
      fail(path, "cannot be parsed: truncated or corrupt PLY file: element '" + e.name + "' declares " + std::to_string(e.count) +
                     " items, more than the " +
                     std::to_string(body) + " bytes after the header can hold");
  }

  auto truncated = [&](const PlyElement& e, std::uint64_t item) {
    fail(path, "cannot be parsed: truncated PLY file, data ends in element '" + e.name + "' (item " + std::to_string(item) +
                   " of " + std::to_string(e.count) + ")");
  };
  auto check_index = [&](long long idx, const PlyElement& e, std::uint64_t item) {
    if (e.name == "tristrips" && idx == -1) return;  // strip restart
    if (idx < 0 || static_cast<std::uint64_t>(idx) >= num_vertices)
      fail(path, "face " + std::to_string(item) + " has vertex index " + std::to_string(idx) + " outside [0, " +
                     std::to_string(num_vertices) + ")");
  };
  auto empty_list = [&](const PlyElement& e, std::uint64_t item) {
    fail(path, "cannot be parsed: PLY " + e.name + " " + std::to_string(item) + " has an empty vertex index list");
  };

  if (ascii) {
    // one item per line, exactly the declared values, each a number of its property's type
    for (const auto& e : elements) {
      for (std::uint64_t i = 0; i < e.count; ++i) {
        if (!next_line(path, data, pos, line, "the PLY body")) truncated(e, i);
        const auto tok = split_tokens(line);
        if (tok.empty())
          fail(path, "cannot be parsed: blank line in the PLY body where item " + std::to_string(i) + " of element '" + e.name +
                         "' is due");
        std::size_t t = 0;
        auto value = [&](const PlyType& type) {
          if (t >= tok.size())
            fail(path, "cannot be parsed: PLY element '" + e.name + "' item " + std::to_string(i) + " has fewer values than declared");
          const std::string_view v = tok[t++];
          long long ignored = 0;
          if (type.is_float ? !is_number(v) : !parse_integer(v, ignored))
            fail(path, "cannot be parsed: non-numeric token " + quote(v) + " where a" + (type.is_float ? " number" : "n integer") +
                           " is due in PLY element '" + e.name + "' item " + std::to_string(i));
          return v;
        };
        for (const auto& prop : e.properties) {
          if (!prop.is_list) {
            value(prop.value_type);
            continue;
          }
          long long n = 0;
          parse_integer(value(prop.count_type), n);
          if (n < 0 || static_cast<std::uint64_t>(n) > tok.size() - t)
            fail(path, "cannot be parsed: bad list length " + std::to_string(n) + " in PLY element '" + e.name + "' item " +
                           std::to_string(i));
          const bool indices = ply_is_index_list(e, prop);
          if (indices && n == 0) empty_list(e, i);
          for (long long k = 0; k < n; ++k) {
            const std::string_view v = value(prop.value_type);
            long long idx = 0;
            if (indices && parse_integer(v, idx)) check_index(idx, e, i);
          }
        }
        if (t != tok.size())
          fail(path, "cannot be parsed: PLY element '" + e.name + "' item " + std::to_string(i) + " has " +
                         std::to_string(tok.size()) + " values, more than declared");
      }
    }
    return header;
  }

  const bool big = format == Format::big;
  const auto* bytes = reinterpret_cast<const unsigned char*>(data.data());
  const std::uint64_t size = data.size();
  for (const auto& e : elements) {
    if (e.count == 0) continue;
    bool fixed = true;
    std::uint64_t stride = 0;
    for (const auto& prop : e.properties) {
      fixed = fixed && !prop.is_list;
      stride += static_cast<std::uint64_t>(prop.value_type.size);
    }
    if (fixed) {
      if (e.count > (size - pos) / stride) truncated(e, (size - pos) / stride);
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
        if (ply_is_index_list(e, prop)) {
          if (n == 0) empty_list(e, i);
          for (long long k = 0; k < n; ++k)
            check_index(ply_read_integer(bytes + pos + static_cast<std::uint64_t>(k) * vsize, prop.value_type, big), e, i);
        }
        pos += static_cast<std::uint64_t>(n) * vsize;
      }
    }
  }
  return header;
}

}  // namespace impact::detail::mesh_file
