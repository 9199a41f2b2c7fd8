// SPDX-License-Identifier: MIT
// Reader of the CCD query files with exact ground truth (ccd-queries/<scene>/{vertex-face,
// edge-edge}/*.csv): 8 rows per query, 7 integer columns xn,xd,yn,yd,zn,zd,truth. Each rational
// is converted to double exactly, and the conversion is proven exact: the denominator must be a
// power of two and the numerator's odd part must fit in 53 bits with the exponent in range.
// Shared by the ccd tests and impact-ccd-bench.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace impact::test {

/// One query: the 8 points in file order (vertex-face: p, f0, f1, f2 at t0 then at t1;
/// edge-edge: a0, a1, b0, b1 at t0 then at t1) and the exact answer.
struct CcdQueryRecord {
  std::array<Eigen::Vector3d, 8> points;
  bool truth = false;
};

/// Converts the decimal integer ratio num/den to a double when it is exactly representable;
/// returns false otherwise (or when the text is not an integer). Arbitrary length.
inline bool exact_ratio_to_double(const std::string& num, const std::string& den, double& out) {
  // Parse a decimal string into little-endian 32-bit limbs, with a sign.
  auto parse = [](const std::string& s, std::vector<std::uint32_t>& limbs, bool& neg) {
    std::size_t i = 0;
    neg = false;
    if (i < s.size() && (s[i] == '-' || s[i] == '+')) neg = s[i++] == '-';
    if (i == s.size()) return false;
    limbs.clear();
    for (; i < s.size(); ++i) {
      if (s[i] < '0' || s[i] > '9') return false;
      std::uint64_t carry = std::uint64_t(s[i] - '0');
      for (auto& l : limbs) {
        const std::uint64_t x = std::uint64_t(l) * 10u + carry;
        l = std::uint32_t(x);
        carry = x >> 32;
      }
      if (carry) limbs.push_back(std::uint32_t(carry));
    }
    while (!limbs.empty() && limbs.back() == 0) limbs.pop_back();
    return true;
  };
  auto bit = [](const std::vector<std::uint32_t>& l, std::size_t k) { return (l[k / 32] >> (k % 32)) & 1u; };
  std::vector<std::uint32_t> n, d;
  bool nneg = false, dneg = false;
  if (!parse(num, n, nneg) || !parse(den, d, dneg)) return false;
  if (d.empty()) return false;  // division by zero
  // The denominator must be a power of two: exactly one bit set.
  std::size_t dbits = 0, dexp = 0;
  for (std::size_t k = 0; k < d.size() * 32; ++k)
    if (bit(d, k)) {
      ++dbits;
      dexp = k;
    }
  if (dbits != 1) return false;
  if (n.empty()) {
    out = 0.0;
    return true;
  }
  std::size_t lowest = 0, highest = 0;
  bool seen = false;
  for (std::size_t k = 0; k < n.size() * 32; ++k)
    if (bit(n, k)) {
      if (!seen) lowest = k;
      seen = true;
      highest = k;
    }
  if (highest - lowest >= 53) return false;  // odd part needs more than 53 bits
  std::uint64_t odd = 0;
  for (std::size_t k = highest + 1; k-- > lowest;) odd = (odd << 1) | bit(n, k);
  // value = odd * 2^(lowest - dexp); odd < 2^53. Exact iff the result is neither below the
  // subnormal range (lowest set bit >= 2^-1074) nor above the largest double.
  const long e = long(lowest) - long(dexp);
  const long top = e + long(highest - lowest);  // exponent of the leading bit
  if (e < -1074 || top > 1023) return false;
  out = std::ldexp(double(odd), int(e));
  if (nneg != dneg) out = -out;
  // Verify: the double, scaled back by the exponent, gives back the odd integer.
  return std::ldexp(std::abs(out), int(-e)) == double(odd);
}

/// Reads one query file. Throws std::runtime_error on a malformed row, a rational that is not an
/// exact double, a row count that is not a multiple of 8, or truth values differing inside a query.
inline std::vector<CcdQueryRecord> read_ccd_queries(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  std::vector<CcdQueryRecord> out;
  std::string line;
  std::size_t row = 0;
  CcdQueryRecord q;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    std::vector<std::string> cols;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) cols.push_back(c);
    if (cols.size() != 7)
      throw std::runtime_error(path + ": row " + std::to_string(row + 1) + " has " + std::to_string(cols.size()) + " columns");
    const std::size_t k = row % 8;
    for (int i = 0; i < 3; ++i) {
      double v = 0;
      if (!exact_ratio_to_double(cols[2 * i], cols[2 * i + 1], v))
        throw std::runtime_error(path + ": row " + std::to_string(row + 1) + ": " + cols[2 * i] + "/" + cols[2 * i + 1] +
                                 " is not an exact double");
      q.points[k][i] = v;
    }
    const bool truth = cols[6] == "1";
    if (!truth && cols[6] != "0") throw std::runtime_error(path + ": bad truth value " + cols[6]);
    if (k == 0)
      q.truth = truth;
    else if (q.truth != truth)
      throw std::runtime_error(path + ": truth differs inside a query at row " + std::to_string(row + 1));
    if (k == 7) out.push_back(q);
    ++row;
  }
  if (row % 8 != 0) throw std::runtime_error(path + ": row count not a multiple of 8");
  return out;
}

/// The query files of one kind ("vertex-face" or "edge-edge") under root (the ccd-queries folder):
/// root/<scene>/<kind>/*.csv, sorted by path.
inline std::vector<std::string> find_ccd_query_files(const std::string& root, const std::string& kind) {
  namespace fs = std::filesystem;
  std::vector<std::string> files;
  std::error_code ec;
  if (!fs::is_directory(root, ec)) return files;
  for (const auto& scene : fs::directory_iterator(root, ec)) {
    const fs::path dir = scene.path() / kind;
    if (!fs::is_directory(dir, ec)) continue;
    for (const auto& f : fs::directory_iterator(dir, ec))
      if (f.path().extension() == ".csv") files.push_back(f.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace impact::test
