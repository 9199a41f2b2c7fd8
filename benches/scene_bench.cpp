// SPDX-License-Identifier: MIT
// impact-scene-bench: broad phases on big scenes, against FCL's DynamicAABBTreeCollisionManager
// and Bullet's btDbvtBroadphase, on the same objects in one run.
//
//   impact-scene-bench [--objects N] [--dynamic F] [--steps S] [--warmup W] [--seed K]
//                      [--allpairs-max M] [--scaling-max N] [--bullet-prediction P]
//                      [--bullet-deferred 0|1] [--only NAME] [--threads T] [--json FILE]
//
// A scene of N objects (70% spheres of radius 0.2..0.8, 30% small meshes: an 80-triangle icosphere
// and a 144-triangle torus) uniform in a cube sized for 0.1 objects per unit volume; a fraction F is
// dynamic and moves every step (random velocity up to 0.1 per axis, meshes also rotate). Per step
// each method gets the new poses of the moved objects and returns the broad-phase pairs: objects
// whose tight world AABBs overlap, static–static pairs excluded. Methods: impact all-pairs (N <=
// --allpairs-max), impact static/dynamic split, impact hierarchical (incremental AABB trees);
// FCL's dynamic AABB tree manager as its users split a world (a static manager set up once, a
// dynamic manager updated with the moved objects; dynamic against itself and against static), with
// fcl::Sphere and fcl::BVHModel<OBBRSS> objects; Bullet's btDbvtBroadphase as btCollisionWorld
// drives it (static proxies in the static filter group), with its defaults and with the tuned
// knobs (--bullet-prediction, --bullet-deferred). The peers bound objects by their own (looser or
// enlarged) boxes, so they keep the pairs whose tight AABBs overlap: every method must return the
// same set. Mismatches: pairs in the symmetric difference with the reference (all-pairs when it
// runs; otherwise static/dynamic, itself checked against the first peer), summed over every step
// (warm-up steps included); the exit status is 3 when there is any.
// --only NAME keeps the methods whose name contains NAME (for profiling one of them).
// Then the same for an all-static scene (F = 0), and a scaling table for N = 10^2 .. --scaling-max.
// Times are CPU time of the bench thread (setup excluded from ms/step, --warmup untimed steps
// first), so that a loaded machine does not distort the comparison; the impact scenes of these
// rows run with SceneOptions::threads = 1.
// Last, the threads table (--threads T, default the hardware concurrency): Scene::find_pairs and
// Scene::collide on 1 and on T threads on the main scene; the T-thread pairs must equal the
// 1-thread pairs in the same order (else exit status 3). Speed-ups by the wall clock and by the
// CPU times (see Times::cpu_speedup), since on a shared machine the wall clock measures the
// neighbours too.
#include "bench_util.hpp"
#include "impact/broad/scene.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "support/random.hpp"

#ifdef IMPACT_HAVE_FCL
#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/OBBRSS.h>
#endif

#ifdef IMPACT_HAVE_BULLET
#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>
#include <BulletCollision/BroadphaseCollision/btOverlappingPairCache.h>
#endif

#include <cmath>
#include <cstdio>
#include <algorithm>
#include <cstdlib>
#include <functional>
#include <memory>
#include <string>
#include <vector>

using namespace impact;
using impact::bench::process_seconds;
using impact::bench::thread_seconds;
using impact::bench::wall_seconds;

namespace {

struct Args {
  long objects = 100000;
  double dynamic = 0.1;
  int steps = 10;
  int warmup = 50;
  std::uint64_t seed = 1;
  long allpairs_max = 5000;
  long scaling_max = 100000;
  double bullet_prediction = 2.0;
  bool bullet_deferred = false;
  std::string only;
  int threads = 0;
  std::string json;
};

constexpr const char* kUsage =
    "usage: impact-scene-bench [--objects N] [--dynamic F] [--steps S] [--warmup W] [--seed K]\n"
    "                          [--allpairs-max M] [--scaling-max N] [--bullet-prediction P]\n"
    "                          [--bullet-deferred 0|1] [--only NAME] [--threads T] [--json FILE]\n";

[[noreturn]] void usage(const char* msg) { bench::exit_usage(msg, kUsage); }

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto next = [&] { return bench::option_value(argc, argv, i, kUsage); };
    if (s == "--objects")
      a.objects = long(bench::parse_integer(s, next(), 2, 10000000, kUsage));
    else if (s == "--dynamic")
      a.dynamic = bench::parse_real(s, next(), 0, 1, kUsage);
    else if (s == "--steps")
      a.steps = int(bench::parse_integer(s, next(), 1, 1000000, kUsage));
    else if (s == "--warmup")
      a.warmup = int(bench::parse_integer(s, next(), 0, 1000000, kUsage));
    else if (s == "--seed")
      a.seed = bench::parse_seed(s, next(), kUsage);
    else if (s == "--allpairs-max")
      a.allpairs_max = long(bench::parse_integer(s, next(), 0, 10000000, kUsage));
    else if (s == "--scaling-max")
      a.scaling_max = long(bench::parse_integer(s, next(), 0, 10000000, kUsage));
    else if (s == "--bullet-prediction")
      a.bullet_prediction = bench::parse_real(s, next(), 0, 1e6, kUsage);
    else if (s == "--bullet-deferred")
      a.bullet_deferred = bench::parse_integer(s, next(), 0, 1, kUsage) != 0;
    else if (s == "--only")
      a.only = next();
    else if (s == "--threads")
      a.threads = int(bench::parse_integer(s, next(), 0, 1024, kUsage));
    else if (s == "--json")
      a.json = next();
    else
      bench::reject_option(s, kUsage);
  }
  bench::check_writable(a.json, kUsage);
  return a;
}

using Mesh = MeshBvh<Sphere<double>>;

struct Meshes {
  TriangleMesh<double> ico = make_icosphere<double>(0.5, 1);
  TriangleMesh<double> torus = make_torus<double>(0.45, 0.15, 12, 6);
  Mesh ico_bvh{ico};
  Mesh torus_bvh{torus};
  /// Per mesh kind (1 icosphere, 2 torus): local vertex box and largest distance of a vertex from
  /// its centre, for the peers' tight world boxes.
  Aabb<double> local[3];
  double reach[3] = {0, 0, 0};
  Meshes() {
    for (int k = 1; k <= 2; ++k) {
      const TriangleMesh<double>& m = k == 1 ? ico : torus;
      for (Eigen::Index i = 0; i < m.V.rows(); ++i) local[k].extend(m.V.row(i).transpose());
      for (Eigen::Index i = 0; i < m.V.rows(); ++i)
        reach[k] = std::max(reach[k], (m.V.row(i).transpose() - local[k].center()).norm());
    }
  }
};

/// The scene description shared by every method, and its motion.
struct World {
  struct Obj {
    int kind;  // 0 sphere, 1 icosphere, 2 torus
    double radius;
    bool dynamic;
    RigidTransform<double> pose;
    Eigen::Vector3d velocity;
    Eigen::Matrix3d spin;  // rotation applied per step (meshes)
  };
  std::vector<Obj> obj;
  std::vector<std::int32_t> dynamic_ids;
  double L = 0;

  World(long n, double frac, std::uint64_t seed) {
    test::Rng rng(seed);
    L = std::cbrt(double(n) / 0.1);
    obj.resize(std::size_t(n));
    for (long i = 0; i < n; ++i) {
      Obj& o = obj[std::size_t(i)];
      const double u = rng.uniform();
      o.kind = u < 0.7 ? 0 : (u < 0.85 ? 1 : 2);
      o.radius = rng.uniform(0.2, 0.8);
      o.dynamic = rng.uniform() < frac;
      o.pose = {o.kind ? rng.rotation() : Eigen::Matrix3d::Identity(), rng.vec(0, L)};
      o.velocity = rng.vec(-0.1, 0.1);
      o.spin = Eigen::AngleAxisd(rng.uniform(0, 0.05), rng.vec(-1, 1).normalized()).toRotationMatrix();
      if (o.dynamic) dynamic_ids.push_back(std::int32_t(i));
    }
  }
  /// Advances every dynamic object by one step (bouncing off the scene cube).
  void advance() {
    for (const std::int32_t i : dynamic_ids) {
      Obj& o = obj[std::size_t(i)];
      Eigen::Vector3d t = o.pose.t + o.velocity;
      for (int k = 0; k < 3; ++k)
        if (t[k] < 0 || t[k] > L) {
          o.velocity[k] = -o.velocity[k];
          t[k] = std::min(std::max(t[k], 0.0), L);
        }
      o.pose.t = t;
      if (o.kind) {
        Eigen::Quaterniond q(o.spin * o.pose.R);
        o.pose.R = q.normalized().toRotationMatrix();
      }
    }
  }
};

using PairKeys = std::vector<std::uint64_t>;

/// The tight world box the scene computes (sphere: centre +- r; mesh: its vertex box rotated,
/// capped by the ball around its centre), which the peers use to keep the same pairs.
Aabb<double> tight_box(const World::Obj& o, const Meshes& m) {
  if (o.kind == 0) return {o.pose.t.array() - o.radius, o.pose.t.array() + o.radius};
  const Aabb<double>& local = m.local[o.kind];
  const Eigen::Vector3d c = o.pose.apply(local.center());
  const Eigen::Vector3d e =
      (o.pose.R.cwiseAbs() * ((local.max - local.min) / 2.0)).cwiseMin(Eigen::Vector3d::Constant(m.reach[o.kind]));
  return {c - e, c + e};
}

std::size_t mismatches(PairKeys a, PairKeys b) {
  std::sort(a.begin(), a.end());
  std::sort(b.begin(), b.end());
  std::size_t i = 0, j = 0, m = 0;
  while (i < a.size() && j < b.size()) {
    if (a[i] == b[j])
      ++i, ++j;
    else if (a[i] < b[j])
      ++i, ++m;
    else
      ++j, ++m;
  }
  return m + (a.size() - i) + (b.size() - j);
}

inline std::uint64_t key(std::uint64_t a, std::uint64_t b) { return a < b ? (a << 32) | b : (b << 32) | a; }

struct Row {
  std::string method;
  long objects = 0;
  double fraction = 0, build_ms = 0, ms_per_step = 0;
  double pairs = 0;  // mean per step
  std::size_t mismatches = 0;
  BroadPhaseStats stats;  // impact methods: work counters summed over the steps
};

class ImpactMethod {
 public:
  ImpactMethod(BroadPhaseKind kind, const World& w, const Meshes& m) : w_(w), m_(m) {
    SceneOptions o;
    o.broad_phase = kind;
    o.threads = 1;  // one thread: the CPU time of the bench thread is the method's time
    scene_ = std::make_unique<Scene<double>>(o);
  }
  void setup() {
    for (std::size_t i = 0; i < w_.obj.size(); ++i) {
      const auto& o = w_.obj[i];
      const Shape<double> s =
          o.kind == 0 ? Shape<double>::sphere(o.radius) : Shape<double>::mesh_of(o.kind == 1 ? m_.ico_bvh : m_.torus_bvh);
      scene_->add(i, s, o.pose, {o.dynamic ? BodyType::Dynamic : BodyType::Static});
    }
    PairKeys k;
    pairs(k);
  }
  void step(PairKeys& out) {
    for (const std::int32_t i : w_.dynamic_ids) scene_->set_pose(ObjectId(i), w_.obj[std::size_t(i)].pose);
    pairs(out);
  }
  BroadPhaseStats total;  ///< summed over the timed steps

 private:
  void pairs(PairKeys& out) {
    out.clear();
    scene_->for_each_pair(
        [&](ObjectId a, ObjectId b) {
          out.push_back(key(a, b));
          return true;
        },
        total);
  }
  const World& w_;
  const Meshes& m_;
  std::unique_ptr<Scene<double>> scene_;
};

#ifdef IMPACT_HAVE_FCL
class FclMethod {
 public:
  FclMethod(const World& w, const Meshes& m) : w_(w), m_(m) {
    ico_ = make_model(m.ico);
    torus_ = make_model(m.torus);
  }
  void setup() {
    objs_.clear();
    boxes_.resize(w_.obj.size());
    for (std::size_t i = 0; i < w_.obj.size(); ++i) {
      const auto& o = w_.obj[i];
      std::shared_ptr<fcl::CollisionGeometryd> g;
      if (o.kind == 0)
        g = std::make_shared<fcl::Sphered>(o.radius);
      else
        g = o.kind == 1 ? ico_ : torus_;
      auto obj = std::make_unique<fcl::CollisionObjectd>(g, to_fcl(o.pose));
      obj->setUserData(reinterpret_cast<void*>(i));
      objs_.push_back(std::move(obj));
      boxes_[i] = tight_box(o, m_);
    }
    // As FCL's users split a world: static objects in one manager, set up once and never
    // updated; dynamic objects in another, updated with the moved objects every step.
    std::vector<fcl::CollisionObjectd*> statics, dynamics;
    for (std::size_t i = 0; i < objs_.size(); ++i) (w_.obj[i].dynamic ? dynamics : statics).push_back(objs_[i].get());
    static_.registerObjects(statics);
    static_.setup();
    dynamic_.registerObjects(dynamics);
    dynamic_.setup();
    moved_ = dynamics;
    PairKeys k;
    collide(k);
  }
  void step(PairKeys& out) {
    for (const std::int32_t i : w_.dynamic_ids) {
      fcl::CollisionObjectd* o = objs_[std::size_t(i)].get();
      o->setTransform(to_fcl(w_.obj[std::size_t(i)].pose));
      o->computeAABB();
      boxes_[std::size_t(i)] = tight_box(w_.obj[std::size_t(i)], m_);
    }
    dynamic_.update(moved_);
    collide(out);
  }

 private:
  struct Data {
    const FclMethod* self;
    PairKeys* out;
  };
  static bool callback(fcl::CollisionObjectd* a, fcl::CollisionObjectd* b, void* data) {
    auto* d = static_cast<Data*>(data);
    const auto i = reinterpret_cast<std::size_t>(a->getUserData());
    const auto j = reinterpret_cast<std::size_t>(b->getUserData());
    if (!overlap(d->self->boxes_[i], d->self->boxes_[j])) return false;
    d->out->push_back(key(i, j));
    return false;
  }
  void collide(PairKeys& out) {
    out.clear();
    Data d{this, &out};
    dynamic_.collide(&d, &FclMethod::callback);            // dynamic against dynamic
    dynamic_.collide(&static_, &d, &FclMethod::callback);  // dynamic against static
  }
  std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> make_model(const TriangleMesh<double>& m) {
    auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
    std::vector<fcl::Vector3d> pts;
    std::vector<fcl::Triangle> tris;
    for (Eigen::Index i = 0; i < m.V.rows(); ++i) pts.push_back(m.V.row(i).transpose());
    for (Eigen::Index t = 0; t < m.F.rows(); ++t)
      tris.emplace_back(std::size_t(m.F(t, 0)), std::size_t(m.F(t, 1)), std::size_t(m.F(t, 2)));
    model->beginModel();
    model->addSubModel(pts, tris);
    model->endModel();
    model->computeLocalAABB();
    return model;
  }
  static fcl::Transform3d to_fcl(const RigidTransform<double>& x) {
    fcl::Transform3d t = fcl::Transform3d::Identity();
    t.linear() = x.R;
    t.translation() = x.t;
    return t;
  }

  const World& w_;
  const Meshes& m_;
  std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> ico_, torus_;
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objs_;
  std::vector<fcl::CollisionObjectd*> moved_;
  std::vector<Aabb<double>> boxes_;
  fcl::DynamicAABBTreeCollisionManagerd static_, dynamic_;
};
#endif

#ifdef IMPACT_HAVE_BULLET
/// Bullet 3's btDbvtBroadphase used as btCollisionWorld uses it: a proxy per object with its tight
/// world box, static objects in the StaticFilter group with mask AllFilter ^ StaticFilter (so
/// static–static pairs are filtered out), dynamic ones in DefaultFilter with mask AllFilter; per
/// step setAabb of the moved objects, calculateOverlappingPairs, then a walk over the overlapping
/// pair cache (what btCollisionWorld's dispatcher does) that keeps the pairs whose tight boxes
/// overlap (the cache holds pairs of Bullet's enlarged leaf boxes, and stale ones until its
/// incremental clean-up removes them). `deferred` and `prediction` are the two knobs Bullet's
/// users tune (btDbvtBroadphase::m_deferedcollide, m_prediction; defaults false and 0).
class BulletMethod {
 public:
  BulletMethod(const World& w, const Meshes& m, bool deferred, double prediction) : w_(w), m_(m) {
    bp_.m_deferedcollide = deferred;
    bp_.setVelocityPrediction(btScalar(prediction));
  }
  ~BulletMethod() {
    // Pairs first (one hash removal each): destroyProxy scans the whole pair cache for its pairs.
    btOverlappingPairCache* cache = bp_.getOverlappingPairCache();
    btBroadphasePairArray& arr = cache->getOverlappingPairArray();
    while (arr.size() > 0) cache->removeOverlappingPair(arr[arr.size() - 1].m_pProxy0, arr[arr.size() - 1].m_pProxy1, nullptr);
    for (btBroadphaseProxy* p : proxy_) bp_.destroyProxy(p, nullptr);
  }
  BulletMethod(const BulletMethod&) = delete;
  BulletMethod& operator=(const BulletMethod&) = delete;
  void setup() {
    boxes_.resize(w_.obj.size());
    proxy_.resize(w_.obj.size());
    for (std::size_t i = 0; i < w_.obj.size(); ++i) {
      const auto& o = w_.obj[i];
      boxes_[i] = tight_box(o, m_);
      const int group = o.dynamic ? int(btBroadphaseProxy::DefaultFilter) : int(btBroadphaseProxy::StaticFilter);
      const int mask = o.dynamic ? int(btBroadphaseProxy::AllFilter)
                                 : int(btBroadphaseProxy::AllFilter) ^ int(btBroadphaseProxy::StaticFilter);
      proxy_[i] = bp_.createProxy(bt(boxes_[i].min), bt(boxes_[i].max),
                                  o.kind == 0 ? SPHERE_SHAPE_PROXYTYPE : TRIANGLE_MESH_SHAPE_PROXYTYPE,
                                  reinterpret_cast<void*>(i), group, mask, nullptr);
    }
    PairKeys k;
    pairs(k);
  }
  void step(PairKeys& out) {
    for (const std::int32_t i : w_.dynamic_ids) {
      const auto s = std::size_t(i);
      boxes_[s] = tight_box(w_.obj[s], m_);
      bp_.setAabb(proxy_[s], bt(boxes_[s].min), bt(boxes_[s].max), nullptr);
    }
    pairs(out);
  }

 private:
  static btVector3 bt(const Eigen::Vector3d& v) { return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())); }
  void pairs(PairKeys& out) {
    out.clear();
    bp_.calculateOverlappingPairs(nullptr);
    btBroadphasePairArray& arr = bp_.getOverlappingPairCache()->getOverlappingPairArray();
    for (int p = 0; p < arr.size(); ++p) {
      const auto i = reinterpret_cast<std::size_t>(arr[p].m_pProxy0->m_clientObject);
      const auto j = reinterpret_cast<std::size_t>(arr[p].m_pProxy1->m_clientObject);
      if (overlap(boxes_[i], boxes_[j])) out.push_back(key(i, j));
    }
  }
  const World& w_;
  const Meshes& m_;
  btDbvtBroadphase bp_;
  std::vector<btBroadphaseProxy*> proxy_;
  std::vector<Aabb<double>> boxes_;
};
#endif

/// Runs every method on one scene for `steps` steps; returns the rows of the methods that ran, in
/// the order all-pairs, static/dynamic, hierarchical, FCL, Bullet defaults, Bullet tuned.
std::vector<Row> run(long n, double frac, int steps, const Args& args, const Meshes& meshes) {
  World world(n, frac, args.seed);
  struct Method {
    std::string name;
    std::function<void()> setup;
    std::function<void(PairKeys&)> step;
    const BroadPhaseStats* stats = nullptr;
  };
  std::vector<Method> methods;
  ImpactMethod all(BroadPhaseKind::AllPairs, world, meshes), sd(BroadPhaseKind::StaticDynamic, world, meshes),
      hi(BroadPhaseKind::Hierarchical, world, meshes);
  const bool with_all = n <= args.allpairs_max;
  auto impact_method = [&](const char* name, ImpactMethod& m) {
    methods.push_back({name, [&m] { m.setup(); }, [&m](PairKeys& o) { m.step(o); }, &m.total});
  };
  if (with_all) impact_method("impact-all-pairs", all);
  impact_method("impact-static-dynamic", sd);
  impact_method("impact-hierarchical", hi);
#ifdef IMPACT_HAVE_FCL
  FclMethod fcl_m(world, meshes);
  methods.push_back({"fcl-dynamic-aabb-tree", [&] { fcl_m.setup(); }, [&](PairKeys& o) { fcl_m.step(o); }});
#endif
#ifdef IMPACT_HAVE_BULLET
  BulletMethod bt_default(world, meshes, false, 0.0), bt_tuned(world, meshes, args.bullet_deferred, args.bullet_prediction);
  methods.push_back({"bullet-dbvt-defaults", [&] { bt_default.setup(); }, [&](PairKeys& o) { bt_default.step(o); }});
  methods.push_back({"bullet-dbvt-tuned", [&] { bt_tuned.setup(); }, [&](PairKeys& o) { bt_tuned.step(o); }});
#endif
  if (!args.only.empty()) {
    std::vector<Method> kept;
    for (auto& m : methods)
      if (m.name.find(args.only) != std::string::npos) kept.push_back(std::move(m));
    methods = std::move(kept);
    if (methods.empty()) usage(("--only " + args.only + " names no method").c_str());
  }
  // The reference: the first method (all-pairs when it runs, else static/dynamic), itself checked
  // against the first peer (FCL, else Bullet, else the next impact method) unless it is all-pairs.
  const std::size_t ref = 0;
  std::size_t check = ref;
  if (methods[0].name != "impact-all-pairs") {
    for (std::size_t m = methods.size(); m-- > 1;)
      if (methods[m].name.rfind("impact", 0) != 0 || check == ref) check = m;
  }
  std::vector<Row> rows(methods.size());
  std::vector<double> total(methods.size(), 0.0);
  std::vector<PairKeys> k(methods.size());
  for (std::size_t m = 0; m < methods.size(); ++m) {
    rows[m].method = methods[m].name;
    rows[m].objects = n;
    rows[m].fraction = frac;
    const double t0 = thread_seconds();
    methods[m].setup();
    rows[m].build_ms = 1e3 * (thread_seconds() - t0);
  }
  // The first --warmup steps are not timed (each method reaches its steady state); every step is
  // checked.
  for (int s = 0; s < args.warmup + steps; ++s) {
    world.advance();
    const bool timed = s >= args.warmup;
    if (s == args.warmup) all.total = sd.total = hi.total = {};
    for (std::size_t m = 0; m < methods.size(); ++m) {
      const double t0 = thread_seconds();
      methods[m].step(k[m]);
      if (!timed) continue;
      total[m] += thread_seconds() - t0;
      rows[m].pairs += double(k[m].size());
    }
    for (std::size_t m = 0; m < methods.size(); ++m)
      if (m != ref)
        rows[m].mismatches += mismatches(k[m], k[ref]);
      else if (check != ref)
        rows[m].mismatches += mismatches(k[m], k[check]);
  }
  for (std::size_t m = 0; m < methods.size(); ++m) {
    if (methods[m].stats) rows[m].stats = *methods[m].stats;
    rows[m].ms_per_step = 1e3 * total[m] / steps;
    rows[m].pairs /= steps;
  }
  return rows;
}

double ms_of(const std::vector<Row>& rows, const std::string& method) {
  for (const auto& r : rows)
    if (r.method == method) return r.ms_per_step;
  return 0;
}

void print_table(const std::vector<Row>& rows, int steps) {
  const double f = ms_of(rows, "fcl-dynamic-aabb-tree"), b = ms_of(rows, "bullet-dbvt-tuned");
  std::printf("  %-24s %10s %12s %12s %11s %11s %11s | per step: %10s %10s %10s %10s\n", "method", "build ms", "ms/step",
              "pairs/step", "mismatches", "FCL/method", "Btun/method", "bv tests", "aabb tests", "reinserts", "st.queries");
  for (const auto& r : rows) {
    char rf[32] = "-", rb[32] = "-";
    if (f > 0 && r.ms_per_step > 0) std::snprintf(rf, sizeof rf, "%.2fx", f / r.ms_per_step);
    if (b > 0 && r.ms_per_step > 0) std::snprintf(rb, sizeof rb, "%.2fx", b / r.ms_per_step);
    std::printf("  %-24s %10.2f %12.4f %12.1f %11zu %11s %11s |           %10.0f %10.0f %10.0f %10.0f\n", r.method.c_str(),
                r.build_ms, r.ms_per_step, r.pairs, r.mismatches, rf, rb, double(r.stats.bv_tests) / steps,
                double(r.stats.pairs_tested) / steps, double(r.stats.reinserts) / steps, double(r.stats.static_queries) / steps);
  }
}

std::string json_row(const Row& r) {
  bench::JsonObject o;
  o.add("method", r.method).add("objects", static_cast<long long>(r.objects)).add("dynamic_fraction", r.fraction);
  o.add("build_ms", r.build_ms).add("ms_per_step", r.ms_per_step).add("pairs", r.pairs).add("mismatches", r.mismatches);
  return o.str();
}

/// Time of one query: wall clock, CPU time of the calling thread and of the whole process.
struct Times {
  double wall = 0, caller = 0, process = 0;
  template <class F>
  void add(F&& f) {
    const double w = wall_seconds(), c = thread_seconds(), p = process_seconds();
    f();
    wall += wall_seconds() - w;
    caller += thread_seconds() - c;
    process += process_seconds() - p;
  }
  /// The speed-up over `one` (a one-thread run) on an otherwise idle machine (bench::cpu_speedup).
  double cpu_speedup(const Times& one, int threads) const { return bench::cpu_speedup(one.caller, caller, process, threads); }
};

/// The threads table: find_pairs and collide on 1 and on `threads` threads, same scene and
/// motion. Reports the wall-clock speed-up and, because wall time on a shared machine measures
/// the neighbours too, the speed-up the CPU times give (Times::cpu_speedup). Returns the number
/// of steps whose T-thread answer differs from the 1-thread one (pairs, in order).
std::size_t run_threads(const Args& args, const Meshes& meshes, int threads, std::vector<std::string>& json) {
  std::size_t differ = 0;
  std::printf("\nthreads, %ld objects, %.0f%% dynamic, %d steps: ms/step (1 thread: CPU time; %d threads: wall clock, CPU of the calling\n"
              "thread, CPU of the process), speed-up by the wall clock and by the CPU times\n",
              args.objects, 100 * args.dynamic, args.steps, threads);
  std::printf("  %-22s %-10s %9s %9s %9s %9s %9s %9s\n", "method", "query", "1 thread", "wall", "caller", "process", "wall x", "cpu x");
  for (const BroadPhaseKind kind : {BroadPhaseKind::StaticDynamic, BroadPhaseKind::Hierarchical}) {
    const char* name = kind == BroadPhaseKind::StaticDynamic ? "impact-static-dynamic" : "impact-hierarchical";
    World world(args.objects, args.dynamic, args.seed);
    std::unique_ptr<Scene<double>> sc[2];
    for (int k = 0; k < 2; ++k) {
      SceneOptions o;
      o.broad_phase = kind;
      o.threads = k == 0 ? 1 : threads;
      sc[k] = std::make_unique<Scene<double>>(o);
      for (std::size_t i = 0; i < world.obj.size(); ++i) {
        const auto& ob = world.obj[i];
        const Shape<double> shape = ob.kind == 0 ? Shape<double>::sphere(ob.radius)
                                                 : Shape<double>::mesh_of(ob.kind == 1 ? meshes.ico_bvh : meshes.torus_bvh);
        sc[k]->add(i, shape, ob.pose, {ob.dynamic ? BodyType::Dynamic : BodyType::Static});
      }
      sc[k]->find_pairs();  // builds the trees
    }
    Times pairs_t[2], collide_t[2];
    for (int s = 0; s < args.steps; ++s) {
      world.advance();
      PairResult p[2];
      SceneCollideResult<double> c[2];
      for (int k = 0; k < 2; ++k) {
        for (const std::int32_t i : world.dynamic_ids) sc[k]->set_pose(ObjectId(i), world.obj[std::size_t(i)].pose);
        pairs_t[k].add([&] { p[k] = sc[k]->find_pairs(); });  // the edits' deferred work included, as in the rows above
        collide_t[k].add([&] { c[k] = sc[k]->collide(); });
      }
      if (p[0].pairs != p[1].pairs || c[0].pairs != c[1].pairs) ++differ;
    }
    for (const auto& [query, t] : {std::make_pair("find_pairs", pairs_t), std::make_pair("collide", collide_t)}) {
      const double ms = 1e3 / args.steps;
      std::printf("  %-22s %-10s %9.3f %9.3f %9.3f %9.3f %8.2fx %8.2fx\n", name, query, ms * t[0].caller, ms * t[1].wall, ms * t[1].caller,
                  ms * t[1].process, t[0].wall / std::max(t[1].wall, 1e-12), t[1].cpu_speedup(t[0], threads));
      bench::JsonObject o;
      o.add("method", name).add("query", query).add("objects", static_cast<long long>(args.objects)).add("threads", threads);
      o.add("ms_per_step_1_thread", ms * t[0].caller).add("ms_per_step_wall", ms * t[1].wall);
      o.add("ms_per_step_caller_cpu", ms * t[1].caller).add("ms_per_step_process_cpu", ms * t[1].process);
      o.add("speedup_wall", t[0].wall / std::max(t[1].wall, 1e-12)).add("speedup_cpu", t[1].cpu_speedup(t[0], threads));
      o.add("steps_differing", static_cast<long long>(differ));
      json.push_back(o.str());
    }
  }
  std::printf("  threads: %d; steps whose answers differ from one thread: %zu\n", threads, differ);
  return differ;
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse(argc, argv);
  const Meshes meshes;
#ifndef IMPACT_HAVE_FCL
  std::printf("note: built without FCL; the FCL rows are missing\n");
#endif
#ifndef IMPACT_HAVE_BULLET
  std::printf("note: built without Bullet; the Bullet rows are missing\n");
#endif
  std::vector<std::string> json_rows, json_scaling;
  std::size_t total_mismatches = 0;

  std::printf(
      "impact-scene-bench: %ld objects (70%% spheres, 30%% meshes of 80/144 triangles), %.0f%% dynamic, %d steps, seed %llu\n",
      args.objects, 100 * args.dynamic, args.steps, static_cast<unsigned long long>(args.seed));
  std::printf("reference for mismatches: the first row (%s)\n",
              args.objects <= args.allpairs_max && args.only.empty()
                  ? "impact-all-pairs"
                  : "itself checked against the first peer when it is not all-pairs");
  const auto main_rows = run(args.objects, args.dynamic, args.steps, args, meshes);
  print_table(main_rows, args.steps);
  for (const auto& r : main_rows) {
    json_rows.push_back(json_row(r));
    total_mismatches += r.mismatches;
  }

  std::printf("\nall-static scene, %ld objects (per step: nothing moves, pairs found again)\n", args.objects);
  const auto static_rows = run(args.objects, 0.0, args.steps, args, meshes);
  print_table(static_rows, args.steps);
  for (const auto& r : static_rows) {
    json_rows.push_back(json_row(r));
    total_mismatches += r.mismatches;
  }

  std::printf("\nscaling, %.0f%% dynamic: ms/step\n", 100 * args.dynamic);
  const char* names[] = {"impact-all-pairs",      "impact-static-dynamic", "impact-hierarchical",
                         "fcl-dynamic-aabb-tree", "bullet-dbvt-defaults",  "bullet-dbvt-tuned"};
  std::printf("  %8s %12s %12s %12s %12s %12s %12s %9s %9s\n", "N", "all-pairs", "static-dyn", "hierarch.", "fcl", "bullet-def",
              "bullet-tun", "FCL/s-d", "Btun/s-d");
  for (long n = 100; n <= args.scaling_max; n *= 10) {
    const auto rows = run(n, args.dynamic, args.steps, args, meshes);
    for (const auto& r : rows) {
      json_scaling.push_back(json_row(r));
      total_mismatches += r.mismatches;
    }
    std::printf("  %8ld", n);
    for (const char* name : names) {
      const double v = ms_of(rows, name);
      if (v > 0)
        std::printf(" %12.4f", v);
      else
        std::printf(" %12s", "-");
    }
    const double sdv = ms_of(rows, names[1]);
    for (const int peer : {3, 5}) {
      const double v = ms_of(rows, names[peer]);
      if (v > 0 && sdv > 0)
        std::printf(" %8.2fx", v / sdv);
      else
        std::printf(" %9s", "-");
    }
    std::printf("\n");
  }
  std::vector<std::string> json_threads;
  total_mismatches += run_threads(args, meshes, resolve_threads(args.threads), json_threads);
  std::printf("\ntotal mismatches: %zu\n", total_mismatches);

  if (!args.json.empty()) {
    bench::JsonObject o;
    o.add("bench", "impact-scene-bench")
        .add("objects", static_cast<long long>(args.objects))
        .add("dynamic_fraction", args.dynamic);
    o.add("steps", args.steps).add("warmup", args.warmup).add("seed", static_cast<long long>(args.seed));
    o.add("bullet_prediction", args.bullet_prediction).add("bullet_deferred", args.bullet_deferred);
    o.raw("rows", bench::JsonObject::array(json_rows));
    o.raw("scaling", bench::JsonObject::array(json_scaling));
    o.raw("threads", bench::JsonObject::array(json_threads));
    if (!bench::write_file(args.json, o.str())) {
      std::fprintf(stderr, "cannot write %s\n", args.json.c_str());
      return 1;
    }
  }
  return total_mismatches == 0 ? 0 : 3;
}
