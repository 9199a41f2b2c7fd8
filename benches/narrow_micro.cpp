// SPDX-License-Identifier: MIT
// Micro-benchmarks of the narrow-phase primitives on fixed, seeded sets of primitive pairs:
// triangles_intersect on intersecting and on disjoint pairs whose bounding spheres overlap (the
// pairs a BVH leaf test sees), and on leaf-like groups (one triangle against 16 neighbours, plain
// and with the first triangle prepared); FCL's Intersect<double>::intersect_Triangle on the same
// pairs when FCL is available; watertight ray–triangle and closest point on triangle. `--json FILE` writes Google Benchmark's JSON report.
#include "impact/narrow/closest_point.hpp"
#include "impact/narrow/ray_triangle.hpp"
#include "impact/narrow/triangle_triangle.hpp"
#include "support/random.hpp"

#include <benchmark/benchmark.h>

#ifdef IMPACT_HAVE_FCL
#include <fcl/narrowphase/detail/traversal/collision/intersect.h>
#endif

#include <cstring>
#include <string>
#include <vector>

using namespace impact;

namespace {

constexpr std::size_t kPairs = 4096;

struct PairSet {
  std::vector<Triangle<double>> a, b;
};

/// Random unit-size triangles around nearby centres, kept when triangles_intersect == want and the
/// bounding spheres (about the centroids) overlap.
PairSet make_pairs(bool want, std::uint64_t seed) {
  test::Rng rng(seed);
  PairSet s;
  while (s.a.size() < kPairs) {
    const Eigen::Vector3d ca = rng.vec(-1, 1), cb = ca + rng.vec(-0.6, 0.6);
    const Triangle<double> ta(ca + rng.vec(-0.5, 0.5), ca + rng.vec(-0.5, 0.5), ca + rng.vec(-0.5, 0.5));
    const Triangle<double> tb(cb + rng.vec(-0.5, 0.5), cb + rng.vec(-0.5, 0.5), cb + rng.vec(-0.5, 0.5));
    auto radius = [](const Triangle<double>& t) {
      const Eigen::Vector3d c = t.centroid();
      return std::max({(t.a - c).norm(), (t.b - c).norm(), (t.c - c).norm()});
    };
    if ((ta.centroid() - tb.centroid()).norm() > radius(ta) + radius(tb)) continue;
    if (triangles_intersect(ta, tb) != want) continue;
    s.a.push_back(ta);
    s.b.push_back(tb);
  }
  return s;
}

const PairSet& pairs(bool intersecting) {
  static const PairSet yes = make_pairs(true, 1), no = make_pairs(false, 2);
  return intersecting ? yes : no;
}

void BM_impact_tri_tri(benchmark::State& state) {
  const PairSet& s = pairs(state.range(0) != 0);
  std::size_t i = 0, hits = 0;
  for (auto _ : state) {
    hits += triangles_intersect(s.a[i], s.b[i]);
    i = (i + 1) % kPairs;
  }
  benchmark::DoNotOptimize(hits);
  state.SetItemsProcessed(std::int64_t(state.iterations()));
}
BENCHMARK(BM_impact_tri_tri)->ArgName("intersecting")->Arg(1)->Arg(0);

void BM_impact_tri_tri_float(benchmark::State& state) {
  const PairSet& s = pairs(state.range(0) != 0);
  std::vector<Triangle<float>> a, b;
  for (std::size_t k = 0; k < kPairs; ++k) a.push_back(s.a[k].cast<float>()), b.push_back(s.b[k].cast<float>());
  std::size_t i = 0, hits = 0;
  for (auto _ : state) {
    hits += triangles_intersect(a[i], b[i]);
    i = (i + 1) % kPairs;
  }
  benchmark::DoNotOptimize(hits);
  state.SetItemsProcessed(std::int64_t(state.iterations()));
}
BENCHMARK(BM_impact_tri_tri_float)->ArgName("intersecting")->Arg(1)->Arg(0);

/// Leaf-like groups: each triangle of "mesh A" against 16 nearby triangles of "mesh B" whose
/// bounding spheres overlap it (about a tenth of them intersect), the pattern of a BVH leaf pair.
struct LeafSet {
  std::vector<Triangle<double>> a, b;  // b[16 g + k] is tested against a[g]
  std::size_t intersecting = 0;
};

const LeafSet& leaves() {
  static const LeafSet set = [] {
    test::Rng rng(5);
    LeafSet s;
    auto radius = [](const Triangle<double>& t) {
      const Eigen::Vector3d c = t.centroid();
      return std::max({(t.a - c).norm(), (t.b - c).norm(), (t.c - c).norm()});
    };
    while (s.a.size() < kPairs / 16) {
      const Eigen::Vector3d ca = rng.vec(-1, 1);
      const Triangle<double> ta(ca + rng.vec(-0.5, 0.5), ca + rng.vec(-0.5, 0.5), ca + rng.vec(-0.5, 0.5));
      s.a.push_back(ta);
      for (int k = 0; k < 16;) {
        const Eigen::Vector3d cb = ca + rng.vec(-0.6, 0.6);
        const Triangle<double> tb(cb + rng.vec(-0.5, 0.5), cb + rng.vec(-0.5, 0.5), cb + rng.vec(-0.5, 0.5));
        if ((ta.centroid() - tb.centroid()).norm() > radius(ta) + radius(tb)) continue;
        s.b.push_back(tb);
        s.intersecting += triangles_intersect(ta, tb);
        ++k;
      }
    }
    return s;
  }();
  return set;
}

/// One prepared triangle against its 16 leaf partners.
void BM_leaf_impact_prepared(benchmark::State& state) {
  const LeafSet& s = leaves();
  std::size_t g = 0, hits = 0;
  for (auto _ : state) {
    const PreparedTriangle<double> pa(s.a[g]);
    for (std::size_t k = 0; k < 16; ++k) hits += triangles_intersect(pa, s.b[16 * g + k]);
    g = (g + 1) % s.a.size();
  }
  benchmark::DoNotOptimize(hits);
  state.SetItemsProcessed(std::int64_t(state.iterations()) * 16);
  state.counters["intersecting_fraction"] = double(s.intersecting) / double(s.b.size());
}
BENCHMARK(BM_leaf_impact_prepared);

void BM_leaf_impact(benchmark::State& state) {
  const LeafSet& s = leaves();
  std::size_t g = 0, hits = 0;
  for (auto _ : state) {
    for (std::size_t k = 0; k < 16; ++k) hits += triangles_intersect(s.a[g], s.b[16 * g + k]);
    g = (g + 1) % s.a.size();
  }
  benchmark::DoNotOptimize(hits);
  state.SetItemsProcessed(std::int64_t(state.iterations()) * 16);
}
BENCHMARK(BM_leaf_impact);

#ifdef IMPACT_HAVE_FCL
void BM_leaf_fcl(benchmark::State& state) {
  const LeafSet& s = leaves();
  std::size_t g = 0, hits = 0;
  for (auto _ : state) {
    const Triangle<double>& a = s.a[g];
    for (std::size_t k = 0; k < 16; ++k) {
      const Triangle<double>& b = s.b[16 * g + k];
      hits += fcl::detail::Intersect<double>::intersect_Triangle(a.a, a.b, a.c, b.a, b.b, b.c);
    }
    g = (g + 1) % s.a.size();
  }
  benchmark::DoNotOptimize(hits);
  state.SetItemsProcessed(std::int64_t(state.iterations()) * 16);
}
BENCHMARK(BM_leaf_fcl);
#endif

void BM_impact_triangle_intersection_contact(benchmark::State& state) {
  const PairSet& s = pairs(true);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(triangle_intersection(s.a[i], s.b[i]));
    i = (i + 1) % kPairs;
  }
  state.SetItemsProcessed(std::int64_t(state.iterations()));
}
BENCHMARK(BM_impact_triangle_intersection_contact);

#ifdef IMPACT_HAVE_FCL
void BM_fcl_tri_tri(benchmark::State& state) {
  const PairSet& s = pairs(state.range(0) != 0);
  std::size_t agree = 0;
  for (std::size_t k = 0; k < kPairs; ++k)
    agree += fcl::detail::Intersect<double>::intersect_Triangle(s.a[k].a, s.a[k].b, s.a[k].c, s.b[k].a, s.b[k].b, s.b[k].c) ==
             (state.range(0) != 0);
  std::size_t i = 0, hits = 0;
  for (auto _ : state) {
    hits += fcl::detail::Intersect<double>::intersect_Triangle(s.a[i].a, s.a[i].b, s.a[i].c, s.b[i].a, s.b[i].b, s.b[i].c);
    i = (i + 1) % kPairs;
  }
  benchmark::DoNotOptimize(hits);
  state.SetItemsProcessed(std::int64_t(state.iterations()));
  state.counters["agree_with_impact"] = double(agree) / double(kPairs);
}
BENCHMARK(BM_fcl_tri_tri)->ArgName("intersecting")->Arg(1)->Arg(0);
#endif

template <class S> void BM_ray_triangle(benchmark::State& state) {
  test::Rng rng(3);
  std::vector<Ray<S>> rays;
  std::vector<Triangle<S>> tris;
  for (std::size_t k = 0; k < kPairs; ++k) {
    const Eigen::Vector3d c = rng.vec(-1, 1);
    tris.emplace_back((c + rng.vec(-0.5, 0.5)).cast<S>(), (c + rng.vec(-0.5, 0.5)).cast<S>(), (c + rng.vec(-0.5, 0.5)).cast<S>());
    const Eigen::Vector3d o = rng.vec(-3, 3);
    rays.emplace_back(o.cast<S>(), (c + rng.vec(-0.3, 0.3) - o).cast<S>());
  }
  std::size_t i = 0, hits = 0;
  for (auto _ : state) {
    hits += intersect_ray_triangle(rays[i], tris[i]).has_value();
    i = (i + 1) % kPairs;
  }
  benchmark::DoNotOptimize(hits);
  state.SetItemsProcessed(std::int64_t(state.iterations()));
}
BENCHMARK_TEMPLATE(BM_ray_triangle, float);
BENCHMARK_TEMPLATE(BM_ray_triangle, double);

template <class S> void BM_closest_point_triangle(benchmark::State& state) {
  test::Rng rng(4);
  std::vector<Vec3<S>> pts;
  std::vector<Triangle<S>> tris;
  for (std::size_t k = 0; k < kPairs; ++k) {
    tris.emplace_back(rng.vec(-1, 1).cast<S>(), rng.vec(-1, 1).cast<S>(), rng.vec(-1, 1).cast<S>());
    pts.push_back(rng.vec(-2, 2).cast<S>());
  }
  std::size_t i = 0;
  S acc = 0;
  for (auto _ : state) {
    acc += closest_point_on_triangle(pts[i], tris[i]).squared_distance;
    i = (i + 1) % kPairs;
  }
  benchmark::DoNotOptimize(acc);
  state.SetItemsProcessed(std::int64_t(state.iterations()));
}
BENCHMARK_TEMPLATE(BM_closest_point_triangle, float);
BENCHMARK_TEMPLATE(BM_closest_point_triangle, double);

}  // namespace

int main(int argc, char** argv) {
  // translate the smoke harness's `--json FILE` into Google Benchmark's output flags
  std::vector<std::string> args;
  for (int k = 0; k < argc; ++k) {
    if (std::strcmp(argv[k], "--json") == 0 && k + 1 < argc) {
      args.push_back(std::string("--benchmark_out=") + argv[++k]);
      args.push_back("--benchmark_out_format=json");
    } else {
      args.emplace_back(argv[k]);
    }
  }
  std::vector<char*> cargs;
  for (auto& a : args) cargs.push_back(a.data());
  int n = int(cargs.size());
  benchmark::Initialize(&n, cargs.data());
  if (benchmark::ReportUnrecognizedArguments(n, cargs.data())) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
