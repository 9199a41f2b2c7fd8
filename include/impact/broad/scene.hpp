// SPDX-License-Identifier: MIT
/// \file
/// Scene<S>: the objects of a simulation (spheres, oriented boxes, meshes, particles; each static
/// or dynamic, with a user id, a collision filter and a sleeping flag) and the broad phase chosen
/// for them (BroadPhaseKind), dispatched once per call through a std::variant — never inside the
/// inner loops. Its second template parameter is the shape set (CoreSceneShapes below: Shape<S> and
/// narrow_dispatch.hpp); convex/scene_shapes.hpp gives ConvexScene<S>, the same scene with
/// capsules, cylinders, cones and convex hulls too (target impact::convex, libccd).
///
///   Scene<double> scene({BroadPhaseKind::StaticDynamic});
///   scene.add(7, Shape<double>::sphere(0.5), pose);               // dynamic by default
///   scene.add(8, Shape<double>::mesh_of(bunny), pose2, {BodyType::Static});
///   scene.set_pose(7, new_pose);                                   // cheap: flushed at the next query
///   PairResult pairs = scene.find_pairs();                         // broad phase only
///   auto hits = scene.collide({/*contacts=*/true});                // + narrow phase
///
/// Edits validate their input first and throw impact::InvalidInput (NaN or non-rigid poses,
/// negative or non-finite sizes, unknown or duplicate ids, removing twice); a throwing call leaves
/// the scene unchanged. Pair semantics are those of broad_phase.hpp: static–static and sleeping
/// pairs never appear, filtered pairs are dropped before any geometry test.
///
/// Thread safety: the queries (find_pairs, for_each_pair, collide, any_collision and the const
/// accessors) are const and may be called from any number of threads at once on a scene that no
/// thread is editing. Edits (add, remove, set_pose, set_position, set_sleeping, set_filter,
/// ignore_pair, unignore_pair) and update() must not overlap any other call on the same scene.
/// The broad phase's deferred work (refits, rebuilds, cached candidates) is done once, by the first
/// query after edits (the others wait for it) or ahead of time by update().
///
/// Threads: find_pairs and collide run on SceneOptions::threads threads (default: the hardware
/// concurrency; 1 is the serial path) when the scene holds at least parallel_min_objects objects.
/// The answer never depends on the thread count: the same pairs (and contacts) in the same order,
/// and the same work counters, as the serial path. for_each_pair, whose visitor is the caller's,
/// is always serial.
#pragma once

#include "impact/broad/all_pairs.hpp"
#include "impact/broad/hierarchical.hpp"
#include "impact/broad/narrow_dispatch.hpp"
#include "impact/broad/static_dynamic.hpp"
#include "impact/core/error.hpp"
#include "impact/core/parallel.hpp"
#include "impact/core/validate.hpp"
#include "impact/geometry/transform.hpp"

#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <string>
#include <unordered_map>
#include <variant>

namespace impact {

namespace detail {
/// "Edits are pending" and the lock under which the first query after them applies them. Copying
/// a scene copies the flag (a new lock).
class PendingEdits {
 public:
  PendingEdits() = default;
  PendingEdits(const PendingEdits& o) : pending_(o.pending_.load()) {}
  PendingEdits& operator=(const PendingEdits& o) {
    pending_.store(o.pending_.load());
    return *this;
  }
  /// An edit happened (edits never run concurrently with queries).
  void mark() { pending_.store(true, std::memory_order_relaxed); }
  /// Runs apply() once if edits are pending; concurrent callers wait for it.
  template <class F>
  void apply(F&& f) {
    if (!pending_.load(std::memory_order_acquire)) return;
    std::lock_guard<std::mutex> lock(m_);
    if (!pending_.load(std::memory_order_relaxed)) return;
    f();
    pending_.store(false, std::memory_order_release);
  }

 private:
  std::atomic<bool> pending_{false};
  std::mutex m_;
};
}  // namespace detail

/// Static objects never move (moving one is allowed but rebuilds the static tree); dynamic ones
/// may move every step.
enum class BodyType : std::uint8_t { Static, Dynamic };

/// The caller's name for an object.
using ObjectId = std::uint64_t;

/// Per-object options at insertion.
struct ObjectOptions {
  BodyType body = BodyType::Dynamic;
  CollisionFilter filter{};
  bool sleeping = false;  ///< a sleeping dynamic object is only tested against awake ones
};

struct SceneOptions {
  BroadPhaseKind broad_phase = BroadPhaseKind::StaticDynamic;
  DynamicTreeOptions tree{};  ///< the incremental trees (Hierarchical, and StaticDynamic's dynamic part)
  int static_leaf_size = 2;   ///< objects per leaf of StaticDynamic's static tree
  /// Threads of find_pairs, collide and the deferred broad-phase work: <= 0 the hardware
  /// concurrency, 1 the serial path. Results do not depend on it.
  int threads = 0;
  /// Scenes with fewer objects run serially (a parallel call costs a few microseconds).
  std::size_t parallel_min_objects = 1000;
};

/// Two objects, a < b.
struct ObjectPair {
  ObjectId a = 0, b = 0;
  friend bool operator==(const ObjectPair& x, const ObjectPair& y) { return x.a == y.a && x.b == y.b; }
  friend bool operator<(const ObjectPair& x, const ObjectPair& y) { return x.a < y.a || (x.a == y.a && x.b < y.b); }
};

/// Candidate pairs of the broad phase (overlapping world AABBs), in no particular order.
struct PairResult {
  std::vector<ObjectPair> pairs;
  BroadPhaseStats stats;
};

struct SceneCollideOptions {
  bool contacts = false;       ///< compute a contact per colliding pair (otherwise only the pairs)
  bool stop_at_first = false;  ///< boolean query: stop at the first colliding pair
};

/// A contact between objects a < b; the normal points from a towards b.
template <class S>
struct SceneContact {
  ObjectId a = 0, b = 0;
  ShapeContact<S> contact;
};

template <class S>
struct SceneCollideResult {
  bool colliding = false;
  std::vector<ObjectPair> pairs;          ///< pairs whose shapes touch
  std::vector<SceneContact<S>> contacts;  ///< one per pair, when asked for
  BroadPhaseStats stats;
};

/// Pads a world box (in place) for the rounding of the narrow phase, as Scene's broad phase needs:
/// by 32u (|t|_inf + |R|_inf P), P the shape's extent in its own frame, for the rounding of the box
/// and of the relative pose the narrow phase moves one shape by (each pair's pads add up to about
/// twice the bound of that rounding), and by 2 g P, g >= |R^T R - I|_2, since the narrow phase sees
/// the other shape through R^T, which is not quite R's inverse for a pose rigid only within
/// rotation_tolerance (a point x of the other shape it finds on this one lies within g |x - t| of
/// where the world has it). `round`: only the pose's translation moves the shape (spheres,
/// particles). Without the pads, shapes touching exactly at large translations were missed
/// (tests/broad/test_narrow_dispatch.cpp).
template <class S>
void pad_scene_box(Aabb<S>& box, const RigidTransform<S>& pose, S P, bool round) {
  constexpr S u = std::numeric_limits<S>::epsilon() / S(2);
  S g = S(0);
  if (!round) {
    const Mat3<S> G = pose.R.transpose() * pose.R - Mat3<S>::Identity();
    g = G.cwiseAbs().sum() * (S(1) + S(16) * u) + S(16) * u * (pose.R.squaredNorm() + S(3));
  }
  const S r_inf = round ? S(1) : pose.R.cwiseAbs().rowwise().sum().maxCoeff();
  const S pad = (S(32) * u * (pose.t.cwiseAbs().maxCoeff() + r_inf * P) + S(2) * g * P) * (S(1) + S(8) * u);
  box.min.array() -= pad;
  box.max.array() += pad;
}

/// The shape set of a Scene, its second template parameter. This one is the core's: Shape<S>
/// (sphere, box, mesh, particle) with the narrow phase shapes_intersect of narrow_dispatch.hpp.
/// The convex layer's ConvexSceneShapes (convex/scene_shapes.hpp, target impact::convex) adds
/// capsules, cylinders, cones and convex hulls the same way, so the core scene never includes
/// libccd. A shape set is a small value (its options, copied into the scene) with:
///   Shape                    the objects' shape type (default constructible: a removed slot)
///   Local                    what add() computes once per object for world_box
///   Local local(shape)       that
///   void check(shape, who)   throws InvalidInput naming `who` for an invalid shape
///   Aabb<S> world_box(shape, local, pose)   the object's world box, padded so that the broad
///                            phase never drops a pair the narrow phase would report
///   bool intersect(a, pa, b, pb, ShapeContact<S>* contact, BroadPhaseStats& stats)
///                            the narrow phase of a pair (contact normal from a towards b)
/// All of it is resolved at compile time: no virtual call in the scene's loops.
template <class S>
struct CoreSceneShapes {
  using Shape = impact::Shape<S>;
  /// Meshes: the box of the vertices in the mesh frame and the largest distance of a vertex from
  /// its centre; nothing for the other shapes.
  struct Local {
    Aabb<S> box;
    S reach = S(0);
  };
  static Local local(const Shape& shape) {
    Local l;
    if (shape.kind == ShapeKind::Mesh) {
      const auto& V = shape.mesh->mesh().V;
      for (Eigen::Index i = 0; i < V.rows(); ++i) l.box.extend(V.row(i).transpose());
      const Vec3<S> c = l.box.center();
      for (Eigen::Index i = 0; i < V.rows(); ++i) l.reach = std::max(l.reach, (V.row(i).transpose() - c).norm());
    }
    return l;
  }
  static bool intersect(const Shape& a, const RigidTransform<S>& pa, const Shape& b, const RigidTransform<S>& pb,
                        ShapeContact<S>* contact, BroadPhaseStats&) {
    return shapes_intersect(a, pa, b, pb, contact);
  }

  /// Throws InvalidInput (naming `who`) for a negative or non-finite size or a null mesh.
  static void check(const Shape& shape, const std::string& who) {
    switch (shape.kind) {
      case ShapeKind::Sphere:
      case ShapeKind::Particle:
        validate_length(shape.radius, who.c_str(), "radius");
        break;
      case ShapeKind::Box:
        for (int k = 0; k < 3; ++k) validate_length(shape.half[k], who.c_str(), "half extent");
        break;
      case ShapeKind::Mesh:
        if (!shape.mesh) throw InvalidInput(who + ": null mesh");
        break;
    }
  }

  /// Conservative world box: for spheres, particles and boxes their box, for meshes the
  /// intersection of the rotated vertex box and the cube around the vertices' bounding sphere (both
  /// contain the mesh; the first is tighter for elongated meshes, the second for round ones); then
  /// padded by pad_scene_box.
  static Aabb<S> world_box(const Shape& shape, const Local& loc, const RigidTransform<S>& pose) {
    const Aabb<S>& local = loc.box;
    const S reach = loc.reach;
    Aabb<S> box;
    S P = S(0);
    switch (shape.kind) {
      case ShapeKind::Sphere:
      case ShapeKind::Particle: {
        const Vec3<S> r = Vec3<S>::Constant(shape.radius);
        box = {pose.t - r, pose.t + r};
        P = shape.radius;  // only the centre is moved: no rotation involved
        break;
      }
      case ShapeKind::Box: {
        const Vec3<S> e = pose.R.cwiseAbs() * shape.half;
        box = {pose.t - e, pose.t + e};
        P = shape.half.sum();
        break;
      }
      case ShapeKind::Mesh:
      default: {
        const Vec3<S> c = pose.apply(local.center());
        const Vec3<S> e = (pose.R.cwiseAbs() * ((local.max - local.min) / S(2))).cwiseMin(Vec3<S>::Constant(reach));
        box = {c - e, c + e};
        P = local.center().cwiseAbs().sum() + reach + (local.max - local.min).sum();
        break;
      }
    }
    pad_scene_box(box, pose, P, shape.is_round());
    return box;
  }
};

template <class S, class Shapes = CoreSceneShapes<S>>
class Scene {
  static_assert(is_supported_scalar_v<S>, "Scene<S>: S must be float or double");
  static_assert(is_broad_phase_v<AllPairsBroadPhase<S>, S> && is_broad_phase_v<StaticDynamicBroadPhase<S>, S> &&
                    is_broad_phase_v<HierarchicalBroadPhase<S>, S>,
                "every broad phase implements the interface of broad_phase.hpp");

 public:
  using ShapeType = typename Shapes::Shape;

  /// Throws InvalidInput for options outside their ranges (check_options). `shapes` is the shape
  /// set's value (its options, e.g. ConvexSceneShapes' solver tolerances).
  explicit Scene(const SceneOptions& opt = {}, const Shapes& shapes = {}) : opt_(opt), shapes_(shapes) {
    check_options(opt);
    switch (opt.broad_phase) {
      case BroadPhaseKind::AllPairs:
        broad_.template emplace<AllPairsBroadPhase<S>>();
        break;
      case BroadPhaseKind::StaticDynamic:
        broad_.template emplace<StaticDynamicBroadPhase<S>>(opt.tree, opt.static_leaf_size);
        break;
      case BroadPhaseKind::Hierarchical:
        broad_.template emplace<HierarchicalBroadPhase<S>>(opt.tree);
        break;
    }
  }

  /// Adds an object. For spheres and particles only the pose's translation matters. Throws
  /// InvalidInput for a duplicate id, a non-finite or non-rigid pose (R^T R off the identity by
  /// more than sqrt(eps) for float, 1e-6 for double, or det R <= 0), a negative or non-finite
  /// size, or a null mesh.
  void add(ObjectId id, const ShapeType& shape, const RigidTransform<S>& pose, const ObjectOptions& options = {}) {
    if (ids_.count(id)) throw InvalidInput("Scene::add: id " + std::to_string(id) + " is already in the scene");
    shapes_.check(shape, "Scene::add: object " + std::to_string(id));
    check_pose(pose, "Scene::add", id);
    typename Shapes::Local local = shapes_.local(shape);
    const Aabb<S> box = shapes_.world_box(shape, local, pose);
    if (!all_finite(box.min) || !all_finite(box.max))
      throw InvalidInput("Scene::add: object " + std::to_string(id) + " has non-finite bounds");
    std::int32_t slot;
    if (!free_.empty()) {
      slot = free_.back();
      free_.pop_back();
    } else {
      slot = table_.size();
      table_.push_back();
      objects_.emplace_back();
      slot_ids_.emplace_back();
    }
    const auto s = static_cast<std::size_t>(slot);
    objects_[s] = {id, shape, pose, std::move(local)};
    slot_ids_[s] = id;
    table_.box(slot) = box;
    table_.flags(slot) = std::uint8_t(ObjectTable<S>::Alive | (options.body == BodyType::Static ? ObjectTable<S>::Static : 0) |
                                      (options.sleeping ? ObjectTable<S>::Sleeping : 0));
    table_.filter(slot) = options.filter;
    table_.ignore_count(slot) = 0;
    ids_.emplace(id, slot);
    ++count_;
    std::visit([&](auto& b) { b.insert(slot, table_); }, broad_);
    pending_.mark();
  }

  /// Removes an object. Throws InvalidInput when the id is unknown (also when removed already).
  void remove(ObjectId id) {
    const std::int32_t slot = slot_of(id, "Scene::remove");
    const auto s = static_cast<std::size_t>(slot);
    std::visit([&](auto& b) { b.remove(slot, table_); }, broad_);
    pending_.mark();
    if (table_.ignore_count(slot)) {
      for (auto it = table_.ignored.begin(); it != table_.ignored.end();) {
        const auto x = std::int32_t(*it >> 32), y = std::int32_t(*it & 0xffffffffu);
        if (x == slot || y == slot) {
          --table_.ignore_count(x == slot ? y : x);
          it = table_.ignored.erase(it);
        } else {
          ++it;
        }
      }
      table_.ignore_count(slot) = 0;
    }
    table_.flags(slot) = 0;
    objects_[s].shape = ShapeType{};
    ids_.erase(id);
    free_.push_back(slot);
    --count_;
  }

  /// Moves an object. The broad phase is updated lazily at the next query, once per object however
  /// often it moved. Throws InvalidInput for an unknown id or a non-finite or non-rigid pose.
  void set_pose(ObjectId id, const RigidTransform<S>& pose) {
    const std::int32_t slot = slot_of(id, "Scene::set_pose");
    check_pose(pose, "Scene::set_pose", id);
    const auto s = static_cast<std::size_t>(slot);
    const Aabb<S> box = shapes_.world_box(objects_[s].shape, objects_[s].local, pose);
    if (!all_finite(box.min) || !all_finite(box.max))
      throw InvalidInput("Scene::set_pose: object " + std::to_string(id) + " has non-finite bounds");
    objects_[s].pose = pose;
    table_.box(slot) = box;
    std::visit([&](auto& b) { b.moved(slot, table_); }, broad_);
    pending_.mark();
  }
  /// Moves an object by translation only (the rotation is kept).
  void set_position(ObjectId id, const Vec3<S>& p) {
    const std::int32_t slot = slot_of(id, "Scene::set_position");
    set_pose(id, RigidTransform<S>(objects_[static_cast<std::size_t>(slot)].pose.R, p));
  }

  /// Puts a dynamic object to sleep or wakes it. Sleeping objects are not tested against static
  /// or sleeping ones. Throws for unknown ids and for static objects.
  void set_sleeping(ObjectId id, bool sleeping) {
    const std::int32_t slot = slot_of(id, "Scene::set_sleeping");
    if (table_.is_static(slot)) throw InvalidInput("Scene::set_sleeping: object " + std::to_string(id) + " is static");
    auto& f = table_.flags(slot);
    const std::uint8_t nf = sleeping ? std::uint8_t(f | ObjectTable<S>::Sleeping) : std::uint8_t(f & ~ObjectTable<S>::Sleeping);
    if (nf == f) return;
    f = nf;
    std::visit([&](auto& b) { b.activity_changed(slot, table_); }, broad_);
    pending_.mark();
  }

  /// Replaces an object's group/mask filter.
  void set_filter(ObjectId id, const CollisionFilter& filter) {
    const std::int32_t slot = slot_of(id, "Scene::set_filter");
    table_.filter(slot) = filter;
    std::visit([&](auto& b) { b.filter_changed(slot, table_); }, broad_);
    pending_.mark();
  }

  /// Never report the pair {a, b} (forgotten when either object is removed). Throws for unknown
  /// ids or a == b.
  void ignore_pair(ObjectId a, ObjectId b) {
    const std::int32_t sa = slot_of(a, "Scene::ignore_pair"), sb = slot_of(b, "Scene::ignore_pair");
    if (sa == sb) throw InvalidInput("Scene::ignore_pair: both ids are " + std::to_string(a));
    if (!table_.ignored.insert(ObjectTable<S>::pair_key(sa, sb)).second) return;
    ++table_.ignore_count(sa);
    ++table_.ignore_count(sb);
    pair_filter_changed(sa, sb);
  }
  /// Reports the pair {a, b} again after ignore_pair. Throws for unknown ids; a pair that was not
  /// ignored is left alone.
  void unignore_pair(ObjectId a, ObjectId b) {
    const std::int32_t sa = slot_of(a, "Scene::unignore_pair"), sb = slot_of(b, "Scene::unignore_pair");
    if (!table_.ignored.erase(ObjectTable<S>::pair_key(sa, sb))) return;
    --table_.ignore_count(sa);
    --table_.ignore_count(sb);
    pair_filter_changed(sa, sb);
  }

  bool contains(ObjectId id) const { return ids_.count(id) != 0; }
  std::size_t size() const { return count_; }
  BroadPhaseKind broad_phase() const { return opt_.broad_phase; }
  /// The object's world AABB, what the broad phase compares: exact for spheres, particles and
  /// boxes, conservative for meshes. Throws for unknown ids.
  const Aabb<S>& bounds(ObjectId id) const { return table_.box(slot_of(id, "Scene::bounds")); }
  const RigidTransform<S>& pose(ObjectId id) const { return objects_[static_cast<std::size_t>(slot_of(id, "Scene::pose"))].pose; }
  const ShapeType& shape(ObjectId id) const { return objects_[static_cast<std::size_t>(slot_of(id, "Scene::shape"))].shape; }

  /// Applies the edits since the last query to the broad phase now (refits, rebuilds, cached
  /// candidates), adding its work to *stats; otherwise the first query after edits does it. An
  /// edit-class call: not concurrent with any other call. Useful before querying from many threads.
  void update(BroadPhaseStats* stats = nullptr) {
    BroadPhaseStats st;
    apply_pending(st);
    if (stats) *stats += st;
  }

  /// Sets SceneOptions::threads (an edit-class call).
  void set_threads(int threads) { opt_.threads = threads; }
  /// The thread count the next find_pairs or collide will use (1 below parallel_min_objects).
  int query_threads() const { return count_ < opt_.parallel_min_objects ? 1 : resolve_threads(opt_.threads); }

  /// Calls visit(ObjectId a, ObjectId b) -> bool (a < b) for every pair of the pair rule
  /// (broad_phase.hpp), each once, without allocating; stops when visit returns false. Returns
  /// false when stopped. Serial (visit runs on the calling thread).
  template <class Visit>
  bool for_each_pair(Visit&& visit, BroadPhaseStats& stats) const {
    apply_pending(stats);
    return std::visit(
        [&](const auto& b) {
          return b.find_pairs(
              table_,
              [&](std::int32_t x, std::int32_t y) {
                const auto [ia, ib] = ids_of(x, y);
                return bool(visit(ia, ib));
              },
              stats);
        },
        broad_);
  }

  /// The broad-phase pairs: objects whose world AABBs overlap, after the skip rules and filters.
  /// In the same order for every thread count.
  PairResult find_pairs() const {
    PairResult r;
    apply_pending(r.stats);
    const int threads = query_threads();
    if (threads <= 1) {
      std::visit(
          [&](const auto& b) {
            b.find_pairs(
                table_,
                [&](std::int32_t x, std::int32_t y) {
                  const auto [ia, ib] = ids_of(x, y);
                  r.pairs.push_back({ia, ib});
                  return true;
                },
                r.stats);
          },
          broad_);
      return r;
    }
    struct Part {
      std::vector<ObjectPair> pairs;
      BroadPhaseStats stats;
    };
    std::visit(
        [&](const auto& b) {
          const std::vector<PairTask> tasks = b.split_pairs(table_, 8 * std::size_t(threads));
          std::vector<Part> parts(tasks.size());
          parallel_for(tasks.size(), threads, [&](std::size_t k) {
            Part& part = parts[k];
            b.find_pairs_part(
                table_, tasks[k],
                [&](std::int32_t x, std::int32_t y) {
                  const auto [ia, ib] = ids_of(x, y);
                  part.pairs.push_back({ia, ib});
                  return true;
                },
                part.stats);
          });
          std::size_t total = 0;
          for (const Part& p : parts) total += p.pairs.size();
          r.pairs.reserve(total);
          for (const Part& p : parts) {
            r.pairs.insert(r.pairs.end(), p.pairs.begin(), p.pairs.end());
            r.stats += p.stats;
          }
        },
        broad_);
    return r;
  }

  /// Broad phase, then the narrow phase (narrow_dispatch.hpp) on each candidate pair: the pairs
  /// whose shapes touch, with contacts when asked for. stop_at_first stops both phases at the first
  /// colliding pair. The same pairs, contacts and counters (in the same order) for every thread
  /// count; with stop_at_first, the pair the serial path would find first.
  SceneCollideResult<S> collide(const SceneCollideOptions& options = {}) const {
    SceneCollideResult<S> r;
    apply_pending(r.stats);
    const int threads = query_threads();
    if (threads <= 1) {
      std::visit(
          [&](const auto& b) {
            b.find_pairs(
                table_, [&](std::int32_t x, std::int32_t y) { return narrow_pair(x, y, options, r.pairs, r.contacts, r.stats); },
                r.stats);
          },
          broad_);
      r.colliding = !r.pairs.empty();
      return r;
    }
    struct Part {
      std::vector<ObjectPair> pairs;
      std::vector<SceneContact<S>> contacts;
      BroadPhaseStats stats;
    };
    std::visit(
        [&](const auto& b) {
          const std::vector<PairTask> tasks = b.split_pairs(table_, 8 * std::size_t(threads));
          std::vector<Part> parts(tasks.size());
          // With stop_at_first, the lowest part that found a pair: later parts give up (their
          // results would be dropped); earlier ones run to their end or their own first pair.
          std::atomic<std::size_t> first_hit{std::numeric_limits<std::size_t>::max()};
          parallel_for(tasks.size(), threads, [&](std::size_t k) {
            if (options.stop_at_first && first_hit.load(std::memory_order_relaxed) < k) return;
            Part& part = parts[k];
            b.find_pairs_part(
                table_, tasks[k],
                [&](std::int32_t x, std::int32_t y) {
                  if (options.stop_at_first && first_hit.load(std::memory_order_relaxed) < k) return false;
                  if (narrow_pair(x, y, options, part.pairs, part.contacts, part.stats)) return true;
                  std::size_t f = first_hit.load(std::memory_order_relaxed);
                  while (k < f && !first_hit.compare_exchange_weak(f, k, std::memory_order_relaxed)) {
                  }
                  return false;
                },
                part.stats);
          });
          for (const Part& p : parts) {
            r.pairs.insert(r.pairs.end(), p.pairs.begin(), p.pairs.end());
            r.contacts.insert(r.contacts.end(), p.contacts.begin(), p.contacts.end());
            r.stats += p.stats;
            if (options.stop_at_first && !p.pairs.empty()) break;
          }
        },
        broad_);
    r.colliding = !r.pairs.empty();
    return r;
  }

  /// True when any two objects touch (stops at the first pair found).
  bool any_collision(BroadPhaseStats* stats = nullptr) const {
    SceneCollideOptions o;
    o.stop_at_first = true;
    const auto r = collide(o);
    if (stats) *stats = r.stats;
    return r.colliding;
  }

  /// The broad phase in use, for inspection in tests (e.g. tree validity).
  template <class B>
  const B* broad_phase_as() const {
    return std::get_if<B>(&broad_);
  }

 private:
  struct Object {
    ObjectId id = 0;
    ShapeType shape;
    RigidTransform<S> pose;
    typename Shapes::Local local;  ///< what world_box needs besides the shape and the pose
  };

  /// The ignore list changed for the pair (sa, sb): only its dynamic members can hold cached
  /// results about it (static–static pairs are never reported).
  void pair_filter_changed(std::int32_t sa, std::int32_t sb) {
    std::visit(
        [&](auto& bp) {
          if (!table_.is_static(sa)) bp.filter_changed(sa, table_);
          if (!table_.is_static(sb)) bp.filter_changed(sb, table_);
        },
        broad_);
    pending_.mark();
  }

  /// Applies pending edits to the broad phase (once; concurrent queries wait for it).
  void apply_pending(BroadPhaseStats& stats) const {
    pending_.apply([&] {
      const int threads = query_threads();
      std::visit([&](auto& b) { b.update(table_, stats, threads); }, broad_);
    });
  }

  /// The ids of slots x and y, smaller first.
  std::pair<ObjectId, ObjectId> ids_of(std::int32_t x, std::int32_t y) const {
    ObjectId ia = slot_ids_[static_cast<std::size_t>(x)], ib = slot_ids_[static_cast<std::size_t>(y)];
    if (ib < ia) std::swap(ia, ib);
    return {ia, ib};
  }

  /// The narrow phase of one candidate pair, appended to pairs/contacts when the shapes touch.
  /// Returns whether the traversal goes on (false: stop at this first colliding pair).
  bool narrow_pair(std::int32_t x, std::int32_t y, const SceneCollideOptions& options, std::vector<ObjectPair>& pairs,
                   std::vector<SceneContact<S>>& contacts, BroadPhaseStats& stats) const {
    const Object* oa = &objects_[static_cast<std::size_t>(x)];
    const Object* ob = &objects_[static_cast<std::size_t>(y)];
    if (ob->id < oa->id) std::swap(oa, ob);
    ++stats.narrow_tests;
    ShapeContact<S> c;
    if (!shapes_.intersect(oa->shape, oa->pose, ob->shape, ob->pose, options.contacts ? &c : nullptr, stats)) return true;
    pairs.push_back({oa->id, ob->id});
    if (options.contacts) {
      ++stats.contacts;
      contacts.push_back({oa->id, ob->id, c});
    }
    return !options.stop_at_first;
  }

  std::int32_t slot_of(ObjectId id, const char* where) const {
    const auto it = ids_.find(id);
    if (it == ids_.end()) throw InvalidInput(std::string(where) + ": unknown object id " + std::to_string(id));
    return it->second;
  }

  /// validate_pose with the object's name in the message. The plainly valid case is decided first
  /// without building the name (set_pose runs once per moving object and step).
  static void check_pose(const RigidTransform<S>& pose, const char* where, ObjectId id) {
    if (IMPACT_LIKELY(plainly_rigid(pose))) return;
    validate_pose(pose, where, ("pose of object " + std::to_string(id)).c_str());
  }
  /// validate_pose's own test of the common case (t within CoordinateRange, R rigid within
  /// rotation_tolerance; NaN and infinities fail it), so that the name is built only when
  /// validate_pose is going to throw.
  static bool plainly_rigid(const RigidTransform<S>& pose) {
    constexpr S range = CoordinateRange<S>::max;
    const Vec3<S>& t = pose.t;
    return std::abs(t.x()) <= range && std::abs(t.y()) <= range && std::abs(t.z()) <= range && pose.is_rigid(rotation_tolerance<S>());
  }

  /// A broad phase of the enum, static_leaf_size >= 1, the tree's fat_fraction, fat_margin and
  /// predict finite and >= 0, its rebuild_ratio finite and >= 1.
  static void check_options(const SceneOptions& opt) {
    constexpr const char* where = "Scene";
    require(opt.broad_phase == BroadPhaseKind::AllPairs || opt.broad_phase == BroadPhaseKind::StaticDynamic ||
                opt.broad_phase == BroadPhaseKind::Hierarchical,
            where, "options.broad_phase is not a BroadPhaseKind");
    validate_in_range(opt.static_leaf_size, 1, 1 << 20, where, "options.static_leaf_size");
    validate_nonnegative(opt.tree.fat_fraction, where, "options.tree.fat_fraction");
    validate_nonnegative(opt.tree.fat_margin, where, "options.tree.fat_margin");
    validate_nonnegative(opt.tree.predict, where, "options.tree.predict");
    validate_finite(opt.tree.rebuild_ratio, where, "options.tree.rebuild_ratio");
    require(opt.tree.rebuild_ratio >= 1.0, where, "options.tree.rebuild_ratio must be >= 1");
  }

  SceneOptions opt_;
  Shapes shapes_;
  ObjectTable<S> table_;
  std::vector<Object> objects_;
  std::vector<ObjectId> slot_ids_;  ///< objects_[slot].id, dense: reporting a pair reads only these
  std::unordered_map<ObjectId, std::int32_t> ids_;
  std::vector<std::int32_t> free_;
  std::size_t count_ = 0;
  /// Mutable: the first query after edits applies them (apply_pending, under pending_'s lock).
  mutable std::variant<AllPairsBroadPhase<S>, StaticDynamicBroadPhase<S>, HierarchicalBroadPhase<S>> broad_;
  mutable detail::PendingEdits pending_;
};

}  // namespace impact
