// Structural invariants of the BVH built by backends/bvh: node layout, containment, leaf sizes, primitive
// coverage, kind separation, depth cap and SAH quality against an object-median build.

#include "backends/bvh/bvh_backend.h"
#include "backends/bvh/bvh_builder.h"
#include "backends/bvh/primitive_gather.h"
#include "backends/wide/wide_backend.h"
#include "core/sampling/rng.h"
#include "core/scene/procedural.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace twinray {
namespace {

struct NamedScene {
  std::string name;
  SceneGeometry geometry;
};

std::vector<NamedScene> test_scenes() {
  std::vector<NamedScene> scenes;
  scenes.push_back({"soup", random_triangle_soup(4000, 11)});
  scenes.push_back({"tessellated sphere", tessellated_sphere(glm::vec3(1.0f, 2.0f, 3.0f), 2.0f, 4)});
  scenes.push_back({"grid", grid_mesh(40, 30)});
  scenes.push_back({"spheres", random_spheres(600, 12)});
  scenes.push_back({"mixed", mixed_spheres_and_triangles(300, 1500, 13)});
  return scenes;
}

Bounds3 node_bounds(const BvhNode& n) { return {n.lo, n.hi}; }

// Walks the tree from the root, checking what must hold at every node, and records every primitive key
// found in a leaf.
struct TreeChecker {
  const BvhBackend& bvh;
  const SceneGeometry& geometry;
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> seen;  // (geom_id, prim_id) -> leaves holding it
  std::size_t reached = 0, leaves = 0, max_depth = 0;

  Bounds3 primitive_bounds(const PrimitiveKey& key, bool sphere) const {
    if (sphere) {
      for (const Sphere& s : geometry.spheres)
        if (s.geom_id == key.geom_id) return s.bounds();
    } else {
      for (const TriangleMesh& m : geometry.meshes) {
        if (m.geom_id != key.geom_id) continue;
        const glm::uvec3 tri = m.indices.at(key.prim_id);
        Bounds3 b = Bounds3::of_point(m.positions[tri.x]);
        b.extend(m.positions[tri.y]);
        b.extend(m.positions[tri.z]);
        return b;
      }
    }
    ADD_FAILURE() << "key (" << key.geom_id << ", " << key.prim_id << ") names no primitive";
    return {};
  }

  void visit(std::uint32_t index, std::size_t depth) {
    const std::span<const BvhNode> nodes = bvh.nodes();
    ASSERT_LT(index, nodes.size());
    ++reached;
    max_depth = std::max(max_depth, depth);
    ASSERT_LT(depth, kBvhMaxDepth);
    const BvhNode& node = nodes[index];
    if (!node.is_leaf()) {
      const std::uint32_t left = index + 1, right = node.second_child();
      ASSERT_GT(right, left);  // depth-first: the second child follows the whole first subtree
      EXPECT_TRUE(node_bounds(node).contains(node_bounds(nodes[left]))) << "node " << index;
      EXPECT_TRUE(node_bounds(node).contains(node_bounds(nodes[right]))) << "node " << index;
      visit(left, depth + 1);
      visit(right, depth + 1);
      return;
    }
    ++leaves;
    const std::uint32_t count = node.prim_count();
    EXPECT_GE(count, 1u);
    EXPECT_LE(count, static_cast<std::uint32_t>(bvh.options().max_leaf_size)) << "leaf " << index;
    const bool sphere = node.is_sphere_leaf();
    const PrimitiveStore& store = bvh.primitives();
    const auto& keys = sphere ? store.sphere_keys : store.triangle_keys;
    ASSERT_LE(std::size_t{node.first_prim()} + count, keys.size());
    if (!sphere) {
      EXPECT_EQ(node.first_prim() % kTriangleBlockLanes, 0u) << "a triangle leaf starts a block";
    }
    for (std::uint32_t i = node.first_prim(); i < node.first_prim() + count; ++i) {
      ++seen[{keys[i].geom_id, keys[i].prim_id}];
      EXPECT_TRUE(node_bounds(node).contains(primitive_bounds(keys[i], sphere))) << "leaf " << index;
    }
  }
};

void check_tree(const SceneGeometry& geometry, const BvhBuildOptions& options, const std::string& name) {
  SCOPED_TRACE(name);
  BvhBackend bvh(options);
  bvh.build(geometry);
  ASSERT_FALSE(bvh.nodes().empty());
  TreeChecker checker{bvh, geometry, {}};
  checker.visit(0, 0);
  EXPECT_EQ(checker.reached, bvh.nodes().size()) << "every node is reachable exactly once";

  // Every primitive in exactly one leaf.
  EXPECT_EQ(checker.seen.size(), geometry.primitive_count());
  for (const auto& [key, leaves] : checker.seen) EXPECT_EQ(leaves, 1) << key.first << "/" << key.second;
  for (const TriangleMesh& m : geometry.meshes)
    for (std::uint32_t i = 0; i < m.indices.size(); ++i) EXPECT_TRUE(checker.seen.count({m.geom_id, i}));
  for (const Sphere& s : geometry.spheres) EXPECT_TRUE(checker.seen.count({s.geom_id, 0u}));

  // The leaf-ordered copy is bit-identical to the scene's geometry.
  const PrimitiveStore& store = bvh.primitives();
  ASSERT_EQ(store.triangle_keys.size(), store.triangle_blocks.size() * kTriangleBlockLanes);
  for (std::uint32_t slot = 0; slot < store.triangle_keys.size(); ++slot) {
    const PrimitiveKey key = store.triangle_keys[slot];
    if (key.is_padding()) continue;
    for (const TriangleMesh& m : geometry.meshes) {
      if (m.geom_id != key.geom_id) continue;
      const glm::uvec3 tri = m.indices[key.prim_id];
      EXPECT_EQ(store.triangle_vertex(slot, 0), m.positions[tri.x]);
      EXPECT_EQ(store.triangle_vertex(slot, 1), m.positions[tri.y]);
      EXPECT_EQ(store.triangle_vertex(slot, 2), m.positions[tri.z]);
    }
  }

  const BuildStats stats = bvh.build_stats();
  EXPECT_EQ(stats.nodes, bvh.nodes().size());
  EXPECT_EQ(stats.leaves, checker.leaves);
  EXPECT_EQ(stats.max_depth, checker.max_depth);
  EXPECT_EQ(stats.nodes, 2 * stats.leaves - 1);  // a binary tree
  EXPECT_EQ(stats.triangles, geometry.triangle_count());
  EXPECT_EQ(stats.spheres, geometry.sphere_count());
  EXPECT_EQ(stats.built_triangles, geometry.has_triangles());
  EXPECT_EQ(stats.built_spheres, geometry.has_spheres());
  EXPECT_GE(stats.memory_bytes, stats.nodes * sizeof(BvhNode));
  EXPECT_GT(stats.sah_cost, 0.0);
}

TEST(BvhInvariants, NodeIs32Bytes) { EXPECT_EQ(sizeof(BvhNode), 32u); }

TEST(BvhInvariants, TreesAreWellFormed) {
  for (const NamedScene& scene : test_scenes()) {
    check_tree(scene.geometry, {}, scene.name);
    BvhBuildOptions small_leaves;
    small_leaves.max_leaf_size = 1;
    small_leaves.bins = 32;
    check_tree(scene.geometry, small_leaves, scene.name + " (leaf size 1, 32 bins)");
    BvhBuildOptions median;
    median.split_method = BvhSplitMethod::ObjectMedian;
    median.max_leaf_size = 3;
    check_tree(scene.geometry, median, scene.name + " (object median)");
  }
}

TEST(BvhInvariants, SerialAndParallelBuildsAreIdentical) {
  // 20000: parallel recursion only; 70000: the top nodes also bin (merging per-chunk bin grids) and
  // partition in parallel chunks, each chunk's sides placed by its own bin counts (a serial build runs the
  // same chunks one after the other). The triangles are sorted along x so that each chunk fills different
  // bins and the merge has to combine them. Both the bvh's options and bvh8's binary tree's, nodes and
  // primitive order.
  for (const int triangles : {20000, 70000}) {
    SceneGeometry soup = random_triangle_soup(triangles, 5);
    TriangleMesh& mesh = soup.meshes.front();
    std::sort(mesh.indices.begin(), mesh.indices.end(),
              [&](const auto& a, const auto& b) { return mesh.positions[a.x].x < mesh.positions[b.x].x; });
    BvhBuildOptions serial;
    serial.parallel = false;
    BvhBackend a(serial), b{BvhBuildOptions{}};
    a.build(soup);
    b.build(soup);
    ASSERT_EQ(a.nodes().size(), b.nodes().size()) << triangles;
    EXPECT_EQ(0, std::memcmp(a.nodes().data(), b.nodes().data(), a.nodes().size_bytes())) << triangles;

    const std::vector<Bounds3> bounds = primitive_bounds(soup);
    for (BvhBuildOptions options : {BvhBuildOptions{}, WideBuildOptions::default_binary()}) {
      const BvhTree parallel = build_bvh(bounds, static_cast<std::uint32_t>(bounds.size()), options);
      options.parallel = false;
      const BvhTree one_pass = build_bvh(bounds, static_cast<std::uint32_t>(bounds.size()), options);
      ASSERT_EQ(parallel.nodes.size(), one_pass.nodes.size()) << triangles;
      EXPECT_EQ(0, std::memcmp(parallel.nodes.data(), one_pass.nodes.data(), parallel.nodes.size() * sizeof(BvhNode)))
          << triangles;
      EXPECT_EQ(parallel.prim_order, one_pass.prim_order) << triangles;
    }
  }
}

TEST(BvhInvariants, EveryInstructionSetBuildsTheSameTree) {
  // The AVX2 binning kernel keeps bins as (lo, -hi) rows and must pick the same planes as the SSE2 one, and
  // the AVX2 builds of the sweeps, the partition and the chunk scatter must split the same way:
  // a mixed scene (ranges of 32 or more with both kinds, so the kinds are counted per bin) and the sorted
  // soup of 70000 whose top nodes merge per-chunk grids. On a CPU without AVX2 only SSE2 runs (compared
  // with itself).
  SceneGeometry soup = random_triangle_soup(70000, 5);
  TriangleMesh& mesh = soup.meshes.front();
  std::sort(mesh.indices.begin(), mesh.indices.end(),
            [&](const auto& a, const auto& b) { return mesh.positions[a.x].x < mesh.positions[b.x].x; });
  const std::pair<std::string, SceneGeometry> scenes[] = {{"mixed", mixed_spheres_and_triangles(2000, 6000, 21)},
                                                          {"sorted soup", std::move(soup)}};
  for (const auto& [name, geometry] : scenes) {
    const std::vector<Bounds3> bounds = primitive_bounds(geometry);
    const auto first_sphere = static_cast<std::uint32_t>(geometry.triangle_count());
    for (const BvhBuildOptions& options : {BvhBuildOptions{}, WideBuildOptions::default_binary()}) {
      const BvhTree sse2 = build_bvh(bounds, first_sphere, options, Isa::Sse2);
      for (const Isa isa : runnable_isas()) {
        const BvhTree tree = build_bvh(bounds, first_sphere, options, isa);
        ASSERT_EQ(sse2.nodes.size(), tree.nodes.size()) << name << " " << to_string(isa);
        EXPECT_EQ(0, std::memcmp(sse2.nodes.data(), tree.nodes.data(), tree.nodes.size() * sizeof(BvhNode))) << name << " " << to_string(isa);
        EXPECT_EQ(sse2.prim_order, tree.prim_order) << name << " " << to_string(isa);
      }
    }
  }
}

TEST(BvhInvariants, SmallNodeStaysALeafExactlyWhenItsCentroidsFallInTwoBins) {
  // bvh8's binary tree (leaves of at most 3, C_trav = C_isect) keeps a node of two primitives as a leaf when
  // a binned plane exists, which the builder decides from the centroid extents alone: some axis must have a
  // positive, finite extent with a finite scale (bins / extent). Otherwise it splits at the object median.
  const auto point = [](float x, float y) { return Bounds3{{x, y, 0.0f}, {x, y, 0.0f}}; };
  const auto nodes_of = [](std::vector<Bounds3> bounds) {
    return build_bvh(bounds, static_cast<std::uint32_t>(bounds.size()), WideBuildOptions::default_binary()).nodes.size();
  };
  EXPECT_EQ(1u, nodes_of({point(0.0f, 0.0f), point(1.0f, 0.0f)}));  // two bins on x
  // A denormal extent has an infinite scale: not binnable.
  EXPECT_EQ(3u, nodes_of({point(0.0f, 0.0f), point(1e-40f, 0.0f)}));
  // A centroid at infinity (0.5 (lo + hi) overflows): the extent is infinite, the scale 0, every centroid in
  // bin 0; binnable only through another axis.
  const Bounds3 far{{3.0e38f, 0.0f, 0.0f}, {3.4e38f, 0.0f, 0.0f}};
  EXPECT_EQ(3u, nodes_of({point(0.0f, 0.0f), far}));
  EXPECT_EQ(1u, nodes_of({point(0.0f, 1e-4f), far}));  // area 3.4e34: below the bound of the leaf check
}

TEST(BvhInvariants, SahBuildBeatsObjectMedian) {
  for (const NamedScene& scene : test_scenes()) {
    BvhBuildOptions median;
    median.split_method = BvhSplitMethod::ObjectMedian;
    BvhBackend sah_bvh, median_bvh(median);
    sah_bvh.build(scene.geometry);
    median_bvh.build(scene.geometry);
    EXPECT_LT(sah_bvh.build_stats().sah_cost, median_bvh.build_stats().sah_cost) << scene.name;
  }
}

TEST(BvhInvariants, CoincidentCentroidsStillRespectLeafSize) {
  // 200 copies of one triangle (and 50 of one sphere): no plane separates them, the builder must fall back
  // to splitting the list in half.
  SceneGeometry g;
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  for (int i = 0; i < 200; ++i) mesh.indices.emplace_back(0, 1, 2);
  g.meshes.push_back(mesh);
  for (std::uint32_t k = 1; k <= 50; ++k) g.spheres.push_back({k, glm::vec3(0.25f, 0.25f, 0.0f), 0.5f});
  check_tree(g, {}, "coincident");
}

TEST(BvhInvariants, LeavesNeverMixKinds) {
  // Implied by check_tree (a sphere leaf's keys index sphere_keys), made explicit: sphere leaves hold
  // exactly the spheres.
  const SceneGeometry g = mixed_spheres_and_triangles(200, 800, 21);
  BvhBackend bvh;
  bvh.build(g);
  std::size_t in_sphere_leaves = 0, in_triangle_leaves = 0;
  for (const BvhNode& n : bvh.nodes()) {
    if (!n.is_leaf()) continue;
    (n.is_sphere_leaf() ? in_sphere_leaves : in_triangle_leaves) += n.prim_count();
  }
  EXPECT_EQ(in_sphere_leaves, g.sphere_count());
  EXPECT_EQ(in_triangle_leaves, g.triangle_count());
}

TEST(BvhInvariants, OptionsAreValidated) {
  for (int bins : {12, 16, 32}) {
    BvhBuildOptions o;
    o.bins = bins;
    EXPECT_NO_THROW(BvhBackend{o});
  }
  for (int bins : {0, 11, 33}) {
    BvhBuildOptions o;
    o.bins = bins;
    EXPECT_THROW(BvhBackend{o}, std::invalid_argument);
  }
  BvhBuildOptions o;
  o.max_leaf_size = 0;
  EXPECT_THROW(BvhBackend{o}, std::invalid_argument);
  o = {};
  o.traversal_cost = 0.0f;
  EXPECT_THROW(make_bvh_backend(o), std::invalid_argument);
  EXPECT_EQ(make_bvh_backend()->name(), "bvh");
}

TEST(BvhInvariants, EmptySceneBuildsAndMisses) {
  BvhBackend bvh;
  const SceneGeometry empty;
  bvh.build(empty);
  EXPECT_TRUE(bvh.nodes().empty());
  Hit hit;
  EXPECT_FALSE(bvh.intersect(Ray{}, hit));
  EXPECT_FALSE(bvh.occluded(Ray{}));
}


// Any hit visits children in the closest-hit order and stops at its first hit, so on every ray it tests
// at most the boxes and primitives the closest-hit query tests: an any-hit query can never cost more.
TEST(BvhInvariants, AnyHitNeverDoesMoreWorkThanClosestHit) {
  const SceneGeometry g = mixed_spheres_and_triangles(30, 3000, 4);
  BvhBackend bvh;
  bvh.build(g);
  Rng rng(8, 1);
  const auto uniform = [&] { return 3.0f * rng.next_float() - 1.5f; };
  std::size_t hits = 0, cheaper = 0;
  for (int i = 0; i < 5000; ++i) {
    Ray ray;
    ray.org = {uniform(), uniform(), uniform()};
    ray.dir = glm::vec3(uniform(), uniform(), uniform()) - ray.org;
    if (ray.dir == glm::vec3(0.0f)) ray.dir.x = 1.0f;
    QueryStats closest, any;
    Hit hit;
    hits += bvh.intersect(ray, hit, &closest) ? 1 : 0;
    bvh.occluded(ray, &any);
    ASSERT_LE(any.nodes_visited, closest.nodes_visited) << "ray " << i;
    ASSERT_LE(any.primitives_tested, closest.primitives_tested) << "ray " << i;
    cheaper += any.nodes_visited < closest.nodes_visited ? 1 : 0;
  }
  EXPECT_GT(hits, 1000u);
  EXPECT_GT(cheaper, 100u);  // and it does stop early
}

}  // namespace
}  // namespace twinray
