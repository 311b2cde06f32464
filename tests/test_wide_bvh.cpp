// The 8-wide tree (backends/wide): its structure after the cost-driven collapse, and the run-time choice of
// instruction set. Its answers are checked against the brute-force oracle on every instruction set in
// test_bvh_vs_brute.cpp, its batches in test_bvh_batch.cpp, and against Embree in test_backends_agree.cpp.

#include "backends/bvh/bvh_builder.h"
#include "backends/simd/isa.h"
#include "backends/bvh/primitive_gather.h"
#include "backends/wide/wide_any_order.h"
#include "backends/wide/wide_backend.h"
#include "backends/wide/wide_collapse.h"
#include "core/scene/procedural.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <cstdlib>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace twinray {
namespace {

TEST(WideBvh, NodeIs224Bytes) { EXPECT_EQ(sizeof(WideNode), 224u); }

// Walks the tree from the root: every filled slot's box contains its subtree, empty slots come last and
// hold the empty box, every primitive is in exactly one leaf, and leaves never mix kinds.
void expect_well_formed(const WideBackend& tree, const SceneGeometry& g) {
  const std::span<const WideNode> nodes = tree.nodes();
  const PrimitiveStore& prims = tree.primitives();
  ASSERT_FALSE(nodes.empty());
  std::multiset<std::pair<std::uint32_t, std::uint32_t>> seen;  // (geom, prim) of every stored primitive
  std::vector<std::uint32_t> stack = {0};
  std::size_t visited = 0;
  while (!stack.empty()) {
    const WideNode& node = nodes[stack.back()];
    stack.pop_back();
    ++visited;
    bool empty_seen = false;
    int filled = 0;
    for (int s = 0; s < kWideWidth; ++s) {
      const Bounds3 box{{node.lo[0][s], node.lo[1][s], node.lo[2][s]}, {node.hi[0][s], node.hi[1][s], node.hi[2][s]}};
      const bool empty = std::isinf(box.lo.x) && box.lo.x > 0 && std::isinf(box.hi.x) && box.hi.x < 0;
      if (empty) {
        empty_seen = true;
        continue;
      }
      ASSERT_FALSE(empty_seen) << "filled slots come first";
      ++filled;
      const std::uint32_t ref = node.child[s];
      if (!WideRef::is_leaf(ref)) {
        // A node's byte offset (wide_node.h), never the root's.
        ASSERT_EQ(ref % sizeof(WideNode), 0u);
        ASSERT_GT(ref, 0u);
        ASSERT_LT(wide_node_index(ref), nodes.size());
        const WideNode& child = nodes[wide_node_index(ref)];
        for (int c = 0; c < kWideWidth; ++c) {
          if (std::isinf(child.lo[0][c])) continue;
          for (int a = 0; a < 3; ++a) {
            EXPECT_LE(box.lo[a], child.lo[a][c]);
            EXPECT_GE(box.hi[a], child.hi[a][c]);
          }
        }
        stack.push_back(wide_node_index(ref));
        continue;
      }
      const std::uint32_t first = WideRef::first(ref), count = WideRef::count(ref);
      ASSERT_LE(count, WideRef::kMaxLeafCount);
      if (!WideRef::is_sphere_leaf(ref)) {
        // Leaves share blocks but never touch more of them than ceil(count / 4), the block tests an
        // aligned leaf costs; the decode names the same lanes.
        const std::uint32_t blocks_needed = (count + kTriangleBlockLanes - 1) / kTriangleBlockLanes;
        EXPECT_EQ((first + count - 1) / kTriangleBlockLanes - first / kTriangleBlockLanes + 1, blocks_needed);
        const WideTriangleLeaf leaf = wide_triangle_leaf(ref);
        EXPECT_EQ(leaf.block, first / kTriangleBlockLanes);
        EXPECT_EQ(static_cast<std::uint32_t>(__builtin_popcount(leaf.lanes)), count);
        EXPECT_EQ(static_cast<std::uint32_t>(__builtin_ctz(leaf.lanes)), first % kTriangleBlockLanes);
        ASSERT_LE(std::size_t{first} + count, prims.triangle_keys.size());
      }
      for (std::uint32_t i = 0; i < count; ++i) {
        if (WideRef::is_sphere_leaf(ref)) {
          const StoredSphere& sp = prims.spheres[first + i];
          for (int a = 0; a < 3; ++a) {
            EXPECT_LE(box.lo[a], sp.center[a] - sp.radius);
            EXPECT_GE(box.hi[a], sp.center[a] + sp.radius);
          }
          seen.insert({prims.sphere_keys[first + i].geom_id, prims.sphere_keys[first + i].prim_id});
        } else {
          const std::uint32_t slot = first + i;
          for (std::uint32_t v = 0; v < 3; ++v) {
            const glm::vec3 p = prims.triangle_vertex(slot, v);
            for (int a = 0; a < 3; ++a) {
              EXPECT_LE(box.lo[a], p[a]);
              EXPECT_GE(box.hi[a], p[a]);
            }
          }
          ASSERT_FALSE(prims.triangle_keys[slot].is_padding());
          seen.insert({prims.triangle_keys[slot].geom_id, prims.triangle_keys[slot].prim_id});
        }
      }
    }
    EXPECT_GE(filled, 1);
  }
  EXPECT_EQ(visited, nodes.size()) << "every node reachable exactly once";
  EXPECT_EQ(seen.size(), g.primitive_count());
  // Lanes no leaf holds are padding: the leaves' lanes are all the store's keyed ones.
  EXPECT_EQ(std::count_if(prims.triangle_keys.begin(), prims.triangle_keys.end(),
                          [](const PrimitiveKey& key) { return !key.is_padding(); }),
            static_cast<std::ptrdiff_t>(g.triangle_count()));
  for (const TriangleMesh& mesh : g.meshes)
    for (std::uint32_t i = 0; i < mesh.indices.size(); ++i) EXPECT_EQ(seen.count({mesh.geom_id, i}), 1u);
  for (const Sphere& s : g.spheres) EXPECT_EQ(seen.count({s.geom_id, 0u}), 1u);
}

TEST(WideBvh, TreesAreWellFormed) {
  for (const SceneGeometry& g : {random_triangle_soup(3000, 5), mixed_spheres_and_triangles(60, 900, 2),
                                 random_spheres(100, 4), grid_mesh(3, 3)}) {
    WideBackend tree;
    tree.build(g);
    expect_well_formed(tree, g);
    EXPECT_GT(tree.build_stats().nodes, 0u);
    EXPECT_LE(tree.build_stats().max_depth, kWideMaxDepth);
  }
}

// The packing rule of LeafPacking::kSharedBlocks on a sequence worked by hand: a leaf of up to four goes
// into the oldest open block with room, a longer one starts in the newest block when it still touches only
// ceil(count / 4) blocks from there, and a block's free lanes are padded by the last leaf put in it.
TEST(WideBvh, SharedBlocksPackLeavesByTheRule) {
  const SceneGeometry g = random_triangle_soup(18, 1);
  std::vector<std::uint32_t> order(18);
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::vector<LeafToGather> leaves;
  std::uint32_t at = 0;
  for (const std::uint32_t count : {3u, 2u, 1u, 5u, 2u, 4u, 1u}) {
    leaves.push_back({at, count, false});
    at += count;
  }
  PrimitiveStore shared, aligned;
  const std::vector<std::uint32_t> shared_at = gather_leaves(g, order, leaves, shared, LeafPacking::kSharedBlocks);
  const std::vector<std::uint32_t> aligned_at = gather_leaves(g, order, leaves, aligned, LeafPacking::kBlockAligned);
  // 3 opens block 0; 2 does not fit there and opens block 1; 1 fills block 0; 5 starts at lane 2 of block
  // 1 (the newest) and ends in block 2; 2 opens block 3; 4 takes block 4 whole; 1 fills block 2.
  EXPECT_EQ(shared_at, (std::vector<std::uint32_t>{0, 4, 3, 6, 12, 16, 11}));
  ASSERT_EQ(shared.triangle_blocks.size(), 5u);
  ASSERT_EQ(shared.triangle_keys.size(), 20u);
  for (std::uint32_t slot = 0; slot < 20; ++slot)
    EXPECT_EQ(shared.triangle_keys[slot].is_padding(), slot == 14 || slot == 15) << slot;
  // Padding repeats the last triangle of the leaf before it (block 3's second lane).
  EXPECT_EQ(shared.triangle_vertex(15, 0), shared.triangle_vertex(13, 0));
  EXPECT_EQ(aligned_at, (std::vector<std::uint32_t>{0, 4, 8, 12, 20, 24, 28}));
  EXPECT_EQ(aligned.triangle_blocks.size(), 8u);
  // The same triangles either way, lane for lane.
  for (std::size_t i = 0; i < leaves.size(); ++i)
    for (std::uint32_t j = 0; j < leaves[i].count; ++j) {
      const std::uint32_t a = aligned_at[i] + j, b = shared_at[i] + j;
      EXPECT_EQ(aligned.triangle_keys[a].prim_id, shared.triangle_keys[b].prim_id);
      EXPECT_EQ(shared.triangle_keys[b].prim_id, leaves[i].first + j);
      for (std::uint32_t v = 0; v < 3; ++v) EXPECT_EQ(aligned.triangle_vertex(a, v), shared.triangle_vertex(b, v));
    }
}

// On a soup, whose leaves are of one to four triangles, shared blocks are nearly full (one leaf per block
// leaves about 40% of the lanes empty; docs/bvh-backend.md, "Memory").
TEST(WideBvh, SharedBlocksAreNearlyFullOnASoup) {
  const SceneGeometry g = random_triangle_soup(20000, 6);
  WideBackend tree;
  tree.build(g);
  const PrimitiveStore& prims = tree.primitives();
  EXPECT_GE(double(g.triangle_count()), 0.9 * double(prims.triangle_keys.size()));
}

TEST(WideBvh, OneTrianglePutsOneLeafUnderTheRoot) {
  SceneGeometry g;
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.indices = {{0, 1, 2}};
  g.meshes.push_back(mesh);
  WideBackend tree;
  tree.build(g);
  ASSERT_EQ(tree.nodes().size(), 1u);
  EXPECT_TRUE(WideRef::is_leaf(tree.nodes()[0].child[0]));
  expect_well_formed(tree, g);
  // The root's visit plus one block test, each weighted by the root's area over itself, plus the memory
  // price of the block's three empty lanes (padding_cost block_cost A(root) / 1 primitive each).
  const WideCollapseOptions costs;
  const double padding = 3.0 * double(costs.padding_cost) * double(costs.block_cost);
  EXPECT_NEAR(tree.build_stats().sah_cost, double(costs.node_cost) + double(costs.block_cost) + padding, 1e-6);
  Ray ray;
  ray.org = {0.25f, 0.25f, 1.0f};
  ray.dir = {0.0f, 0.0f, -1.0f};
  Hit hit;
  EXPECT_TRUE(tree.intersect(ray, hit));
  EXPECT_EQ(hit.t, 1.0f);
}

// The collapse's cost is the optimum over all ways to cut the binary tree into wide nodes, so it is never
// above that of the plain cut that keeps every binary leaf and pulls up children level by level.
TEST(WideBvh, CollapseCostIsNoWorseThanKeepingEveryBinaryLeaf) {
  const SceneGeometry g = random_triangle_soup(5000, 9);
  const std::vector<Bounds3> bounds = primitive_bounds(g);
  const BvhTree binary = build_bvh(bounds, static_cast<std::uint32_t>(bounds.size()), WideBuildOptions::default_binary());
  WideCollapseOptions merge, keep;
  keep.max_leaf_size = 1;  // no merge can then form a leaf (binary leaves are kept whatever their size)
  const WideTree merged = collapse_to_wide(binary, merge);
  const WideTree kept = collapse_to_wide(binary, keep);
  EXPECT_GT(merged.sah_cost, 0.0);
  EXPECT_LE(merged.sah_cost, kept.sah_cost * (1.0 + 1e-6));
  // A far costlier node visit makes the collapse choose fewer, fuller nodes.
  WideCollapseOptions dear_nodes;
  dear_nodes.node_cost = 8.0f;
  EXPECT_LE(collapse_to_wide(binary, dear_nodes).nodes.size(), merged.nodes.size());
}

// The collapse runs in TBB tasks over independent subtrees, each writing only its own places: one thread
// and several must give the same bytes. 30000 triangles: about 20000 binary nodes, so the dynamic program
// splits into tasks (4096 nodes or more) and the top wide nodes measure and emit their children in tasks
// (4096 primitives or more); spheres too, for the leaf kinds.
TEST(WideBvh, CollapseIsTheSameOnAnyNumberOfThreads) {
  for (const SceneGeometry& g : {random_triangle_soup(30000, 3), mixed_spheres_and_triangles(3000, 20000, 4)}) {
    const std::vector<Bounds3> bounds = primitive_bounds(g);
    const BvhTree binary = build_bvh(bounds, static_cast<std::uint32_t>(g.triangle_count()), WideBuildOptions::default_binary());
    ASSERT_GT(binary.nodes.size(), 8192u);
    const auto collapse_on = [&](int threads) {
      return tbb::task_arena(threads).execute([&] { return collapse_to_wide(binary, WideCollapseOptions{}); });
    };
    const WideTree one = collapse_on(1);
    for (const int threads : {2, 4}) {
      const WideTree many = collapse_on(threads);
      ASSERT_EQ(one.nodes.size(), many.nodes.size()) << threads;
      EXPECT_EQ(0, std::memcmp(one.nodes.data(), many.nodes.data(), one.nodes.size() * sizeof(WideNode))) << threads;
      ASSERT_EQ(one.leaves.size(), many.leaves.size()) << threads;
      for (std::size_t i = 0; i < one.leaves.size(); ++i) {
        EXPECT_EQ(one.leaves[i].first_prim, many.leaves[i].first_prim) << i;
        EXPECT_EQ(one.leaves[i].count, many.leaves[i].count) << i;
        EXPECT_EQ(one.leaves[i].spheres, many.leaves[i].spheres) << i;
      }
      EXPECT_EQ(one.max_depth, many.max_depth);
      EXPECT_EQ(one.sah_cost, many.sah_cost);
    }
  }
}

// The whole bvh8 build (binary build, swept small subtrees, collapse, gather) gives the same bytes on one, two
// and four threads: the binary build's chunks and the swept subtrees do not depend on the schedule.
TEST(WideBvh, WholeBuildIsTheSameOnAnyNumberOfThreads) {
  for (const SceneGeometry& g : {random_triangle_soup(40000, 11), mixed_spheres_and_triangles(2000, 30000, 12)}) {
    const auto build_on = [&](int threads) {
      auto backend = std::make_unique<WideBackend>();
      tbb::task_arena(threads).execute([&] { backend->build(g); });
      return backend;
    };
    // memcmp must not see the null data() of an empty vector (the soup has no spheres).
    const auto same_bytes = [](const void* a, const void* b, std::size_t n) { return n == 0 || std::memcmp(a, b, n) == 0; };
    const auto one = build_on(1);
    for (const int threads : {2, 4}) {
      const auto many = build_on(threads);
      ASSERT_EQ(one->nodes().size(), many->nodes().size()) << threads;
      EXPECT_TRUE(same_bytes(one->nodes().data(), many->nodes().data(), one->nodes().size_bytes())) << threads;
      const PrimitiveStore& a = one->primitives();
      const PrimitiveStore& b = many->primitives();
      ASSERT_EQ(a.triangle_keys.size(), b.triangle_keys.size()) << threads;
      EXPECT_TRUE(same_bytes(a.triangle_keys.data(), b.triangle_keys.data(), a.triangle_keys.size() * sizeof(PrimitiveKey)))
          << threads;
      ASSERT_EQ(a.sphere_keys.size(), b.sphere_keys.size()) << threads;
      EXPECT_TRUE(same_bytes(a.sphere_keys.data(), b.sphere_keys.data(), a.sphere_keys.size() * sizeof(PrimitiveKey)))
          << threads;
    }
  }
}

// The layout the emission computes from subtree sizes: the root first, each node's wide children one
// contiguous block in slot order, placed right after everything its earlier siblings' subtrees hold (a
// depth-first walk that appends each node's children as a block), and leaves numbered in node order.
// Also: every binary primitive in exactly one leaf, and the depth is the tree's height.
TEST(WideBvh, CollapseLaysOutChildBlocksDepthFirstAndLeavesInNodeOrder) {
  const SceneGeometry g = random_triangle_soup(30000, 8);
  const std::vector<Bounds3> bounds = primitive_bounds(g);
  const BvhTree binary = build_bvh(bounds, static_cast<std::uint32_t>(bounds.size()), WideBuildOptions::default_binary());
  const WideTree tree = collapse_to_wide(binary, WideCollapseOptions{});
  ASSERT_GT(tree.nodes.size(), 100u);

  std::uint32_t next_node = 1;
  std::size_t deepest = 0;
  const auto walk = [&](const auto& self, std::uint32_t w, std::size_t depth) -> void {
    deepest = std::max(deepest, depth);
    std::vector<std::uint32_t> children;
    for (const std::uint32_t ref : tree.nodes[w].child)
      if (!WideRef::is_leaf(ref) && ref != 0) children.push_back(ref);
    for (std::size_t c = 0; c < children.size(); ++c) ASSERT_EQ(children[c], next_node + c) << "children of node " << w;
    next_node += static_cast<std::uint32_t>(children.size());
    for (const std::uint32_t child : children) self(self, child, depth + 1);
  };
  walk(walk, 0, 1);
  EXPECT_EQ(next_node, tree.nodes.size());
  EXPECT_EQ(deepest, tree.max_depth);

  std::uint32_t next_leaf = 0;
  std::vector<int> covered(bounds.size(), 0);
  for (const WideNode& node : tree.nodes)
    for (const std::uint32_t ref : node.child)
      if (WideRef::is_leaf(ref)) {
        ASSERT_EQ(ref & ~WideRef::kLeafBit, next_leaf) << "leaves in node order";
        const WideLeafRange& leaf = tree.leaves[next_leaf++];
        for (std::uint32_t i = 0; i < leaf.count; ++i) ++covered[leaf.first_prim + i];
      }
  EXPECT_EQ(next_leaf, tree.leaves.size());
  EXPECT_EQ(std::count(covered.begin(), covered.end(), 1), static_cast<std::ptrdiff_t>(covered.size()));
}

// Empty lanes of the leaves' last triangle blocks: the memory the collapse's padding_cost prices.
std::size_t padded_lanes(const WideTree& tree) {
  std::size_t lanes = 0;
  for (const WideLeafRange& leaf : tree.leaves)
    if (!leaf.spheres) lanes += (kTriangleBlockLanes - leaf.count % kTriangleBlockLanes) % kTriangleBlockLanes;
  return lanes;
}

// padding_cost is a Lagrange multiplier on the padded lanes: the dynamic program minimises cost + price x
// lanes exactly, so a higher price can only leave fewer (or as many) empty lanes. From binary leaves of one
// triangle, where every leaf is the collapse's choice, a free padding leaves many.
TEST(WideBvh, PaddingCostFillsTheLeavesBlocks) {
  const SceneGeometry g = random_triangle_soup(5000, 9);
  const std::vector<Bounds3> bounds = primitive_bounds(g);
  BvhBuildOptions singles = WideBuildOptions::default_binary();
  singles.max_leaf_size = 1;
  const BvhTree binary = build_bvh(bounds, static_cast<std::uint32_t>(bounds.size()), singles);
  std::size_t previous = static_cast<std::size_t>(-1);
  for (const float price : {0.0f, 0.25f, 1.0f, 8.0f}) {
    WideCollapseOptions o;
    o.padding_cost = price;
    const std::size_t lanes = padded_lanes(collapse_to_wide(binary, o));
    EXPECT_LE(lanes, previous) << "padding_cost " << price;
    previous = lanes;
  }
  WideCollapseOptions free_padding, dear_padding;
  free_padding.padding_cost = 0.0f;
  dear_padding.padding_cost = 8.0f;
  EXPECT_LT(padded_lanes(collapse_to_wide(binary, dear_padding)), padded_lanes(collapse_to_wide(binary, free_padding)) / 2);
}

TEST(WideBvh, OptionsAreValidated) {
  WideBuildOptions o;
  o.collapse.max_leaf_size = 33;
  EXPECT_THROW(WideBackend{o}, std::invalid_argument);
  o.collapse.max_leaf_size = 17;  // a leaf reference holds counts up to 16 (wide_leaf_ref.h)
  EXPECT_THROW(WideBackend{o}, std::invalid_argument);
  o.collapse.max_leaf_size = 16;
  EXPECT_NO_THROW(WideBackend{o});
  o = {};
  o.collapse.node_cost = 0.0f;
  EXPECT_THROW(WideBackend{o}, std::invalid_argument);
  o = {};
  o.collapse.padding_cost = -1.0f;
  EXPECT_THROW(WideBackend{o}, std::invalid_argument);
  o = {};
  o.binary.max_leaf_size = 40;
  EXPECT_THROW(WideBackend{o}, std::invalid_argument);
  o.binary.max_leaf_size = 17;
  EXPECT_THROW(WideBackend{o}, std::invalid_argument);
}

// A node with the given boxes in its first slots, each a leaf (or, with `inner`, a reference to node 1).
WideNode node_with_boxes(const std::vector<std::pair<glm::vec3, glm::vec3>>& boxes, bool inner = false) {
  WideNode node;
  for (int s = 0; s < kWideWidth; ++s)
    for (int a = 0; a < 3; ++a) node.lo[a][s] = INFINITY, node.hi[a][s] = -INFINITY;
  std::fill(std::begin(node.child), std::end(node.child), 0u);
  for (std::size_t s = 0; s < boxes.size(); ++s) {
    for (int a = 0; a < 3; ++a) node.lo[a][s] = boxes[s].first[a], node.hi[a][s] = boxes[s].second[a];
    node.child[s] = inner ? 1u : WideRef::leaf(static_cast<std::uint32_t>(4 * s), 1, false);
  }
  return node;
}

// The leaves' depth complexity (wide_any_order.h): the leaf boxes' surface areas over the root box's, inner boxes
// not counted, empty slots skipped, and 0 where the ratio means nothing.
TEST(WideBvh, LeafDepthComplexityIsTheLeafBoxesAreaOverTheRoots) {
  const glm::vec3 o(0.0f), one(1.0f);
  // Two unit cubes in a root of two: each leaf is the whole root box.
  std::vector<WideNode> nodes = {node_with_boxes({{o, one}, {o, one}})};
  EXPECT_EQ(wide_leaf_depth_complexity(nodes), 2.0);
  // A root of one inner unit cube over eight flat unit squares (area 2 each, 1/3 of the cube's 6): 8 / 3.
  std::vector<std::pair<glm::vec3, glm::vec3>> squares;
  for (int k = 0; k < 8; ++k) {
    const float z = 0.125f * static_cast<float>(k);
    squares.push_back({glm::vec3(0, 0, z), glm::vec3(1, 1, z)});
  }
  nodes = {node_with_boxes({{o, one}}, /*inner=*/true), node_with_boxes(squares)};
  EXPECT_DOUBLE_EQ(wide_leaf_depth_complexity(nodes), 8.0 / 3.0);
  // Scale-free: the same tree 2^40 times larger (the float sums), and 2^100 times (their products overflow
  // float, and the sum is redone in double).
  for (const float scale : {0x1p40f, 0x1p60f}) {
    for (WideNode& n : nodes)
      for (int a = 0; a < 3; ++a)
        for (int s = 0; s < kWideWidth; ++s) n.lo[a][s] *= scale, n.hi[a][s] *= scale;
    EXPECT_DOUBLE_EQ(wide_leaf_depth_complexity(nodes), 8.0 / 3.0);
  }
  // No tree, and a root box that is a line (zero area), give 0: the stored order.
  EXPECT_EQ(wide_leaf_depth_complexity({}), 0.0);
  nodes = {node_with_boxes({{o, glm::vec3(1, 0, 0)}, {o, glm::vec3(1, 0, 0)}})};
  EXPECT_EQ(wide_leaf_depth_complexity(nodes), 0.0);
  EXPECT_EQ(choose_any_hit_order(nodes).chosen, AnyHitOrder::kStored);
}

// The any-hit order: chosen per tree from its leaf depth complexity unless given. A soup (a volume of small
// triangles, many leaves along any line) takes nearest first; a surface (a tessellated sphere, a grid) keeps the
// stored order. The value is the same on every instruction set (the tree is), so the choice is reproducible.
TEST(WideBvh, AnyHitOrderFollowsTheLeafDepthUnlessGiven) {
  const SceneGeometry soup = random_triangle_soup(20000, 6);
  WideBackend chosen;
  chosen.build(soup);
  const AnyHitOrderChoice& c = chosen.any_hit_order();
  EXPECT_EQ(c.leaf_depth, wide_leaf_depth_complexity(chosen.nodes()));
  EXPECT_GE(c.leaf_depth, kWideNearestMinLeafDepth);
  EXPECT_EQ(c.chosen, AnyHitOrder::kNearest);
  for (const Isa isa : runnable_isas()) {
    WideBackend again({}, isa);
    again.build(soup);
    EXPECT_EQ(again.any_hit_order().leaf_depth, c.leaf_depth) << to_string(isa);
    EXPECT_EQ(again.any_hit_order().chosen, c.chosen) << to_string(isa);
  }
  for (const SceneGeometry& surface : {tessellated_sphere(glm::vec3(0.0f), 1.0f, 5), grid_mesh(100, 100)}) {
    WideBackend tree;
    tree.build(surface);
    EXPECT_LT(tree.any_hit_order().leaf_depth, kWideNearestMinLeafDepth);
    EXPECT_GT(tree.any_hit_order().leaf_depth, 0.0);
    EXPECT_EQ(tree.any_hit_order().chosen, AnyHitOrder::kStored);
  }
  for (const AnyHitOrder order : {AnyHitOrder::kStored, AnyHitOrder::kNearest}) {
    WideBuildOptions o;
    o.any_hit_order = order;
    WideBackend given(o);
    given.build(soup);
    EXPECT_EQ(given.any_hit_order().chosen, order);
    EXPECT_EQ(given.any_hit_order().leaf_depth, 0.0);  // not computed
  }
}

TEST(WideBvh, EmptySceneBuildsAndMisses) {
  WideBackend tree;
  tree.build(SceneGeometry{});
  Ray ray;
  Hit hit;
  EXPECT_FALSE(tree.intersect(ray, hit));
  EXPECT_FALSE(tree.occluded(ray));
}

// Sets TWINRAY_ISA for the scope of one test and restores the previous value.
class ScopedIsaEnv {
 public:
  explicit ScopedIsaEnv(const char* value) {
    if (const char* old = std::getenv("TWINRAY_ISA")) old_ = old;
    if (value) setenv("TWINRAY_ISA", value, 1);
    else unsetenv("TWINRAY_ISA");
  }
  ~ScopedIsaEnv() {
    if (old_) setenv("TWINRAY_ISA", old_->c_str(), 1);
    else unsetenv("TWINRAY_ISA");
  }

 private:
  std::optional<std::string> old_;
};

TEST(CpuIsa, NamesRoundTrip) {
  for (const Isa isa : {Isa::Sse2, Isa::Avx2, Isa::Avx512}) EXPECT_EQ(parse_isa(to_string(isa)), isa);
  EXPECT_FALSE(parse_isa("avx"));
  EXPECT_FALSE(parse_isa("AVX2"));
}

TEST(CpuIsa, EnvironmentLowersTheChoiceAndRejectsWhatTheCpuLacks) {
  {
    const ScopedIsaEnv env(nullptr);
    EXPECT_EQ(selected_isa(), cpu_isa());
  }
  {
    const ScopedIsaEnv env("sse2");
    EXPECT_EQ(selected_isa(), Isa::Sse2);
    EXPECT_EQ(WideBackend{}.isa(), Isa::Sse2);
  }
  {
    const ScopedIsaEnv env("neon");
    EXPECT_THROW(selected_isa(), std::invalid_argument);
    EXPECT_THROW(WideBackend{}, std::invalid_argument);
  }
  if (cpu_isa() < Isa::Avx512) {
    const ScopedIsaEnv env("avx512");
    EXPECT_THROW(selected_isa(), std::invalid_argument);
  }
  const std::vector<Isa> all = runnable_isas();
  ASSERT_FALSE(all.empty());
  EXPECT_EQ(all.front(), Isa::Sse2);
  EXPECT_EQ(all.back(), cpu_isa());
}

}  // namespace
}  // namespace twinray
