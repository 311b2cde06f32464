#include "backends/wide/wide_collapse.h"

#include "backends/bvh/primitive_store.h"

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
    throw std::invalid_argument("wide bvh: max_leaf_size must be in 1..32, got " + std::to_string(o.max_leaf_size));
}

namespace {

constexpr int kW = kWideWidth;
constexpr float kInf = std::numeric_limits<float>::infinity();

// What the dynamic program decided for one binary node.
// Plan and Subtree have no member initialisers: one of each per binary node is allocated uninitialised
// and evaluate() writes every member (clearing them cost more than the rest of the allocation).
struct Plan {
  std::array<float, kW + 1> cost;     // cost[j], j = 1..kW: as at most j slots (cost[0] = inf, never used)
  std::array<std::uint8_t, kW + 1> k;  // j >= 2: left gets k slots; 0: cost[j] = cost[j - 1]
  bool leaf;                           // as one slot: a leaf (else a wide node)
};

struct Subtree {
  std::uint32_t first, count;  // range of prim_order
  bool triangles, spheres;
  float area;
};
static_assert(std::is_trivially_default_constructible_v<Plan> && std::is_trivially_default_constructible_v<Subtree>,
              "new[] must not initialise them");

class Collapser {
 public:
  Collapser(const BvhTree& binary, const WideCollapseOptions& o) : bin_(binary), o_(o) {}

  WideTree run() {
    const std::size_t n = bin_.nodes.size();
    if (n != 0 && !bin_.prim_order.empty()) {
      const float root_area = Bounds3{bin_.nodes[0].lo, bin_.nodes[0].hi}.half_area();
      lane_penalty_ = o_.padding_cost * o_.block_cost * root_area / static_cast<float>(bin_.prim_order.size());
      // In double: a volume of float extents neither overflows nor underflows there. A flat scene has no
      // volume to weigh; an infinite area (coordinates near float's range) leaves the area alone.
      const double root_volume = volume(bin_.nodes[0]);
      if (root_volume > 0.0) volume_weight_ = double(o_.volume_cost) * double(root_area) / root_volume;
      if (!std::isfinite(volume_weight_)) volume_weight_ = 0.0;
    }
    sub_.reset(new Subtree[n]);
    plan_.reset(new Plan[n]);
    // Children come after their parent in the depth-first array: a reverse sweep sees them first.
    for (std::size_t i = n; i-- > 0;) evaluate(static_cast<std::uint32_t>(i));

    WideTree tree;
    if (n == 0) return tree;
    out_ = &tree;
    tree.nodes.emplace_back();
    if (bin_.nodes[0].is_leaf()) {
      // A tree of one leaf: a root node with a single child.
      init_empty(tree.nodes[0]);
      set_slot(0, 0, 0, 1);
    } else {
      emit(0, 0, 1);
    }
    const float root_area = sub_[0].area;
    // A one-leaf tree has no binary children to split between (split_cost would read past the plan): its
    // root's one slot costs the leaf itself.
    const float below_root = bin_.nodes[0].is_leaf() ? plan_[0].cost[1] : split_cost(0, kW);
    tree.sah_cost = root_area > 0.0f ? (o_.node_cost * root_area + below_root) / root_area : 0.0;
    return tree;
  }

 private:
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
      return;
    }
    const Subtree& l = sub_[i + 1];
    const Subtree& r = sub_[node.second_child()];
    s.first = l.first;
    s.count = l.count + r.count;
    s.triangles = l.triangles || r.triangles;
    s.spheres = l.spheres || r.spheres;

    std::array<float, kW + 1> split{};
    std::array<std::uint8_t, kW + 1> split_k{};
    const Plan& pl = plan_[i + 1];
    const Plan& pr = plan_[node.second_child()];
    for (int j = 2; j <= kW; ++j) {
      split[j] = kInf;
      // A valid split even when no cost compares below infinity: coordinates near float's range give
      // infinite or NaN areas, and k = 0 would send distribute() down the tree without end.
      split_k[j] = 1;
      for (int k = 1; k < j; ++k) {
        const float c = pl.cost[k] + pr.cost[j - k];
        if (c < split[j]) {
          split[j] = c;
          split_k[j] = static_cast<std::uint8_t>(k);
        }
      }
    }
    const bool may_be_leaf = s.count <= static_cast<std::uint32_t>(o_.max_leaf_size) && !(s.triangles && s.spheres);
    const float as_leaf = may_be_leaf ? leaf_cost(s) : kInf;
    const float as_node = o_.node_cost * s.area + split[kW];
    // may_be_leaf first: with infinite costs on both sides, a node of too many primitives must not become a leaf.
    p.leaf = may_be_leaf && as_leaf <= as_node;
    p.cost[0] = kInf;
    p.k[0] = 0;
    p.cost[1] = std::min(as_leaf, as_node);
    for (int j = 2; j <= kW; ++j) {
      if (p.cost[j - 1] <= split[j]) {
        p.cost[j] = p.cost[j - 1];
        p.k[j] = 0;
      } else {
        p.cost[j] = split[j];
        p.k[j] = split_k[j];
      }
    }
    p.k[1] = split_k[kW];  // reused: how a wide node at i splits its 8 slots between left and right
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

  static void init_empty(WideNode& node) {
    for (int a = 0; a < 3; ++a)
      for (int s = 0; s < kW; ++s) {
        node.lo[a][s] = kInf;
        node.hi[a][s] = -kInf;
      }
    for (int s = 0; s < kW; ++s) node.child[s] = 0;
  }

  // Writes binary node b into slot s of wide node w: a leaf, or (returns true) a wide node to emit.
  bool set_slot(std::uint32_t w, int s, std::uint32_t b, std::size_t /*depth*/) {
    WideNode& node = out_->nodes[w];
    const BvhNode& bn = bin_.nodes[b];
    for (int a = 0; a < 3; ++a) {
      node.lo[a][s] = bn.lo[a];
      node.hi[a][s] = bn.hi[a];
    }
    if (plan_[b].leaf) {
      const Subtree& sub = sub_[b];
      node.child[s] = WideRef::kLeafBit | static_cast<std::uint32_t>(out_->leaves.size());
      out_->leaves.push_back({sub.first, sub.count, sub.spheres});
      return false;
    }
    return true;
  }

  // Fills wide node w with the slots of binary node i, then its wide children, each group of siblings
  // contiguous in the array (one node's children are fetched from neighbouring lines).
  void emit(std::uint32_t i, std::uint32_t w, std::size_t depth) {
    out_->max_depth = std::max(out_->max_depth, depth);
    Slots slots;
    const int k = plan_[i].k[1];
    distribute(i + 1, k, slots);
    distribute(bin_.nodes[i].second_child(), kW - k, slots);
    // Larger weight (area plus the volume term) first: the any-hit visiting order (see wide_collapse.h).
    std::stable_sort(slots.node.begin(), slots.node.begin() + slots.count,
                     [&](std::uint32_t a, std::uint32_t b) { return sub_[a].area > sub_[b].area; });

    init_empty(out_->nodes[w]);
    std::array<std::uint32_t, kW> inner{};
    std::array<int, kW> inner_slot{};
    int n_inner = 0;
    for (int s = 0; s < slots.count; ++s)
      if (set_slot(w, s, slots.node[static_cast<std::size_t>(s)], depth)) {
        inner[static_cast<std::size_t>(n_inner)] = slots.node[static_cast<std::size_t>(s)];
        inner_slot[static_cast<std::size_t>(n_inner++)] = s;
      }
    const auto base = static_cast<std::uint32_t>(out_->nodes.size());
    out_->nodes.resize(out_->nodes.size() + static_cast<std::size_t>(n_inner));
    for (int c = 0; c < n_inner; ++c)
      out_->nodes[w].child[inner_slot[static_cast<std::size_t>(c)]] = base + static_cast<std::uint32_t>(c);
    for (int c = 0; c < n_inner; ++c) emit(inner[static_cast<std::size_t>(c)], base + static_cast<std::uint32_t>(c), depth + 1);
  }

  const BvhTree& bin_;
  const WideCollapseOptions& o_;
  std::unique_ptr<Subtree[]> sub_;  // per binary node, all written by evaluate()
  std::unique_ptr<Plan[]> plan_;
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
