// SPDX-License-Identifier: MIT
/// \file
/// Small text-scanning helpers shared by the format checks of load_mesh (ply_check.hpp,
/// off_check.hpp, stl_check.hpp): the error helper, line and token splitting that treats every
/// control byte the way assimp's parsers do (or rejects it), and the syntax of the numbers assimp
/// can parse. Internal: impact::detail::mesh_file.
#pragma once

#include "impact/core/error.hpp"

#include <cctype>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace impact::detail::mesh_file {

[[noreturn]] inline void fail(const std::string& path, const std::string& why) {
  throw InvalidInput("load_mesh: '" + path + "': " + why);
}

/// `s` as it may appear in a message: at most 40 bytes, non-printable bytes as \xNN.
inline std::string quote(std::string_view s) {
  std::string out = "'";
  const std::size_t n = s.size() < 40 ? s.size() : 40;
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (std::isprint(c)) {
      out.push_back(static_cast<char>(c));
    } else {
      static const char* hex = "0123456789abcdef";
      out += "\\x";
      out.push_back(hex[c >> 4]);
      out.push_back(hex[c & 15u]);
    }
  }
  return out + (s.size() > n ? "...'" : "'");
}

inline std::string lower_ascii(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

/// True when `s` starts with `prefix`, ignoring ASCII case.
inline bool starts_with_ci(std::string_view s, std::string_view prefix) {
  return s.size() >= prefix.size() && lower_ascii(s.substr(0, prefix.size())) == lower_ascii(prefix);
}

/// A control byte other than tab, carriage return and line feed: assimp's text parsers end lines
/// (or the whole file) at NUL and form feed, and split tokens differently from us at the others,
/// so a text format holding one is rejected rather than guessed at.
inline bool is_stray_control(unsigned char c) { return (c < 32 && c != '\t' && c != '\r' && c != '\n') || c == 127; }

/// The next line of `data` from `pos`: its bytes up to "\n" or "\r\n" (or the end of the data),
/// pos moved past the terminator. False at the end of the data. Throws on a stray control byte
/// or a "\r" not followed by "\n" (assimp reads those as line ends of their own).
inline bool next_line(const std::string& path, const std::string& data, std::size_t& pos, std::string_view& line,
                      const char* where) {
  if (pos >= data.size()) return false;
  std::size_t end = data.find('\n', pos);
  const std::size_t next = end == std::string::npos ? data.size() : end + 1;
  if (end == std::string::npos) end = data.size();
  if (end > pos && data[end - 1] == '\r' && end < data.size()) --end;
  for (std::size_t i = pos; i < end; ++i) {
    const auto c = static_cast<unsigned char>(data[i]);
    if (is_stray_control(c) || c == '\r')
      fail(path, std::string("cannot be parsed: control byte ") + quote(std::string_view(&data[i], 1)) + " in " + where);
  }
  line = std::string_view(data).substr(pos, end - pos);
  pos = next;
  return true;
}

/// Tokens of a line split at spaces and tabs.
inline std::vector<std::string_view> split_tokens(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const std::size_t b = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > b) out.push_back(line.substr(b, i - b));
  }
  return out;
}

/// Parses a token made only of decimal digits (at most 18) into value; false otherwise.
inline bool parse_count(std::string_view t, std::uint64_t& value) {
  if (t.empty() || t.size() > 18) return false;
  value = 0;
  for (const char c : t) {
    if (c < '0' || c > '9') return false;
    value = value * 10 + static_cast<std::uint64_t>(c - '0');
  }
  return true;
}

/// Parses an optionally signed decimal integer token (at most 18 digits); false otherwise.
inline bool parse_integer(std::string_view t, long long& value) {
  const bool negative = !t.empty() && t[0] == '-';
  if (!t.empty() && (t[0] == '-' || t[0] == '+')) t.remove_prefix(1);
  std::uint64_t u = 0;
  if (!parse_count(t, u)) return false;
  value = negative ? -static_cast<long long>(u) : static_cast<long long>(u);
  return true;
}

/// True when the whole token is a decimal floating-point number assimp's parsers read in full:
/// [+-] digits [. digits] [e [+-] digits], or [+-] . digits [...], or nan / inf / infinity (any case;
/// load_mesh rejects non-finite coordinates afterwards with its own message).
inline bool is_number(std::string_view t) {
  std::size_t i = 0;
  if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
  const std::string rest = lower_ascii(t.substr(i));
  if (rest == "nan" || rest == "inf" || rest == "infinity") return true;
  auto digits = [&](std::size_t& k) {
    const std::size_t b = k;
    while (k < t.size() && t[k] >= '0' && t[k] <= '9') ++k;
    return k > b;
  };
  const bool whole = digits(i);
  bool fraction = false;
  if (i < t.size() && t[i] == '.') {
    ++i;
    fraction = digits(i);
  }
  if (!whole && !fraction) return false;
  if (i < t.size() && (t[i] == 'e' || t[i] == 'E')) {
    ++i;
    if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
    if (!digits(i)) return false;
  }
  return i == t.size();
}

}  // namespace impact::detail::mesh_file
