#include "backends/bvh/bvh_builder.h"

#include "backends/bvh/primitive_store.h"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace twinray {

void validate(const BvhBuildOptions& o) {
  if (o.bins < 12 || o.bins > 32) throw std::invalid_argument("bvh: bins must be in 12..32, got " + std::to_string(o.bins));
  if (o.max_leaf_size < 1 || o.max_leaf_size > 255)
    throw std::invalid_argument("bvh: max_leaf_size must be in 1..255, got " + std::to_string(o.max_leaf_size));
  if (!(o.traversal_cost > 0.0f) || !(o.intersection_cost > 0.0f) || !std::isfinite(o.traversal_cost) ||
      !std::isfinite(o.intersection_cost))
    throw std::invalid_argument("bvh: traversal_cost and intersection_cost must be positive and finite");
}

namespace {

constexpr int kMaxBins = 32;
// From this depth on only object-median splits are made. Each halves the primitive count, so at most 32
// more levels (2^32 primitives) plus one split by kind follow: the tree stays within kBvhMaxDepth.
constexpr std::size_t kMedianOnlyDepth = kBvhMaxDepth - 1 - 33;
// Subtrees with fewer primitives are built on the calling thread: task overhead would dominate.
constexpr std::size_t kParallelGrain = 4096;

struct PrimRef {
  Bounds3 box;
  glm::vec3 centroid;
  std::uint32_t id;
};

struct Bin {
  Bounds3 box;
  std::uint32_t count = 0;
  std::uint32_t second_kind = 0;  // of `count`, how many are spheres
};

// Primitive tests a leaf of `count` primitives costs, `second_kind` of them spheres: triangles are tested
// four at a time (triangle_block.h), so a leaf of 1..4 triangles costs one test, 5..8 two; spheres one
// each. Counting blocks rather than triangles is what lets the SAH stop at full blocks instead of
// splitting them (Embree's builders count SIMD blocks the same way).
inline float leaf_tests(std::uint32_t count, std::uint32_t second_kind) {
  const std::uint32_t triangles = count - second_kind;
  return static_cast<float>((triangles + kTriangleBlockLanes - 1) / kTriangleBlockLanes + second_kind);
}

struct Split {
  enum class Kind { None, Bin, ObjectMedian, ByKind } kind = Kind::None;
  int axis = 0;
  int bin = 0;            // Bin: primitives in bins [0, bin) go left
  float cost = INFINITY;  // Bin: SAH cost relative to the node's area, in builder units
};

class Builder {
 public:
  Builder(std::span<PrimRef> refs, std::uint32_t second_kind_begin, const BvhBuildOptions& o)
      : refs_(refs), second_kind_begin_(second_kind_begin), o_(o) {}

  // Appends the subtree over refs_[begin, end) to `out` in depth-first order. Child indices are relative to
  // the start of `out`, which build() relies on when splicing subtrees built by other tasks.
  void build(std::size_t begin, std::size_t end, std::size_t depth, std::vector<BvhNode>& out) const {
    Bounds3 box, centroids;
    std::size_t second_kind = 0;
    for (std::size_t i = begin; i < end; ++i) {
      box.extend(refs_[i].box);
      centroids.extend(refs_[i].centroid);
      second_kind += refs_[i].id >= second_kind_begin_ ? 1 : 0;
    }
    const std::size_t n = end - begin;
    const bool mixed = second_kind != 0 && second_kind != n;

    const std::size_t node_index = out.size();
    out.push_back(BvhNode{box.lo, static_cast<std::uint32_t>(begin), box.hi, 0});

    const Split split = choose_split(begin, end, box, centroids, depth, mixed, static_cast<std::uint32_t>(second_kind));
    if (split.kind == Split::Kind::None) {
      out[node_index].count = static_cast<std::uint32_t>(n) | (second_kind == n ? BvhNode::kSphereLeafBit : 0u);
      return;
    }
    const std::size_t mid = partition(begin, end, centroids, split);

    if (o_.parallel && n >= kParallelGrain) {
      std::vector<BvhNode> left, right;
      tbb::parallel_invoke([&] { build(begin, mid, depth + 1, left); },
                           [&] { build(mid, end, depth + 1, right); });
      append_rebased(left, out);
      out[node_index].offset = static_cast<std::uint32_t>(out.size());
      append_rebased(right, out);
    } else {
      build(begin, mid, depth + 1, out);
      out[node_index].offset = static_cast<std::uint32_t>(out.size());
      build(mid, end, depth + 1, out);
    }
  }

 private:
  static void append_rebased(const std::vector<BvhNode>& subtree, std::vector<BvhNode>& out) {
    const auto base = static_cast<std::uint32_t>(out.size());
    for (BvhNode node : subtree) {
      if (!node.is_leaf()) node.offset += base;
      out.push_back(node);
    }
  }

  Split choose_split(std::size_t begin, std::size_t end, const Bounds3& box, const Bounds3& centroids,
                     std::size_t depth, bool mixed, std::uint32_t second_kind) const {
    const std::size_t n = end - begin;
    const bool fits_leaf = n <= static_cast<std::size_t>(o_.max_leaf_size);
    if (n == 1 || (fits_leaf && !mixed && (o_.split_method == BvhSplitMethod::ObjectMedian || depth >= kMedianOnlyDepth)))
      return {};
    if (fits_leaf && mixed) return {Split::Kind::ByKind};

    const bool centroids_coincide = centroids.extent() == glm::vec3(0.0f);
    if (o_.split_method == BvhSplitMethod::ObjectMedian || depth >= kMedianOnlyDepth || centroids_coincide)
      return {Split::Kind::ObjectMedian, centroids.largest_axis()};

    Split best = best_binned_split(begin, end, centroids);
    if (best.kind == Split::Kind::None)  // centroid extent too small to bin on any axis
      return {Split::Kind::ObjectMedian, centroids.largest_axis()};
    // Compare with stopping here: both costs per unit of this node's area.
    const float area = box.half_area();
    const float split_cost = area > 0.0f ? o_.traversal_cost + o_.intersection_cost * best.cost / area : INFINITY;
    const float leaf_cost = o_.intersection_cost * leaf_tests(static_cast<std::uint32_t>(n), second_kind);
    if (fits_leaf && leaf_cost <= split_cost) return {};
    return best;
  }

  // Bin index of a centroid coordinate; clamped because c == hi maps to `bins` (and rounding may overshoot).
  static int bin_of(float c, float lo, float scale, int bins) {
    const int b = static_cast<int>((c - lo) * scale);
    return std::clamp(b, 0, bins - 1);
  }

  // On each axis, bins the centroids and sweeps the bins-1 planes between them. Split::cost is the
  // un-normalized sum area(L) tests(L) + area(R) tests(R), tests counted as in leaf_tests.
  Split best_binned_split(std::size_t begin, std::size_t end, const Bounds3& centroids) const {
    const int bins = o_.bins;
    Split best;
    for (int axis = 0; axis < 3; ++axis) {
      const float extent = centroids.hi[axis] - centroids.lo[axis];
      const float scale = static_cast<float>(bins) / extent;
      if (!(extent > 0.0f) || !std::isfinite(scale)) continue;
      std::array<Bin, kMaxBins> bin{};
      for (std::size_t i = begin; i < end; ++i) {
        Bin& b = bin[static_cast<std::size_t>(bin_of(refs_[i].centroid[axis], centroids.lo[axis], scale, bins))];
        b.box.extend(refs_[i].box);
        ++b.count;
        b.second_kind += refs_[i].id >= second_kind_begin_ ? 1u : 0u;
      }
      // right_cost[k] = area * primitive tests of bins [k, bins)
      std::array<float, kMaxBins> right_cost{};
      Bounds3 acc;
      std::uint32_t count = 0, second = 0;
      for (int k = bins - 1; k > 0; --k) {
        acc.extend(bin[static_cast<std::size_t>(k)].box);
        count += bin[static_cast<std::size_t>(k)].count;
        second += bin[static_cast<std::size_t>(k)].second_kind;
        right_cost[static_cast<std::size_t>(k)] = count > 0 ? acc.half_area() * leaf_tests(count, second) : INFINITY;
      }
      acc = Bounds3{};
      count = 0;
      second = 0;
      for (int k = 1; k < bins; ++k) {
        acc.extend(bin[static_cast<std::size_t>(k - 1)].box);
        count += bin[static_cast<std::size_t>(k - 1)].count;
        second += bin[static_cast<std::size_t>(k - 1)].second_kind;
        if (count == 0) continue;
        const float cost = acc.half_area() * leaf_tests(count, second) + right_cost[static_cast<std::size_t>(k)];
        if (cost < best.cost) best = {Split::Kind::Bin, axis, k, cost};
      }
    }
    return best;
  }

  std::size_t partition(std::size_t begin, std::size_t end, const Bounds3& centroids, const Split& split) const {
    PrimRef* first = refs_.data() + begin;
    PrimRef* last = refs_.data() + end;
    switch (split.kind) {
      case Split::Kind::Bin: {
        const int axis = split.axis;
        const float lo = centroids.lo[axis];
        const float scale = static_cast<float>(o_.bins) / (centroids.hi[axis] - lo);
        const int bins = o_.bins;
        return static_cast<std::size_t>(
            std::partition(first, last, [&](const PrimRef& r) { return bin_of(r.centroid[axis], lo, scale, bins) < split.bin; }) -
            refs_.data());
      }
      case Split::Kind::ByKind:
        return static_cast<std::size_t>(
            std::stable_partition(first, last, [&](const PrimRef& r) { return r.id < second_kind_begin_; }) - refs_.data());
      case Split::Kind::ObjectMedian: {
        // Ties broken by id, so the split (and the whole tree) does not depend on the partition algorithm.
        const int axis = split.axis;
        PrimRef* mid = first + (last - first) / 2;
        std::nth_element(first, mid, last, [axis](const PrimRef& a, const PrimRef& b) {
          return a.centroid[axis] != b.centroid[axis] ? a.centroid[axis] < b.centroid[axis] : a.id < b.id;
        });
        return static_cast<std::size_t>(mid - refs_.data());
      }
      case Split::Kind::None: break;
    }
    return end;
  }

  std::span<PrimRef> refs_;
  std::uint32_t second_kind_begin_;
  const BvhBuildOptions& o_;
};

void measure(const std::vector<BvhNode>& nodes, std::size_t index, std::size_t depth, BvhTree& tree) {
  tree.max_depth = std::max(tree.max_depth, depth);
  const BvhNode& node = nodes[index];
  if (node.is_leaf()) {
    ++tree.leaves;
    return;
  }
  measure(nodes, index + 1, depth + 1, tree);
  measure(nodes, node.second_child(), depth + 1, tree);
}

}  // namespace

BvhTree build_bvh(std::span<const Bounds3> bounds, std::uint32_t second_kind_begin, const BvhBuildOptions& options) {
  validate(options);
  BvhTree tree;
  if (bounds.empty()) return tree;
  std::vector<PrimRef> refs(bounds.size());
  for (std::size_t i = 0; i < bounds.size(); ++i) refs[i] = {bounds[i], bounds[i].center(), static_cast<std::uint32_t>(i)};

  tree.nodes.reserve(2 * bounds.size());
  Builder(refs, second_kind_begin, options).build(0, refs.size(), 0, tree.nodes);
  tree.nodes.shrink_to_fit();

  tree.prim_order.resize(refs.size());
  for (std::size_t i = 0; i < refs.size(); ++i) tree.prim_order[i] = refs[i].id;
  measure(tree.nodes, 0, 0, tree);
  tree.sah_cost = sah_cost(tree.nodes, options);
  return tree;
}

double sah_cost(std::span<const BvhNode> nodes, const BvhBuildOptions& options) {
  if (nodes.empty()) return 0.0;
  const auto area = [](const BvhNode& n) { return static_cast<double>(Bounds3{n.lo, n.hi}.half_area()); };
  const double root_area = area(nodes[0]);
  double cost = 0.0;
  for (const BvhNode& n : nodes) {
    const double weight = root_area > 0.0 ? area(n) / root_area : 1.0;
    const std::uint32_t spheres = n.is_sphere_leaf() ? n.prim_count() : 0u;
    cost += weight * (n.is_leaf() ? options.intersection_cost * static_cast<double>(leaf_tests(n.prim_count(), spheres))
                                  : options.traversal_cost);
  }
  return cost;
}

}  // namespace twinray
