// SPDX-License-Identifier: MIT
// Small shared pieces of the bench programs: timing, summary statistics, a minimal JSON writer,
// and loading a mesh from a path (through impact::io when built with it).
#pragma once

#include "impact/geometry/triangle_mesh.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#ifdef IMPACT_HAVE_IO
#include "impact/io/load_mesh.hpp"
#endif

namespace impact::bench {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct Summary {
  double median = 0, mean = 0, p99 = 0, max = 0;
};

inline Summary summarize(std::vector<double> v) {
  Summary s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  s.median = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
  s.mean = std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
  s.p99 = v[std::min(v.size() - 1, static_cast<std::size_t>(0.99 * double(v.size())))];
  s.max = v.back();
  return s;
}

/// Builds one JSON object or array by hand (flat values, nested objects/arrays as raw strings).
class JsonObject {
 public:
  JsonObject& add(const std::string& k, const std::string& v) { return raw(k, quote(v)); }
  JsonObject& add(const std::string& k, const char* v) { return raw(k, quote(v)); }
  JsonObject& add(const std::string& k, double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.9g", v);
    return raw(k, buf);
  }
  JsonObject& add(const std::string& k, long long v) { return raw(k, std::to_string(v)); }
  JsonObject& add(const std::string& k, int v) { return raw(k, std::to_string(v)); }
  JsonObject& add(const std::string& k, std::size_t v) { return raw(k, std::to_string(v)); }
  JsonObject& add(const std::string& k, bool v) { return raw(k, v ? "true" : "false"); }
  JsonObject& raw(const std::string& k, const std::string& v) {
    body_ += (body_.empty() ? "" : ", ") + quote(k) + ": " + v;
    return *this;
  }
  std::string str() const { return "{" + body_ + "}"; }
  static std::string quote(const std::string& s) {
    std::string o = "\"";
    for (char c : s) {
      if (c == '"' || c == '\\') o += '\\';
      o += c;
    }
    return o + "\"";
  }
  static std::string array(const std::vector<std::string>& items) {
    std::string o = "[";
    for (std::size_t i = 0; i < items.size(); ++i) o += (i ? ",\n  " : "\n  ") + items[i];
    return o + "\n]";
  }

 private:
  std::string body_;
};

inline bool write_file(const std::string& path, const std::string& text) {
  std::ofstream f(path);
  f << text << "\n";
  return bool(f);
}

}  // namespace impact::bench
