// SPDX-License-Identifier: MIT
/// \file
/// ConvexScene<S>: the core's Scene (broad/scene.hpp) with the convex layer's shapes as objects
/// too: capsules, cylinders, cones and convex hulls beside spheres, boxes, meshes and particles,
/// static or dynamic, in every broad phase, with filters, the ignore list and sleeping as for any
/// object. Needs the impact::convex target (libccd).
///
///   impact::ConvexScene<double> scene({impact::BroadPhaseKind::Hierarchical});
///   scene.add(1, impact::Capsule<double>(0.2, 0.5), pose_a);                 // dynamic
///   scene.add(2, impact::ConvexSceneShape<double>::hull_of(hull), pose_b);   // hull shared, not copied
///   scene.add(3, impact::Shape<double>::mesh_of(ground), ground_pose, {impact::BodyType::Static});
///   auto hits = scene.collide({/*contacts=*/true});  // hits.contacts[i]: a < b, normal a -> b
///
/// How the core stays libccd-free: Scene takes its shape set as a second template parameter
/// (CoreSceneShapes by default: Shape<S> and the narrow phase of broad/narrow_dispatch.hpp). This
/// header gives another shape set, ConvexSceneShapes, whose shape type (ConvexSceneShape) holds a
/// core Shape or a convex one, and ConvexScene<S> = Scene<S, ConvexSceneShapes<S>>. The core
/// includes nothing of this header; a program that includes it links impact::convex. Everything is
/// resolved at compile time: the scene's loops call ConvexSceneShapes::intersect directly, which
/// branches once per pair on the two shapes' kinds (a switch, as the core's shapes_intersect does)
/// and then runs the templated query of that pair of types; no virtual call anywhere.
///
/// Narrow phase per pair (contact normal from the scene's a towards b):
///   core – core                       the core scene's (narrow_dispatch.hpp), unchanged
///   sphere/particle/box – convex,     convex/query.hpp on the pair of types: closed forms where
///   convex – convex                   they exist (sphere/capsule pairs, sphere–box), GJK on the
///                                     core of a sphere or capsule, libccd MPR (boolean) and the
///                                     own EPA (contacts, certified) for the general pairs; a
///                                     particle is a sphere of its radius (0: a point), a core box
///                                     is the convex layer's Box (a zero half extent: a flat box)
///   mesh – convex                     convex/mesh_convex.hpp through the mesh's sphere tree:
///                                     boolean mesh_convex_collides; contact: the deepest of
///                                     mesh_convex_contacts (every touching triangle's convex
///                                     penetration; normal from the triangle towards the shape,
///                                     flipped when the mesh is b)
/// Semantics are the convex layer's: solids, except meshes, which are surfaces (a shape wholly
/// inside a closed mesh does not touch it); touching counts as intersecting. A contact is one
/// point per pair (the deepest); depth and normal are defined as in convex/query.hpp: translating
/// b by depth * normal makes the two only touch.
///
/// Numerical contract: APPROXIMATE for pairs with a convex shape, with convex/query.hpp's
/// contracts (closed forms to rounding; GJK and MPR count pairs within relative_tolerance times the
/// larger shape's size as touching). The world boxes of the broad phase are the shapes' tight boxes
/// (six support calls), padded as the core scene pads them for rounding (pad_scene_box) and by
/// 4 relative_tolerance times the box's half diagonal, so that the broad phase never drops a pair
/// the narrow phase would report. The boolean query (collide without contacts) and the contact
/// query can disagree on pairs within the tolerance of touching (different solvers).
///
/// Validation: add() throws InvalidInput for an invalid convex shape (validate_shape: NaN, zero or
/// negative radii and lengths; a null or empty hull), as for core shapes; the solver options are
/// checked when the shape set is constructed. Iterative solvers are bounded by
/// options.max_iterations; collide() counts the pairs a bound stopped in stats.solver_limits.
/// Thread safety: as Scene's (the shape set is only read by queries; hulls and meshes are shared
/// read-only and must outlive the scene).
#pragma once

#include "impact/broad/scene.hpp"
#include "impact/convex/mesh_convex.hpp"
#include "impact/convex/query.hpp"

#include <string>
#include <type_traits>
#include <variant>

namespace impact {

/// The shape of a ConvexScene object: a core scene shape (Shape<S>: sphere, box, mesh, particle)
/// or a capsule, cylinder, cone or convex hull. Converts implicitly from each, so that
/// scene.add(id, Capsule<double>(0.2, 0.5), pose) reads as the core's add. A hull is shared by
/// pointer (hull_of) and must outlive the scene, as a mesh must.
template <class S>
struct ConvexSceneShape {
  using Convex = std::variant<std::monostate, Capsule<S>, Cylinder<S>, Cone<S>, const ConvexHull<S>*>;
  Shape<S> core;  ///< the shape, when `convex` holds std::monostate
  Convex convex;  ///< the convex-layer shape, or std::monostate

  ConvexSceneShape() = default;
  ConvexSceneShape(const Shape<S>& s) : core(s) {}  // NOLINT(google-explicit-constructor): implicit by design
  ConvexSceneShape(const Capsule<S>& c) : convex(c) {}  // NOLINT(google-explicit-constructor)
  ConvexSceneShape(const Cylinder<S>& c) : convex(c) {}  // NOLINT(google-explicit-constructor)
  ConvexSceneShape(const Cone<S>& c) : convex(c) {}  // NOLINT(google-explicit-constructor)
  /// The convex layer's Box is the core's box shape.
  ConvexSceneShape(const Box<S>& b) : core(Shape<S>::box(b.half)) {}  // NOLINT(google-explicit-constructor)
  /// `h` is not copied: it must outlive the scene.
  static ConvexSceneShape hull_of(const ConvexHull<S>& h) {
    ConvexSceneShape s;
    s.convex = &h;
    return s;
  }
  /// Holds a capsule, cylinder, cone or hull (not a core shape).
  bool is_convex() const { return convex.index() != 0; }
};

namespace detail {
/// Order of the convex kinds in a pair: the query of a pair runs with the lower first (the other
/// order flips the normal), so each unordered pair of types is instantiated once.
template <class T>
struct ConvexSceneRank;
template <class S>
struct ConvexSceneRank<Capsule<S>> : std::integral_constant<int, 1> {};
template <class S>
struct ConvexSceneRank<Cylinder<S>> : std::integral_constant<int, 2> {};
template <class S>
struct ConvexSceneRank<Cone<S>> : std::integral_constant<int, 3> {};
template <class S>
struct ConvexSceneRank<ConvexHull<S>> : std::integral_constant<int, 4> {};

/// Calls f with the convex shape held by s (s.is_convex()).
template <class S, class F>
decltype(auto) with_convex_shape(const ConvexSceneShape<S>& s, F&& f) {
  switch (s.convex.index()) {
    case 1:
      return f(*std::get_if<1>(&s.convex));
    case 2:
      return f(*std::get_if<2>(&s.convex));
    case 3:
      return f(*std::get_if<3>(&s.convex));
    default:
      return f(**std::get_if<4>(&s.convex));
  }
}
}  // namespace detail

/// The shape set of ConvexScene (see broad/scene.hpp, CoreSceneShapes, for what a shape set is).
template <class S>
class ConvexSceneShapes {
 public:
  using Shape = ConvexSceneShape<S>;
  using Local = typename CoreSceneShapes<S>::Local;  ///< convex shapes: their box in their own frame, reach = size

  /// The default options.
  ConvexSceneShapes() : ConvexSceneShapes(ConvexQueryOptions<S>{}) {}
  /// `convex`: the solvers' options (tolerances, iteration bound) of every pair with a convex
  /// shape; `fast_mesh_contacts`: MeshConvexOptions::fast_contacts for mesh–convex contacts.
  /// Throws InvalidInput for options outside their ranges.
  explicit ConvexSceneShapes(const ConvexQueryOptions<S>& convex, bool fast_mesh_contacts = false) : options_(convex) {
    detail::validate_query_options(convex, "ConvexSceneShapes");
    mesh_options_.convex = convex;
    mesh_options_.fast_contacts = fast_mesh_contacts;
  }
  const ConvexQueryOptions<S>& options() const { return options_; }

  Local local(const Shape& s) const {
    if (!s.is_convex()) return CoreSceneShapes<S>::local(s.core);
    return detail::with_convex_shape(s, [](const auto& x) {
      Local l;
      l.box = bounding_box(x, RigidTransform<S>());
      l.reach = shape_size(x);
      return l;
    });
  }

  void check(const Shape& s, const std::string& who) const {
    if (!s.is_convex()) return CoreSceneShapes<S>::check(s.core, who);
    if (const auto* h = std::get_if<4>(&s.convex); h && !*h) throw InvalidInput(who + ": null convex hull");
    detail::with_convex_shape(s, [&](const auto& x) { validate_shape(x, who.c_str()); });
  }

  Aabb<S> world_box(const Shape& s, const Local& l, const RigidTransform<S>& pose) const {
    Aabb<S> box;
    if (!s.is_convex()) {
      box = CoreSceneShapes<S>::world_box(s.core, l, pose);
    } else {
      box = detail::with_convex_shape(s, [&](const auto& x) { return bounding_box(x, pose); });
      pad_scene_box(box, pose, S(l.box.center().cwiseAbs().sum() + (l.box.max - l.box.min).sum()), false);
    }
    // what GJK and MPR count as touching: within relative_tolerance of the larger shape's size
    const S pad = S(4) * options_.relative_tolerance * ((box.max - box.min).norm() / S(2));
    box.min.array() -= pad;
    box.max.array() += pad;
    return box;
  }

  /// The narrow phase of the pair (a at pa, b at pb): see the file comment.
  bool intersect(const Shape& a, const RigidTransform<S>& pa, const Shape& b, const RigidTransform<S>& pb, ShapeContact<S>* contact,
                 BroadPhaseStats& stats) const {
    if (!a.is_convex() && !b.is_convex()) return shapes_intersect(a.core, pa, b.core, pb, contact);
    if (!a.is_convex())
      return detail::with_convex_shape(b, [&](const auto& y) { return core_convex(a.core, pa, y, pb, false, contact, stats); });
    if (!b.is_convex())
      return detail::with_convex_shape(a, [&](const auto& x) { return core_convex(b.core, pb, x, pa, true, contact, stats); });
    return detail::with_convex_shape(a, [&](const auto& x) {
      return detail::with_convex_shape(b, [&](const auto& y) { return ordered_pair(x, pa, y, pb, contact, stats); });
    });
  }

 private:
  static bool flip(bool hit, ShapeContact<S>* contact) {
    if (hit && contact) contact->normal = -contact->normal;
    return hit;
  }

  /// The query of convex/query.hpp on the pair of types (x first): contact or boolean.
  template <class X, class Y>
  bool pair(const X& x, const RigidTransform<S>& px, const Y& y, const RigidTransform<S>& py, ShapeContact<S>* contact,
            BroadPhaseStats& stats) const {
    if (contact) {
      const ConvexContact<S> c = detail::penetration_unchecked(x, px, y, py, options_);
      if (c.limit_reached) ++stats.solver_limits;
      if (!c.intersecting) return false;
      contact->point = c.point;
      contact->normal = c.normal;
      contact->depth = c.depth;
      return true;
    }
    bool limit = false;
    const bool hit = detail::intersect_unchecked(x, px, y, py, options_, &limit);
    if (limit) ++stats.solver_limits;
    return hit;
  }

  /// Two convex shapes, the lower rank first.
  template <class X, class Y>
  bool ordered_pair(const X& x, const RigidTransform<S>& px, const Y& y, const RigidTransform<S>& py, ShapeContact<S>* contact,
                    BroadPhaseStats& stats) const {
    if constexpr (detail::ConvexSceneRank<X>::value > detail::ConvexSceneRank<Y>::value)
      return flip(pair(y, py, x, px, contact, stats), contact);
    else
      return pair(x, px, y, py, contact, stats);
  }

  /// A core shape c (at pc) against a convex shape y (at py); `c_is_b`: c is the scene's b.
  template <class Y>
  bool core_convex(const impact::Shape<S>& c, const RigidTransform<S>& pc, const Y& y, const RigidTransform<S>& py, bool c_is_b,
                   ShapeContact<S>* contact, BroadPhaseStats& stats) const {
    bool hit = false;
    switch (c.kind) {
      case ShapeKind::Sphere:
      case ShapeKind::Particle: {
        const Sphere<S> ball(Vec3<S>::Zero(), c.radius);  // radius 0: a point (the queries take it)
        hit = pair(ball, pc, y, py, contact, stats);
        break;
      }
      case ShapeKind::Box: {
        Box<S> box(Vec3<S>::Ones());
        box.half = c.half;  // a zero half extent (flat box) is allowed here, as in the core scene
        hit = pair(box, pc, y, py, contact, stats);
        break;
      }
      case ShapeKind::Mesh:
      default:
        hit = mesh_convex(*c.mesh, pc, y, py, contact, stats);
        break;
    }
    return c_is_b ? flip(hit, contact) : hit;
  }

  /// A mesh against a convex shape; the normal from the triangle towards the shape.
  template <class Y>
  bool mesh_convex(const typename impact::Shape<S>::MeshType& m, const RigidTransform<S>& pm, const Y& y, const RigidTransform<S>& py,
                   ShapeContact<S>* contact, BroadPhaseStats& stats) const {
    if (!contact) {
      bool limit = false;
      const bool hit = mesh_convex_collides(m, pm, y, py, mesh_options_, nullptr, &limit);
      if (limit) ++stats.solver_limits;
      return hit;
    }
    const MeshConvexContacts<S> r = mesh_convex_contacts(m, pm, y, py, mesh_options_);
    if (r.limit_reached) ++stats.solver_limits;
    const std::ptrdiff_t k = r.deepest();
    if (k < 0) return false;
    const ConvexContact<S>& c = r.contacts[static_cast<std::size_t>(k)].contact;
    contact->point = c.point;
    contact->normal = c.normal;
    contact->depth = c.depth;
    return true;
  }

  ConvexQueryOptions<S> options_;
  MeshConvexOptions<S> mesh_options_;
};

/// The scene with convex shapes (see the file comment).
template <class S>
using ConvexScene = Scene<S, ConvexSceneShapes<S>>;

}  // namespace impact
