// SPDX-License-Identifier: MIT
// Small shared pieces of the bench programs: timing (wall clock, thread and process CPU time),
// summary statistics, a minimal JSON writer, command-line helpers, and loading a mesh from a path
// (through impact::io when built with it).
#pragma once

#include "impact/core/error.hpp"
#include "impact/geometry/triangle_mesh.hpp"
#include "support/obj_reader.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>
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

/// Wall-clock seconds since an arbitrary origin (steady clock).
inline double wall_seconds() { return std::chrono::duration<double>(Clock::now().time_since_epoch()).count(); }

/// CPU seconds of the calling thread: the benchmark machine may be shared, and the wall clock then
/// measures the neighbours as much as the method. Falls back to the wall clock off POSIX.
inline double thread_seconds() {
#if defined(CLOCK_THREAD_CPUTIME_ID)
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
#else
  return wall_seconds();
#endif
}

/// CPU seconds of the whole process (every thread).
inline double process_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

/// The speed-up of a T-thread run over a one-thread run that an otherwise idle machine would show,
/// from CPU times: the calling thread runs the serial parts and its share of the parallel ones,
/// the T - 1 workers share the rest, so the run takes at least max(caller, (process - caller) /
/// (T - 1)). `one_thread`: the CPU time of the one-thread run; `caller`, `process`: the calling
/// thread's and the process's CPU time over the T-thread run.
inline double cpu_speedup(double one_thread, double caller, double process, int threads) {
  const double workers = threads > 1 ? (process - caller) / (threads - 1) : 0;
  return one_thread / std::max({caller, workers, 1e-12});
}

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

/// Prints `msg` and a bench's usage text (which starts with "usage:" and ends with a newline) to
/// stderr and exits with status 2.
[[noreturn]] inline void exit_usage(const std::string& msg, const char* usage) {
  std::fprintf(stderr, "%s\n%s", msg.c_str(), usage);
  std::exit(2);
}

/// The value of the option argv[i]: argv[i + 1], with i moved onto it; exits through
/// exit_usage("missing value after <option>") when there is none.
inline std::string option_value(int argc, char** argv, int& i, const char* usage) {
  if (i + 1 >= argc) exit_usage("missing value after " + std::string(argv[i]), usage);
  return argv[++i];
}

/// The integer an option was given, which must lie in [lo, hi]: the whole of `text` a decimal
/// integer (an optional sign, digits, nothing after them), else the bench exits through exit_usage
/// naming the option, its range and the text. atoi would take "12x" for 12, "abc" for 0 and
/// overflow silently; a bench must not run on a number nobody typed.
inline long long parse_integer(const std::string& option, const std::string& text, long long lo, long long hi,
                               const char* usage) {
  const auto bad = [&] {
    exit_usage(option + " wants an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], not '" + text + "'",
               usage);
  };
  if (text.empty() || std::isspace(static_cast<unsigned char>(text[0]))) bad();
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (errno != 0 || end != text.c_str() + text.size() || v < lo || v > hi) bad();
  return v;
}

/// The real number an option was given: the whole of `text` a finite number in [lo, hi], else the
/// bench exits through exit_usage as parse_integer does.
inline double parse_real(const std::string& option, const std::string& text, double lo, double hi, const char* usage) {
  const auto bad = [&] {
    std::ostringstream range;
    range << option << " wants a number in [" << lo << ", " << hi << "], not '" << text << "'";
    exit_usage(range.str(), usage);
  };
  if (text.empty() || std::isspace(static_cast<unsigned char>(text[0]))) bad();
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (errno == ERANGE || end != text.c_str() + text.size() || !std::isfinite(v) || !(v >= lo && v <= hi)) bad();
  return v;
}

/// A seed: the whole of `text` an unsigned 64-bit decimal integer, else exit_usage.
inline std::uint64_t parse_seed(const std::string& option, const std::string& text, const char* usage) {
  const auto bad = [&] { exit_usage(option + " wants an unsigned 64-bit integer, not '" + text + "'", usage); };
  if (text.empty() || !std::isdigit(static_cast<unsigned char>(text[0]))) bad();
  errno = 0;
  char* end = nullptr;
  const unsigned long long v = std::strtoull(text.c_str(), &end, 10);
  if (errno != 0 || end != text.c_str() + text.size()) bad();
  return std::uint64_t(v);
}

/// Checks at once that the file given to `option` (--json by default) can be written (it is
/// created, or opened for appending when it exists), so that a bad path is reported before the
/// bench runs, not after minutes of work. The bench writes the file whole at its end.
inline void check_writable(const std::string& path, const char* usage, const std::string& option = "--json") {
  if (path.empty()) return;
  std::ofstream f(path, std::ios::app);
  if (!f) exit_usage("cannot write the " + option + " file '" + path + "'", usage);
}

/// A word of the command line that is no option the bench knows: "-h" and "--help" print the
/// usage, any other word starting with '-' is an unknown option; exits either way.
[[noreturn]] inline void reject_option(const std::string& word, const char* usage) {
  exit_usage(word == "-h" || word == "--help" ? "" : "unknown option " + word, usage);
}

#ifdef IMPACT_HAVE_IO
/// The benches' load options: the defaults, and with IMPACT_BENCH_TRUSTED_FILES=1 in the
/// environment also the formats whose assimp readers are not safe on hostile files
/// (LoadOptions::allow_unchecked_formats: .nff, .zae, .ifc, ...), for files you trust, such as
/// Debian's assimp-testmodels.
inline LoadOptions bench_load_options() {
  LoadOptions o;
  const char* trusted = std::getenv("IMPACT_BENCH_TRUSTED_FILES");
  o.allow_unchecked_formats = trusted != nullptr && std::string(trusted) == "1";
  return o;
}
#endif

/// The mesh at `path`: through impact::io when the bench is built with it (bench_load_options),
/// else through the tests' OBJ reader (OBJ files only). Throws on a file it cannot read.
template <class S>
TriangleMesh<S> read_mesh(const std::string& path) {
#ifdef IMPACT_HAVE_IO
  return load_mesh<S>(path, bench_load_options());
#else
  return impact::test::read_obj<S>(path);
#endif
}

/// Throws InvalidInput naming `name` when the mesh has no extent (every vertex at one point, as in
/// files whose triangles all collapsed): the ray, hierarchy, particles, convex and mesh-CCD benches
/// size their rays, particles, shapes and motions by the mesh's bounding box, which is then a
/// point (they hung or aborted on such files).
template <class S> void require_extent(const TriangleMesh<S>& m, const std::string& name) {
  if (m.num_vertices() == 0 || (m.V.colwise().maxCoeff() - m.V.colwise().minCoeff()).maxCoeff() > S(0)) return;
  throw InvalidInput(name + ": the mesh has no extent (every vertex at one point); this bench sizes its queries by the mesh's bounding box");
}

/// The mesh at `path` in double, through impact::io; in a build without it (assimp not found),
/// exits through exit_usage.
inline TriangleMesh<double> load_mesh_or_exit(const std::string& path, const char* usage) {
#ifdef IMPACT_HAVE_IO
  (void)usage;
  return load_mesh<double>(path, bench_load_options());
#else
  (void)path;
  exit_usage("this build has no mesh loader (assimp was not found); run without meshes", usage);
#endif
}

}  // namespace impact::bench
