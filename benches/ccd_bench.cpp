// SPDX-License-Identifier: MIT
// impact-ccd-bench [DIR...] [--json FILE] [--min-separation D] [--tolerance T]
//                  [--max-iterations N] [--recheck N] [--repeat R] [--generated N] [--no-sweep]
//                  [--transform NAME] [--no-metamorphic]
// Runs vertex_face_ccd and edge_edge_ccd over CCD query files with exact ground truth and reports,
// per file and in total, for each kind: queries, positives, false positives, false negatives and
// the mean, p99 and max time per query in microseconds; then a sweep of tolerance, minimum
// separation and re-check budget (--recheck N sets CcdOptions::recheck_iterations; 0 is the
// double-precision search alone) against time and false positives. Each DIR is searched recursively for
// .../vertex-face/*.csv and .../edge-edge/*.csv; without DIR it reads $IMPACT_DATA_DIR/ccd-queries,
// and without that it generates queries (constructed contacts with known truth, and random ones
// whose truth is unknown and not counted in FP/FN). The time of a query is the minimum over R
// runs (default 3), which filters out preemption on a shared machine.
// Metamorphic section (after the sweep; --no-metamorphic skips it): every transform of
// tests/ccd/ccd_transforms.hpp that keeps the exact answer (time reversal, face vertex rotation
// and reflection, swapped and reversed edges, axis permutation, mirroring, scaling by 2^40 and
// 2^-40, exact translation) applied to every query, with FP, FN, budget exhaustions, decisions
// that differ from the untransformed query's, and mean/p99/max time. --transform NAME runs the
// main table on the transformed queries instead.
#include "bench_util.hpp"
#include "ccd/ccd_transforms.hpp"
#include "impact/ccd/edge_edge.hpp"
#include "impact/ccd/vertex_face.hpp"
#include "support/ccd_queries.hpp"

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <random>

namespace {

using impact::bench::Clock;
using impact::test::CcdQueryRecord;

struct QuerySet {
  std::string file, kind;
  std::vector<CcdQueryRecord> queries;
  std::vector<int> truth;  // 1, 0, or -1 when unknown
};

struct Row {
  std::string file, kind;
  std::size_t queries = 0, positives = 0, fp = 0, fn = 0, exhausted = 0;
  double mean = 0, p99 = 0, max = 0;
  std::vector<char> hits;  // per query
};

impact::CcdResult<double> run_one(const std::string& kind, const CcdQueryRecord& q, const impact::CcdOptions& o) {
  const auto& p = q.points;
  if (kind == "vertex-face") return impact::vertex_face_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], o);
  return impact::edge_edge_ccd(p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], o);
}

int g_repeat = 3;

Row run_set(const QuerySet& s, const impact::CcdOptions& o) {
  Row r;
  r.file = s.file;
  r.kind = s.kind;
  std::vector<double> us;
  us.reserve(s.queries.size());
  for (std::size_t i = 0; i < s.queries.size(); ++i) {
    impact::CcdResult<double> res;
    double best = 1e300;
    for (int k = 0; k < g_repeat; ++k) {
      const auto t0 = Clock::now();
      res = run_one(s.kind, s.queries[i], o);
      best = std::min(best, 1e6 * impact::bench::seconds_since(t0));
    }
    us.push_back(best);
    ++r.queries;
    r.hits.push_back(res.hit ? 1 : 0);
    r.exhausted += res.budget_exhausted ? 1 : 0;
    if (s.truth[i] == 1) ++r.positives;
    if (s.truth[i] == 1 && !res.hit) ++r.fn;
    if (s.truth[i] == 0 && res.hit) ++r.fp;
  }
  const auto sm = impact::bench::summarize(us);
  r.mean = sm.mean;
  r.p99 = sm.p99;
  r.max = sm.max;
  return r;
}

// Sum of rows of one kind; p99 and max over all queries need the raw times, so re-time them.
Row total(const std::vector<QuerySet>& sets, const std::string& kind, const impact::CcdOptions& o) {
  QuerySet all;
  all.file = "total";
  all.kind = kind;
  for (const auto& s : sets)
    if (s.kind == kind) {
      all.queries.insert(all.queries.end(), s.queries.begin(), s.queries.end());
      all.truth.insert(all.truth.end(), s.truth.begin(), s.truth.end());
    }
  return run_set(all, o);
}

void collect(const std::string& dir, std::vector<QuerySet>& sets) {
  namespace fs = std::filesystem;
  std::vector<std::string> files;
  std::error_code ec;
  if (fs::is_regular_file(dir, ec))
    files.push_back(dir);
  else
    for (const auto& e : fs::recursive_directory_iterator(dir, ec))
      if (e.path().extension() == ".csv") files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    const std::string kind = fs::path(f).parent_path().filename().string();
    if (kind != "vertex-face" && kind != "edge-edge") continue;
    QuerySet s;
    s.kind = kind;
    // Name: <scene>/<kind>/<file>.
    const fs::path p(f);
    s.file = (p.parent_path().parent_path().filename() / p.parent_path().filename() / p.filename()).string();
    s.queries = impact::test::read_ccd_queries(f);
    for (const auto& q : s.queries) s.truth.push_back(q.truth ? 1 : 0);
    sets.push_back(std::move(s));
  }
}

// Generated queries: contacts built at a known time (truth 1) and random motions (truth unknown).
void generate(std::size_t n, std::vector<QuerySet>& sets) {
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> U(-1.0, 1.0), T(0.0, 1.0);
  auto rnd = [&] { return Eigen::Vector3d(U(rng), U(rng), U(rng)); };
  for (const std::string kind : {"vertex-face", "edge-edge"}) {
    QuerySet s;
    s.file = "generated";
    s.kind = kind;
    for (std::size_t i = 0; i < n; ++i) {
      CcdQueryRecord q;
      if (i % 2 == 0) {
        // Random motion, unknown truth.
        for (auto& p : q.points) p = rnd();
        s.truth.push_back(-1);
      } else {
        // Contact at time tc: build positions at tc with p on the triangle (or the two edge points
        // equal), then move back and forth with random velocities. Rounding may break the exact
        // contact by an ulp, so truth stays unknown; the query is still a near-contact stress case.
        const double tc = T(rng), a = T(rng), b = T(rng) * (1 - a);
        Eigen::Vector3d at[4];
        for (auto& p : at) p = rnd();
        if (kind == "vertex-face")
          at[0] = (1 - a - b) * at[1] + a * at[2] + b * at[3];
        else
          at[0] = at[2] + b * (at[3] - at[2]) - a * (at[1] - at[0]);
        for (int k = 0; k < 4; ++k) {
          const Eigen::Vector3d vel = rnd();
          q.points[std::size_t(k)] = at[k] - tc * vel;
          q.points[std::size_t(k) + 4] = at[k] + (1 - tc) * vel;
        }
        s.truth.push_back(-1);
      }
      s.queries.push_back(q);
    }
    sets.push_back(std::move(s));
  }
}

std::string json_row(const Row& r, bool with_file) {
  impact::bench::JsonObject o;
  if (with_file) o.add("file", r.file);
  o.add("kind", r.kind)
      .add("queries", r.queries)
      .add("positives", r.positives)
      .add("false_positives", r.fp)
      .add("false_negatives", r.fn)
      .add("budget_exhausted", r.exhausted)
      .add("mean_us", r.mean)
      .add("p99_us", r.p99)
      .add("max_us", r.max);
  return o.str();
}

void print_row(const Row& r) {
  std::printf("%-52s %-12s %8zu %9zu %6zu %6zu %10.3f %10.3f %10.3f\n", r.file.c_str(), r.kind.c_str(), r.queries, r.positives,
              r.fp, r.fn, r.mean, r.p99, r.max);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> dirs;
  std::string json;
  impact::CcdOptions opt;
  std::size_t generated = 0;
  bool sweep = true, metamorphic = true;
  std::string transform;
  const char* usage =
      "usage: impact-ccd-bench [DIR...] [--json FILE] [--min-separation D] [--tolerance T] [--max-iterations N] [--recheck N] "
      "[--repeat R] [--generated N] [--no-sweep] [--transform NAME] [--no-metamorphic]\n";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&] { return impact::bench::option_value(argc, argv, i, usage); };
    if (a == "--json")
      json = next();
    else if (a == "--min-separation")
      opt.min_separation = impact::bench::parse_real(a, next(), 0, 1e100, usage);
    else if (a == "--tolerance")
      opt.tolerance = impact::bench::parse_real(a, next(), 0, 1e100, usage);
    else if (a == "--max-iterations")
      opt.max_iterations = impact::bench::parse_integer(a, next(), 1, std::int64_t(1) << 22, usage);
    else if (a == "--recheck")
      opt.recheck_iterations = impact::bench::parse_integer(a, next(), 0, std::int64_t(1) << 22, usage);
    else if (a == "--repeat")
      g_repeat = int(impact::bench::parse_integer(a, next(), 1, 1000, usage));
    else if (a == "--generated")
      generated = std::size_t(impact::bench::parse_integer(a, next(), 0, 10000000, usage));
    else if (a == "--no-sweep")
      sweep = false;
    else if (a == "--no-metamorphic")
      metamorphic = false;
    else if (a == "--transform") {
      transform = next();
      const auto& names = impact::test::ccd_transform_names();
      if (std::find(names.begin(), names.end(), transform) == names.end()) {
        std::fprintf(stderr, "unknown transform %s\n", transform.c_str());
        return 2;
      }
    }
    else if (a == "--help" || a == "-h") {
      std::printf("%s", usage);
      std::printf("transforms:");
      for (const auto& n : impact::test::ccd_transform_names()) std::printf(" %s", n.c_str());
      std::printf("\n");
      return 0;
    } else if (!a.empty() && a[0] == '-') {
      impact::bench::reject_option(a, usage);
    } else
      dirs.push_back(a);
  }
  impact::bench::check_writable(json, usage);
  std::vector<QuerySet> sets;
  try {
    if (dirs.empty() && generated == 0) {
      const char* d = std::getenv("IMPACT_DATA_DIR");
      if (d && *d && std::filesystem::is_directory(std::string(d) + "/ccd-queries"))
        dirs.push_back(std::string(d) + "/ccd-queries");
    }
    for (const auto& d : dirs) collect(d, sets);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "impact-ccd-bench: %s\n", e.what());
    return 1;
  }
  if (sets.empty()) {
    if (!dirs.empty()) {
      std::fprintf(stderr, "impact-ccd-bench: no query files found\n");
      return 1;
    }
    std::printf("no query files: using %zu generated queries per kind (truth unknown, FP/FN not counted)\n",
                generated ? generated : 2000);
    generate(generated ? generated : 2000, sets);
  }

  if (!transform.empty()) {
    // Transform every query that it applies to (the others are left out of the run).
    for (auto& s : sets) {
      QuerySet t;
      t.file = s.file;
      t.kind = s.kind;
      for (std::size_t i = 0; i < s.queries.size(); ++i) {
        auto q = s.queries[i];
        if (!impact::test::apply_ccd_transform(transform, s.kind, q)) continue;
        t.queries.push_back(q);
        t.truth.push_back(s.truth[i]);
      }
      s = std::move(t);
    }
    std::printf("transform %s applied to every query it applies to\n", transform.c_str());
  }
  std::printf("tolerance %g, min_separation %g, max_iterations %lld, recheck_iterations %lld, time = min of %d runs per query\n",
              opt.tolerance, opt.min_separation, static_cast<long long>(opt.max_iterations),
              static_cast<long long>(opt.recheck_iterations), g_repeat);
  std::printf("%-52s %-12s %8s %9s %6s %6s %10s %10s %10s\n", "file", "kind", "queries", "positives", "FP", "FN", "mean_us",
              "p99_us", "max_us");
  std::vector<std::string> results, totals, sweeps, metamorphics;
  for (const auto& s : sets) {
    const Row r = run_set(s, opt);
    print_row(r);
    results.push_back(json_row(r, true));
  }
  bool any_fn = false;
  std::map<std::string, Row> base;
  for (const std::string kind : {"vertex-face", "edge-edge"}) {
    const Row r = total(sets, kind, opt);
    if (r.queries == 0) continue;
    print_row(r);
    std::printf("%-52s %-12s budget exhausted on %zu queries\n", "", kind.c_str(), r.exhausted);
    totals.push_back(json_row(r, false));
    any_fn = any_fn || r.fn > 0;
    base[kind] = r;
  }

  if (sweep) {
    std::printf(
        "\nsweep: time and false positives against tolerance, min separation and re-check budget (FN = misses of d = 0 "
        "contacts)\n");
    std::printf("%10s %14s %8s %-12s %8s %6s %6s %10s %10s %10s\n", "tolerance", "min_sep", "recheck", "kind", "queries", "FP", "FN",
                "mean_us", "p99_us", "max_us");
    struct P {
      double tol, d;
      std::int64_t recheck;
    };
    const std::int64_t rc = opt.recheck_iterations;
    const P grid[] = {{1e-3, 0, rc},   {1e-4, 0, rc},    {1e-5, 0, rc},    {1e-6, 0, rc},    {1e-7, 0, rc},
                      {1e-8, 0, rc},   {1e-6, 0, 0},     {1e-8, 0, 0},     {1e-6, 0, 100},   {1e-6, 0, 200},
                      {1e-6, 0, 1600}, {1e-6, 1e-8, rc}, {1e-6, 1e-6, rc}, {1e-6, 1e-4, rc}, {1e-6, 1e-3, rc}};
    for (const P& g : grid)
      for (const std::string kind : {"vertex-face", "edge-edge"}) {
        impact::CcdOptions o = opt;
        o.tolerance = g.tol;
        o.min_separation = g.d;
        o.recheck_iterations = g.recheck;
        const Row r = total(sets, kind, o);
        if (r.queries == 0) continue;
        std::printf("%10.0e %14.0e %8lld %-12s %8zu %6zu %6zu %10.3f %10.3f %10.3f\n", g.tol, g.d, static_cast<long long>(g.recheck),
                    kind.c_str(), r.queries, r.fp, r.fn, r.mean, r.p99, r.max);
        impact::bench::JsonObject j;
        j.add("tolerance", g.tol)
            .add("min_separation", g.d)
            .add("recheck_iterations", static_cast<long long>(g.recheck))
            .raw("row", json_row(r, false));
        sweeps.push_back(j.str());
      }
  }

  if (metamorphic && transform.empty()) {
    std::printf(
        "\nmetamorphic: each transform applied to every query of the kinds it applies to (exact, so the ground truth holds); "
        "changed = decisions that differ from the untransformed query's\n");
    std::printf("%-14s %-12s %8s %6s %6s %8s %8s %10s %10s %10s\n", "transform", "kind", "queries", "FP", "FN", "budget", "changed",
                "mean_us", "p99_us", "max_us");
    for (const auto& name : impact::test::ccd_transform_names())
      for (const std::string kind : {"vertex-face", "edge-edge"}) {
        if (!impact::test::ccd_transform_applies(name, kind) || base.count(kind) == 0) continue;
        std::vector<QuerySet> tsets;
        std::size_t skipped = 0;
        for (const auto& s : sets) {
          if (s.kind != kind) continue;
          QuerySet t = s;
          for (auto& q : t.queries) skipped += impact::test::apply_ccd_transform(name, kind, q) ? 0 : 1;
          tsets.push_back(std::move(t));
        }
        const Row r = total(tsets, kind, opt);
        std::size_t changed = 0;
        for (std::size_t i = 0; i < r.hits.size(); ++i) changed += r.hits[i] != base[kind].hits[i];
        any_fn = any_fn || r.fn > 0;
        std::printf("%-14s %-12s %8zu %6zu %6zu %8zu %8zu %10.3f %10.3f %10.3f%s\n", name.c_str(), kind.c_str(), r.queries, r.fp, r.fn,
                    r.exhausted, changed, r.mean, r.p99, r.max, skipped ? " (some not transformed)" : "");
        impact::bench::JsonObject j;
        j.add("transform", name).add("changed_decisions", changed).add("not_transformed", skipped).raw("row", json_row(r, false));
        metamorphics.push_back(j.str());
      }
  }

  if (!json.empty()) {
    impact::bench::JsonObject o;
    o.add("tolerance", opt.tolerance)
        .add("min_separation", opt.min_separation)
        .add("max_iterations", static_cast<long long>(opt.max_iterations))
        .add("recheck_iterations", static_cast<long long>(opt.recheck_iterations))
        .raw("results", impact::bench::JsonObject::array(results))
        .raw("totals", impact::bench::JsonObject::array(totals))
        .raw("sweep", impact::bench::JsonObject::array(sweeps))
        .raw("metamorphic", impact::bench::JsonObject::array(metamorphics));
    if (!transform.empty()) o.add("transform", transform);
    if (!impact::bench::write_file(json, o.str())) {
      std::fprintf(stderr, "impact-ccd-bench: cannot write %s\n", json.c_str());
      return 1;
    }
  }
  return any_fn ? 3 : 0;
}
