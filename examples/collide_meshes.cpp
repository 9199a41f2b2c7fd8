// SPDX-License-Identifier: MIT
// Example: load two meshes (or generate a torus and a sphere), build AABB trees, place the second
// mesh with a rigid pose, and print the colliding triangle pairs with a contact point each.
//
//   example-collide_meshes [MESH_A [MESH_B]]
#include "impact/impact.hpp"
#ifdef IMPACT_HAVE_IO
#include "impact/io/load_mesh.hpp"
#endif

#include <cstdio>

int main(int argc, char** argv) {
  using namespace impact;
  TriangleMesh<double> a, b;
  try {
    if (argc > 1) {
#ifdef IMPACT_HAVE_IO
      a = load_mesh<double>(argv[1]);
      b = load_mesh<double>(argc > 2 ? argv[2] : argv[1]);
#else
      (void)argv;
      std::fprintf(stderr, "built without assimp: run without arguments\n");
      return 1;
#endif
    } else {
      a = make_torus<double>(1.0, 0.3, 64, 32);
      b = make_icosphere<double>(0.5, 3);
    }
  } catch (const InvalidInput& e) {  // unreadable file, NaN coordinates, bad indices...
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }

  // 1. Build one tree per mesh (validates the arrays, fits a box per node). Aabb is the safe
  //    choice on any mesh; Sphere trees use the least memory but degrade on long thin triangles,
  //    Obb trees prune best on smooth shapes (docs/hierarchies.md).
  const MeshBvh<Aabb<double>> tree_a(a), tree_b(b);

  // 2. Poses: A at the origin, B moved onto A's surface and tilted.
  const RigidTransform<double> pose_a;
  const Eigen::Vector3d size = a.V.colwise().maxCoeff() - a.V.colwise().minCoeff();
  const RigidTransform<double> pose_b(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()).toRotationMatrix(),
                                      Eigen::Vector3d(0.35 * size.x(), 0.0, 0.0));

  // 3. Query: every colliding pair, with contact points and normals.
  CollideOptions options;
  options.all_pairs = true;
  options.contacts = true;
  const auto result = collide(tree_a, pose_a, tree_b, pose_b, options);

  std::printf("A: %d triangles, B: %d triangles\n", a.num_triangles(), b.num_triangles());
  std::printf("colliding: %s, %zu triangle pairs (%llu BV tests, %llu triangle tests)\n", result.colliding ? "yes" : "no",
              result.pairs.size(), static_cast<unsigned long long>(result.stats.bv_tests),
              static_cast<unsigned long long>(result.stats.primitive_tests));
  for (std::size_t i = 0; i < result.contacts.size() && i < 20; ++i) {
    const auto& c = result.contacts[i];
    std::printf("  A#%d x B#%d at (%.4f, %.4f, %.4f)\n", c.triangle_a, c.triangle_b, c.point.x(), c.point.y(), c.point.z());
  }
  if (result.contacts.size() > 20) std::printf("  ... %zu more\n", result.contacts.size() - 20);
  return 0;
}
