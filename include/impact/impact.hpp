// SPDX-License-Identifier: MIT
/// \file
/// Umbrella header for the core (Eigen only): geometry, fitting, the hierarchy, narrow-phase tests
/// and mesh queries. Optional parts keep their own headers: impact/io (assimp), impact/ccd,
/// impact/broad, impact/response.
#pragma once

#include "impact/core/config.hpp"
#include "impact/core/error.hpp"
#include "impact/core/parallel.hpp"
#include "impact/core/types.hpp"

#include "impact/geometry/aabb.hpp"
#include "impact/geometry/mesh_generators.hpp"
#include "impact/geometry/obb.hpp"
#include "impact/geometry/plane.hpp"
#include "impact/geometry/ray.hpp"
#include "impact/geometry/sphere.hpp"
#include "impact/geometry/transform.hpp"
#include "impact/geometry/triangle.hpp"
#include "impact/geometry/triangle_mesh.hpp"

#include "impact/fit/bounding_sphere.hpp"
#include "impact/fit/bv_traits.hpp"

#include "impact/bvh/build_config.hpp"
#include "impact/bvh/build_top_down.hpp"
#include "impact/bvh/bvh.hpp"
#include "impact/bvh/mesh_bvh.hpp"
#include "impact/bvh/refit.hpp"
#include "impact/bvh/traverse.hpp"
#include "impact/bvh/traverse_pair.hpp"

#include "impact/narrow/closest_point.hpp"
#include "impact/narrow/predicates.hpp"
#include "impact/narrow/ray_triangle.hpp"
#include "impact/narrow/sphere_triangle.hpp"
#include "impact/narrow/triangle_triangle.hpp"

#include "impact/query/closest_point_mesh.hpp"
#include "impact/query/mesh_collide.hpp"
#include "impact/query/ray_mesh.hpp"
#include "impact/query/swept_sphere_mesh.hpp"
