#include "backends/wide/wide_collapse.h"

#include "backends/bvh/bvh_builder_memory.h"
#include "backends/bvh/primitive_store.h"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <immintrin.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace twinray {

void validate(const WideCollapseOptions& o) {
  if (!(o.node_cost > 0.0f) || !(o.block_cost > 0.0f) || !std::isfinite(o.node_cost) || !std::isfinite(o.block_cost))
    throw std::invalid_argument("wide bvh: node_cost and block_cost must be positive and finite");
  if (!(o.padding_cost >= 0.0f) || !std::isfinite(o.padding_cost) || !(o.volume_cost >= 0.0f) || !std::isfinite(o.volume_cost))
    throw std::invalid_argument("wide bvh: padding_cost and volume_cost must be non-negative and finite");
  if (o.max_leaf_size < 1 || o.max_leaf_size > static_cast<int>(WideRef::kMaxLeafCount))
    throw std::invalid_argument("wide bvh: max_leaf_size must be in 1..16, got " + std::to_string(o.max_leaf_size));
}

namespace {

constexpr int kW = kWideWidth;
constexpr float kInf = std::numeric_limits<float>::infinity();
// Binary subtrees of at least this many nodes are evaluated in TBB tasks: a node costs a few hundred
// instructions, so a task holds about a million, far above what scheduling it costs.
constexpr std::size_t kParallelNodes = 4096;
// Wide nodes over at least this many primitives measure and emit their wide children in TBB tasks (a wide
// node costs about a thousand instructions and covers about twenty primitives).
constexpr std::uint32_t kParallelPrims = 4096;

// The wide subtree rooted at a binary node that becomes a wide node: how many wide nodes (itself included)
// and leaves it holds, how many of those leaves are its own slots, and its height in wide nodes. Written by
// measure() for the binary nodes that become wide nodes only.
struct WideSize {
  std::uint32_t nodes, leaves, own_leaves, height;
};

// What the dynamic program decided for one binary node.
// Plan and Subtree have no member initialisers: one of each per binary node is allocated uninitialised
// and evaluate() writes every member (clearing them cost more than the rest of the allocation).
struct Plan {
  // Once the dynamic program is done its costs are read no more (run() takes the tree's cost first), so
  // measure() writes a wide node's size over them: a separate array of sizes per binary node was 16 more
  // bytes of fresh memory per node for the few (one in twenty or thirty) that become wide nodes.
  union {
    std::array<float, kW + 1> cost;   // cost[j], j = 1..kW: as at most j slots (cost[0] = inf, never used)
    WideSize size;                    // after the dynamic program, for a wide node
  };
  std::array<std::uint8_t, kW + 1> k;  // j >= 2: left gets k slots; 0: cost[j] = cost[j - 1]
  // The smallest s with cost[s] == cost[s + 1] == ... == cost[kW] (more slots than s buy nothing), or 0
  // when some cost is NaN (then nothing is known about the order of the costs). See split_of().
  std::uint8_t flat_from;
  bool leaf;                           // as one slot: a leaf (else a wide node)
};

struct Subtree {
  std::uint32_t first, count;  // range of prim_order
  bool triangles, spheres;
  float area;
};

static_assert(std::is_trivially_default_constructible_v<Plan> && std::is_trivially_default_constructible_v<Subtree> &&
                  std::is_trivially_default_constructible_v<WideSize>,
              "new[] must not initialise them");

// Three passes, each parallel over independent subtrees and each writing only its own entries, so the wide
// tree does not depend on the thread count: the dynamic program bottom-up over the binary tree
// (evaluate_subtree), then top-down over the wide nodes it chose, their sizes (measure), then the nodes
// themselves, each written straight to the place the sizes give it (emit). The layout is the one a
// depth-first emission that appends each node's wide children as one block gives (see emit()).
class Collapser {
 public:
  Collapser(const BvhTree& binary, const WideCollapseOptions& o) : bin_(binary), o_(o) {}

  WideTree run() {
    const std::size_t n = bin_.nodes.size();
    WideTree tree;
    if (n == 0) return tree;
    if (!bin_.prim_order.empty()) {
      const float root_area = Bounds3{bin_.nodes[0].lo, bin_.nodes[0].hi}.half_area();
      lane_penalty_ = o_.padding_cost * o_.block_cost * root_area / static_cast<float>(bin_.prim_order.size());
      // In double: a volume of float extents neither overflows nor underflows there. A flat scene has no
      // volume to weigh; an infinite area (coordinates near float's range) leaves the area alone.
      const double root_volume = volume(bin_.nodes[0]);
      if (root_volume > 0.0) volume_weight_ = double(o_.volume_cost) * double(root_area) / root_volume;
      if (!std::isfinite(volume_weight_)) volume_weight_ = 0.0;
    }
    // About 64 bytes per binary node, first touched by evaluate(): on huge pages (bvh_builder_memory.h).
    sub_ = BuildArray<Subtree>(n);
    plan_ = BuildArray<Plan>(n);
    evaluate_subtree(0, static_cast<std::uint32_t>(n));
    // The root's cost, before measure() writes sizes over the costs of the wide nodes' plans. A one-leaf
    // tree has no binary children to split between (split_cost would read past the plan): its root's one
    // slot costs the leaf itself.
    const float root_area = sub_[0].area;
    const float below_root = bin_.nodes[0].is_leaf() ? plan_[0].cost[1] : split_cost(0, kW);
    tree.sah_cost = root_area > 0.0f ? (o_.node_cost * root_area + below_root) / root_area : 0.0;

    out_ = &tree;
    if (bin_.nodes[0].is_leaf()) {
      // A tree of one leaf: a root node with a single child.
      tree.nodes.resize(1);
      tree.leaves.resize(1);
      init_empty(tree.nodes[0]);
      set_box(tree.nodes[0], 0, bin_.nodes[0]);
      tree.nodes[0].child[0] = WideRef::kLeafBit;
      tree.leaves[0] = {sub_[0].first, sub_[0].count, sub_[0].spheres};
    } else {
      const WideSize& root = measure(0);
      // Huge pages for the interior of both (bvh_builder_memory.h), before resize() first touches them.
      resize_on_huge_pages(tree.nodes, root.nodes);
      resize_on_huge_pages(tree.leaves, root.leaves);
      tree.max_depth = root.height;
      emit(0, 0, 1, 0, root.own_leaves);
    }
    return tree;
  }

 private:
  // Evaluates the binary subtree at `i`, which holds the nodes [i, end) (depth-first: a subtree is a
  // contiguous range, its left child's subtree right after it and its right child's after that).
  void evaluate_subtree(std::uint32_t i, std::uint32_t end) {
    if (end - i < kParallelNodes) {
      // Children come after their parent: a reverse sweep sees them first.
      for (std::uint32_t j = end; j-- > i;) evaluate(j);
      return;
    }
    const std::uint32_t right = bin_.nodes[i].second_child();  // an interior node: a leaf is one node
    tbb::parallel_invoke([&] { evaluate_subtree(i + 1, right); }, [&] { evaluate_subtree(right, end); });
    evaluate(i);
  }

  void evaluate(std::uint32_t i) {
    const BvhNode& node = bin_.nodes[i];
    Subtree& s = sub_[i];
    Plan& p = plan_[i];
    // The weight a ray's chance of visiting the box is taken proportional to (wide_collapse.h).
    s.area = Bounds3{node.lo, node.hi}.half_area() + static_cast<float>(volume_weight_ * volume(node));
    if (node.is_leaf()) {
      s.first = node.first_prim();
      s.count = node.prim_count();
      s.spheres = node.is_sphere_leaf();
      s.triangles = !s.spheres;
      p.leaf = true;
      p.cost.fill(leaf_cost(s));
      p.cost[0] = kInf;
      p.k.fill(0);  // distribute() stops at j = 1
      p.flat_from = std::isnan(p.cost[1]) ? 0 : 1;
      return;
    }
    const Subtree& l = sub_[i + 1];
    const Subtree& r = sub_[node.second_child()];
    s.first = l.first;
    s.count = l.count + r.count;
    s.triangles = l.triangles || r.triangles;
    s.spheres = l.spheres || r.spheres;

    std::array<float, kW + 1> split;
    std::array<std::uint8_t, kW + 1> split_k;
    split_of(plan_[i + 1], plan_[node.second_child()], split, split_k);
    const bool may_be_leaf = s.count <= static_cast<std::uint32_t>(o_.max_leaf_size) && !(s.triangles && s.spheres);
    const float as_leaf = may_be_leaf ? leaf_cost(s) : kInf;
    const float as_node = o_.node_cost * s.area + split[kW];
    // may_be_leaf first: with infinite costs on both sides, a node of too many primitives must not become a leaf.
    p.leaf = may_be_leaf && as_leaf <= as_node;
    p.cost[0] = kInf;
    p.k[0] = 0;
    p.cost[1] = std::min(as_leaf, as_node);
    // Only cost[1] can be NaN here: cost[j] for j >= 2 is a copy of cost[j - 1] (k[j] = 0) or a split,
    // which is never NaN and, when cost[j - 1] is not NaN, taken only when strictly below it. So without
    // a NaN the row changes exactly where k[j] != 0.
    int flat = std::isnan(p.cost[1]) ? 0 : 1;
    for (int j = 2; j <= kW; ++j) {
      if (p.cost[j - 1] <= split[j]) {
        p.cost[j] = p.cost[j - 1];
        p.k[j] = 0;
      } else {
        p.cost[j] = split[j];
        p.k[j] = split_k[j];
        if (flat != 0) flat = j;
      }
    }
    p.k[1] = split_k[kW];  // reused: how a wide node at i splits its 8 slots between left and right
    p.flat_from = static_cast<std::uint8_t>(flat);
  }

  // split[j] = min over k in 1..j-1 of l.cost[k] + r.cost[j - k], j = 2..kW, and the first k (smallest)
  // that attains it in split_k[j]. When no sum compares below infinity (coordinates near float's range
  // give infinite or NaN areas), split[j] = inf and k = 1: still a valid split, where k = 0 would send
  // distribute() down the tree without end.
  // Only k <= l.flat_from is tried when neither plan holds a NaN: then both cost rows are non-increasing
  // (cost[j] = min(cost[j - 1], ...)), so for k > s = l.flat_from the sum l.cost[s] + r.cost[j - k] is at
  // least l.cost[s] + r.cost[j - s] (float addition is monotonic), which was tried before and never loses
  // to it under the strict < below. Same minimum, same k, a quarter of the sums where the left child is a
  // leaf (flat from 1), as it is for most nodes near the bottom of the tree.
  // The eight j are eight SSE lanes (two vectors, j = 1..4 and 5..8) and the loop runs over k: for each k
  // the lanes add l.cost[k] to r.cost[j - k], read from a copy of r's row with +inf before it, so that a
  // lane with k >= j (not a split into two non-empty parts) sums to +inf (or NaN) and never wins. A lane
  // keeps its sum where it is strictly below the best so far, as the scalar loop over k does, so the
  // minimum and the first k attaining it are the same, bit for bit (the same float additions and
  // comparisons). Lane j = 1 ends at inf, k = 1 and is never read.
  static void split_of(const Plan& l, const Plan& r, std::array<float, kW + 1>& split,
                       std::array<std::uint8_t, kW + 1>& split_k) {
    static_assert(kW == 8, "two SSE vectors of four lanes");
    const int k_max = l.flat_from != 0 && r.flat_from != 0 ? l.flat_from : kW - 1;
    alignas(16) float padded[2 * kW + 1];  // padded[kW + m] = r.cost[m] (m = 0..kW; cost[0] = inf), inf below
    for (int m = 0; m < kW; ++m) padded[m] = kInf;
    for (int m = 0; m <= kW; ++m) padded[kW + m] = r.cost[static_cast<std::size_t>(m)];
    __m128 best_lo = _mm_set1_ps(kInf), best_hi = best_lo;
    __m128i k_lo = _mm_set1_epi32(1), k_hi = k_lo;
    for (int k = 1; k <= k_max; ++k) {
      const __m128 lk = _mm_set1_ps(l.cost[static_cast<std::size_t>(k)]);
      const __m128 c_lo = _mm_add_ps(lk, _mm_loadu_ps(padded + kW + 1 - k));  // j = 1..4: r.cost[j - k]
      const __m128 c_hi = _mm_add_ps(lk, _mm_loadu_ps(padded + kW + 5 - k));  // j = 5..8
      const __m128i less_lo = _mm_castps_si128(_mm_cmplt_ps(c_lo, best_lo));
      const __m128i less_hi = _mm_castps_si128(_mm_cmplt_ps(c_hi, best_hi));
      best_lo = _mm_min_ps(c_lo, best_lo);  // c < best ? c : best, the scalar update (NaN c keeps best)
      best_hi = _mm_min_ps(c_hi, best_hi);
      const __m128i kv = _mm_set1_epi32(k);
      k_lo = _mm_or_si128(_mm_and_si128(less_lo, kv), _mm_andnot_si128(less_lo, k_lo));
      k_hi = _mm_or_si128(_mm_and_si128(less_hi, kv), _mm_andnot_si128(less_hi, k_hi));
    }
    alignas(16) float cost[kW];
    alignas(16) std::int32_t ks[kW];
    _mm_store_ps(cost, best_lo);
    _mm_store_ps(cost + 4, best_hi);
    _mm_store_si128(reinterpret_cast<__m128i*>(ks), k_lo);
    _mm_store_si128(reinterpret_cast<__m128i*>(ks + 4), k_hi);
    for (int j = 1; j <= kW; ++j) {
      split[static_cast<std::size_t>(j)] = cost[j - 1];
      split_k[static_cast<std::size_t>(j)] = static_cast<std::uint8_t>(ks[j - 1]);
    }
  }

  static double volume(const BvhNode& node) {
    const glm::vec3 e = glm::max(node.hi - node.lo, glm::vec3(0.0f));
    return double(e.x) * double(e.y) * double(e.z);
  }

  float leaf_cost(const Subtree& s) const {
    const std::uint32_t tests = s.spheres ? s.count : (s.count + kTriangleBlockLanes - 1) / kTriangleBlockLanes;
    const float cost = o_.block_cost * s.area * static_cast<float>(tests);
    if (s.spheres) return cost;
    return cost + lane_penalty_ * static_cast<float>(tests * kTriangleBlockLanes - s.count);
  }

  float split_cost(std::uint32_t i, int j) const {
    const std::uint8_t k = plan_[i].k[1];
    return plan_[i + 1].cost[k] + plan_[bin_.nodes[i].second_child()].cost[j - k];
  }

  // At most kW binary nodes, the slots of one wide node (no allocation per node).
  struct Slots {
    std::array<std::uint32_t, kW> node;
    int count = 0;
  };

  // The binary nodes that become the slots of subtree i handed over as at most j slots.
  void distribute(std::uint32_t i, int j, Slots& slots) const {
    while (j > 1 && plan_[i].k[j] == 0) --j;
    if (j == 1) {
      slots.node[static_cast<std::size_t>(slots.count++)] = i;
      return;
    }
    const int k = plan_[i].k[j];
    distribute(i + 1, k, slots);
    distribute(bin_.nodes[i].second_child(), j - k, slots);
  }

  // The binary nodes that become the slots of the wide node at binary node i, in the order distribute()
  // finds them.
  Slots slots_of(std::uint32_t i) const {
    Slots slots;
    const int k = plan_[i].k[1];
    distribute(i + 1, k, slots);
    distribute(bin_.nodes[i].second_child(), kW - k, slots);
    return slots;
  }

  // Larger weight (area plus the volume term) first: the any-hit visiting order (see wide_collapse.h).
  // At most 8 slots: an insertion sort, stable like std::stable_sort and with the same comparison, so the
  // same order whenever the comparison is a strict weak order, i.e. no weight is NaN; with a NaN weight
  // (boxes whose extent overflows float) the two sorts may disagree, and std::stable_sort decides as it
  // always did. std::stable_sort took a temporary buffer from the heap per wide node.
  void sort_by_weight(Slots& slots) const {
    const auto heavier = [&](std::uint32_t a, std::uint32_t b) { return sub_[a].area > sub_[b].area; };
    bool nan = false;
    for (int s = 0; s < slots.count; ++s) nan |= std::isnan(sub_[slots.node[static_cast<std::size_t>(s)]].area);
    if (nan) {
      std::stable_sort(slots.node.begin(), slots.node.begin() + slots.count, heavier);
      return;
    }
    for (int s = 1; s < slots.count; ++s) {
      const std::uint32_t x = slots.node[static_cast<std::size_t>(s)];
      int j = s;
      for (; j > 0 && heavier(x, slots.node[static_cast<std::size_t>(j - 1)]); --j)
        slots.node[static_cast<std::size_t>(j)] = slots.node[static_cast<std::size_t>(j - 1)];
      slots.node[static_cast<std::size_t>(j)] = x;
    }
  }

  // Runs body(c) for c in [0, count): in TBB tasks when the wide node at binary node i covers many
  // primitives, else in order on this thread.
  template <class Body>
  void for_children(std::uint32_t i, int count, const Body& body) const {
    if (sub_[i].count >= kParallelPrims && count > 1)
      tbb::parallel_for(0, count, 1, body);
    else
      for (int c = 0; c < count; ++c) body(c);
  }

  // Sizes the wide subtree rooted at binary node i (a wide node) and those of its wide children. The sizes
  // do not depend on the order of the slots, so they are not sorted here.
  const WideSize& measure(std::uint32_t i) {
    const Slots slots = slots_of(i);
    std::array<std::uint32_t, kW> inner;
    int n_inner = 0;
    WideSize size{1, 0, 0, 1};
    for (int s = 0; s < slots.count; ++s) {
      const std::uint32_t b = slots.node[static_cast<std::size_t>(s)];
      if (plan_[b].leaf) ++size.own_leaves;
      else inner[static_cast<std::size_t>(n_inner++)] = b;
    }
    for_children(i, n_inner, [&](int c) { measure(inner[static_cast<std::size_t>(c)]); });
    size.leaves = size.own_leaves;
    for (int c = 0; c < n_inner; ++c) {
      const WideSize& child = plan_[inner[static_cast<std::size_t>(c)]].size;
      size.nodes += child.nodes;
      size.leaves += child.leaves;
      size.height = std::max(size.height, child.height + 1);
    }
    return plan_[i].size = size;
  }

  static void init_empty(WideNode& node) {
    for (int a = 0; a < 3; ++a)
      for (int s = 0; s < kW; ++s) {
        node.lo[a][s] = kInf;
        node.hi[a][s] = -kInf;
      }
    for (int s = 0; s < kW; ++s) node.child[s] = 0;
  }

  static void set_box(WideNode& node, int s, const BvhNode& box) {
    for (int a = 0; a < 3; ++a) {
      node.lo[a][s] = box.lo[a];
      node.hi[a][s] = box.hi[a];
    }
  }

  // Writes the wide node of binary node i to nodes[w]. The layout is that of a depth-first emission that
  // appends each node's wide children as one block (so siblings are fetched from neighbouring lines) and
  // then emits them in slot order: the subtree of a wide node, less the node itself, is one run of the
  // array (its children's block, then each child's run in turn). Leaves are numbered in node order, node by
  // node and slot by slot: the order the backend stores their primitives in. `children_at` is where i's
  // block of children goes, `own_leaves_at` the number of i's first leaf slot, `below_leaves_at` that of
  // the first leaf of the nodes below i.
  void emit(std::uint32_t i, std::uint32_t w, std::uint32_t children_at, std::uint32_t own_leaves_at,
            std::uint32_t below_leaves_at) {
    Slots slots = slots_of(i);
    sort_by_weight(slots);
    WideNode& node = out_->nodes[w];
    init_empty(node);
    std::array<std::uint32_t, kW> inner;
    int n_inner = 0;
    std::uint32_t leaf = own_leaves_at;
    for (int s = 0; s < slots.count; ++s) {
      const std::uint32_t b = slots.node[static_cast<std::size_t>(s)];
      set_box(node, s, bin_.nodes[b]);
      if (plan_[b].leaf) {
        node.child[s] = WideRef::kLeafBit | leaf;
        out_->leaves[leaf++] = {sub_[b].first, sub_[b].count, sub_[b].spheres};
      } else {
        node.child[s] = children_at + static_cast<std::uint32_t>(n_inner);
        inner[static_cast<std::size_t>(n_inner++)] = b;
      }
    }
    // Where each child's own children, own leaves and the leaves below it go.
    std::array<std::uint32_t, kW> grandchildren_at, child_leaves_at, child_below_at;
    std::uint32_t next_node = children_at + static_cast<std::uint32_t>(n_inner);
    std::uint32_t next_own = below_leaves_at, next_below = below_leaves_at;
    for (int c = 0; c < n_inner; ++c) next_below += plan_[inner[static_cast<std::size_t>(c)]].size.own_leaves;
    for (int c = 0; c < n_inner; ++c) {
      const auto u = static_cast<std::size_t>(c);
      const WideSize& child = plan_[inner[u]].size;
      grandchildren_at[u] = next_node;
      child_leaves_at[u] = next_own;
      child_below_at[u] = next_below;
      next_node += child.nodes - 1;
      next_own += child.own_leaves;
      next_below += child.leaves - child.own_leaves;
    }
    for_children(i, n_inner, [&](int c) {
      const auto u = static_cast<std::size_t>(c);
      emit(inner[u], children_at + static_cast<std::uint32_t>(c), grandchildren_at[u], child_leaves_at[u], child_below_at[u]);
    });
  }

  const BvhTree& bin_;
  const WideCollapseOptions& o_;
  BuildArray<Subtree> sub_;  // per binary node, all written by evaluate()
  BuildArray<Plan> plan_;
  WideTree* out_ = nullptr;
  float lane_penalty_ = 0.0f;    // cost of one empty lane of a leaf's last block (padding_cost in area units)
  double volume_weight_ = 0.0;   // volume_cost A(root) / V(root): area units per unit of volume
};

}  // namespace

WideTree collapse_to_wide(const BvhTree& binary, const WideCollapseOptions& options) {
  validate(options);
  return Collapser(binary, options).run();
}

}  // namespace twinray
