// Closest-hit and any-hit traversal of the flat BVH.
//
// Ordered depth-first traversal: at an interior node both children's boxes are tested, the nearer child is
// visited first and the farther one pushed with its entry distance; popped entries that start beyond the
// current closest hit are skipped without touching their node. The interval [tmin, best t] shrinks as hits
// are found and stays closed, so an equidistant hit in another subtree still reaches `precedes` and the
// winner does not depend on the visiting order: the result is bit-identical to the brute-force loop.
//
// The traversal is a template on the primitive kinds present, so a triangle-only scene runs a loop that
// contains no sphere code at all (and vice versa); a mixed scene branches once per leaf.
//
// No include guard: bvh_kernels_<isa>.cpp includes this file once, inside its own namespace, after the
// headers it needs, with TWINRAY_KERNEL (the target attribute, or nothing), TWINRAY_BOX_PAIR (the
// child-pair box test of ray_box.h) and TWINRAY_BOX_PAIR_RAY (the ray type that test reads) defined. See
// bvh_kernels.h.

// Told about every node a query enters, in order, with the end of the interval still searched (the closest
// hit's t so far). `twinray trace` passes one to print the visit order; the default does nothing and
// compiles away, so the production traversal carries no trace of it.
struct NoVisitObserver {
  void enter(std::uint32_t /*node*/, float /*tmax*/) const {}
};

namespace bvh_detail {

struct StackEntry {
  std::uint32_t node;
  float entry;  // where the ray enters the node's box
};

// The lanes of a triangle block that hold the leaf's triangles, given how many remain from the block's start.
TWINRAY_KERNEL inline unsigned lane_mask(std::uint32_t remaining) {
  return remaining >= kTriangleBlockLanes ? (1u << kTriangleBlockLanes) - 1 : (1u << remaining) - 1;
}


// Pops the next node worth visiting (entry <= tmax). False when the stack is exhausted.
TWINRAY_KERNEL inline bool pop_next(const StackEntry* stack, std::size_t& size, float tmax, std::uint32_t& node) {
  while (size > 0) {
    const StackEntry& e = stack[--size];
    if (e.entry <= tmax) {
      node = e.node;
      return true;
    }
  }
  return false;
}

// Tests both children; continues with the nearer hit child and pushes the other. False when neither is hit.
TWINRAY_KERNEL inline bool descend(std::span<const BvhNode> nodes, std::uint32_t index,
                                   const TWINRAY_BOX_PAIR_RAY& pair_ray, StackEntry* stack, std::size_t& size,
                                   std::uint32_t& next) {
  const std::uint32_t left = index + 1;
  const std::uint32_t right = nodes[index].second_child();
  float entry_left = 0.0f, entry_right = 0.0f;
  const unsigned hits = TWINRAY_BOX_PAIR(nodes[left], nodes[right], pair_ray, entry_left, entry_right);
  const bool hit_left = (hits & TWINRAY_BOX_PAIR_RAY::kFirstHit) != 0;
  const bool hit_right = (hits & TWINRAY_BOX_PAIR_RAY::kSecondHit) != 0;
  if (hit_left && hit_right) {
    const bool left_first = entry_left <= entry_right;
    stack[size++] = left_first ? StackEntry{right, entry_right} : StackEntry{left, entry_left};
    next = left_first ? left : right;
  } else if (hit_left || hit_right) {
    next = hit_left ? left : right;
  } else {
    return false;
  }
  return true;
}

}  // namespace bvh_detail

// Closest hit; fills `hit` completely (t, u, v, ids, normal) or leaves it a miss. The ray must be valid.
// Always inlined into its one caller per instantiation (the kernel below, or a traced query), so that the
// kernels compile to the code they had before observers existed.
template <bool kTriangles, bool kSpheres, typename Observer, bool kCount = true>
TWINRAY_KERNEL __attribute__((always_inline)) inline bool bvh_intersect_observed(const BvhView& bvh, const Ray& ray,
                                                                                Hit& hit, QueryStats* stats,
                                                                                const Observer& observer) {
  using namespace bvh_detail;
  hit = Hit{};
  if (bvh.nodes.empty()) return false;
  // The best hit so far in a local (t and ids), copied to `hit` at the end: `hit` is the caller's memory, and
  // each candidate's tie test would otherwise read the t the previous one stored there (a store-to-load
  // forwarding on the chain to tmax).
  Hit best;
  const BoxRay box_ray(ray);
  [[maybe_unused]] const TriangleRay tri_ray = make_triangle_ray(ray.org, ray.dir);
  const PrimitiveStore& prims = *bvh.prims;

  StackEntry stack[kBvhMaxDepth];
  std::size_t size = 0;
  std::uint64_t nodes_visited = 1, prims_tested = 0;
  float tmax = ray.tmax;          // shrinks to the best hit's t
  bool best_is_sphere = false;
  std::uint32_t best_index = 0;   // into the store's array of the best hit's kind
  // The best triangle's crossing as its t test computed it, for its u, v at the end (triangle_block.h).
  [[maybe_unused]] refine_detail::Crossing best_crossing;
  [[maybe_unused]] bool best_crossing_kept = false;

  float root_entry = 0.0f;
  std::uint32_t index = 0;
  // Boxes are tested against the ray's own [tmin, tmax], unwidened: ray_box.h's near and far distances are
  // bounds of the exact ones, which is what a closed interval of correctly rounded t needs (its comment).
  // The root's box is tested only when an observer is told which nodes the query enters. Otherwise the
  // traversal starts inside the root: its children's boxes are tested anyway (a leaf root's primitives are
  // tested directly), so skipping it changes no answer, and saves a box test on every ray that hits the scene.
  bool more = std::is_same_v<Observer, NoVisitObserver> ||
              intersect_box(bvh.nodes[0], box_ray, ray.tmin, tmax, root_entry);
  TWINRAY_BOX_PAIR_RAY pair_ray(box_ray, ray.tmin, tmax);  // follows tmax
  while (more) {
    observer.enter(index, tmax);
    const BvhNode& node = bvh.nodes[index];
    if (!node.is_leaf()) {
      nodes_visited += 2;
      more = descend(bvh.nodes, index, pair_ray, stack, size, index) || pop_next(stack, size, tmax, index);
      continue;
    }
    const std::uint32_t first = node.first_prim(), count = node.prim_count();
    prims_tested += count;
    if (kTriangles && (!kSpheres || !node.is_sphere_leaf())) {
      for (std::uint32_t slot = first; slot < first + count; slot += kTriangleBlockLanes) {
        // t only: the winner's u, v are computed once, at the end, from its kept crossing.
        bvh_leaf::block_closest(
            tri_ray, prims.block_of(slot), lane_mask(first + count - slot), ray.tmin, tmax,
            [&](unsigned lane, float t, const refine_detail::Crossing* crossing) {
              const PrimitiveKey key = prims.triangle_keys[slot + lane];
              if (!precedes(t, key.geom_id, key.prim_id, best)) return tmax;
              best.t = tmax = t;
              best.geom_id = key.geom_id;
              best.prim_id = key.prim_id;
              best_is_sphere = false;
              best_index = slot + lane;
              best_crossing_kept = crossing != nullptr;
              if (crossing != nullptr) best_crossing = *crossing;
              return tmax;
            });
      }
    } else if constexpr (kSpheres) {
      for (std::uint32_t i = first; i < first + count; ++i) {
        const StoredSphere& s = prims.spheres[i];
        float t;
        if (!intersect_sphere(ray.org, ray.dir, s.center, s.radius, ray.tmin, tmax, t)) continue;
        const PrimitiveKey key = prims.sphere_keys[i];
        if (!precedes(t, key.geom_id, key.prim_id, best)) continue;
        best.t = tmax = t;
        best.geom_id = key.geom_id;
        best.prim_id = key.prim_id;
        best_is_sphere = true;
        best_index = i;
      }
    }
    // Here rather than in the hit callback above: a lambda does not inherit the kernel's target attribute, so
    // the AVX broadcast could not be inlined there. One broadcast per leaf.
    pair_ray.set_tmax(tmax);
    more = pop_next(stack, size, tmax, index);
  }

  if (kCount && stats) {
    stats->nodes_visited += nodes_visited;
    stats->primitives_tested += prims_tested;
  }
  if (!best.found()) return false;
  hit.t = best.t;
  hit.geom_id = best.geom_id;
  hit.prim_id = best.prim_id;
  if (kSpheres && best_is_sphere) {
    const StoredSphere& s = prims.spheres[best_index];
    sphere_hit_attributes(ray.org, ray.dir, hit.t, s.center, s.radius, hit.ng, hit.u, hit.v);
  } else if constexpr (kTriangles) {
    triangle_block_hit_attributes(tri_ray, prims.block_of(best_index), best_index % kTriangleBlockLanes, hit.t, hit.u,
                                  hit.v, hit.ng, best_crossing_kept ? &best_crossing : nullptr);
  }
  return true;
}

// Any hit: returns at the first primitive hit in [tmin, tmax]. The ray must be valid.
template <bool kTriangles, bool kSpheres, typename Observer, bool kCount = true>
TWINRAY_KERNEL __attribute__((always_inline)) inline bool bvh_occluded_observed(const BvhView& bvh, const Ray& ray,
                                                                               QueryStats* stats,
                                                                               const Observer& observer) {
  using namespace bvh_detail;
  if (bvh.nodes.empty()) return false;
  const BoxRay box_ray(ray);
  [[maybe_unused]] const TriangleRay tri_ray = make_triangle_ray(ray.org, ray.dir);
  const PrimitiveStore& prims = *bvh.prims;

  StackEntry stack[kBvhMaxDepth];
  std::size_t size = 0;
  std::uint64_t nodes_visited = 1, prims_tested = 0;
  bool found = false;

  float root_entry = 0.0f;
  std::uint32_t index = 0;
  // As in the closest-hit query: the ray's own interval, and the root's box only when an observer is told.
  bool more = std::is_same_v<Observer, NoVisitObserver> ||
              intersect_box(bvh.nodes[0], box_ray, ray.tmin, ray.tmax, root_entry);
  const TWINRAY_BOX_PAIR_RAY pair_ray(box_ray, ray.tmin, ray.tmax);
  while (more && !found) {
    observer.enter(index, ray.tmax);
    const BvhNode& node = bvh.nodes[index];
    if (!node.is_leaf()) {
      nodes_visited += 2;
      more = descend(bvh.nodes, index, pair_ray, stack, size, index) || pop_next(stack, size, ray.tmax, index);
      continue;
    }
    const std::uint32_t first = node.first_prim(), count = node.prim_count();
    if (kTriangles && (!kSpheres || !node.is_sphere_leaf())) {
      for (std::uint32_t slot = first; slot < first + count && !found; slot += kTriangleBlockLanes) {
        const std::uint32_t in_block = std::min(first + count - slot, kTriangleBlockLanes);
        prims_tested += in_block;
        // Membership decided before the quotient where it can be (triangle_refine.h, certainly_inside).
        found = bvh_leaf::block_any(tri_ray, prims.block_of(slot), lane_mask(in_block), ray.tmin, ray.tmax);
      }
    } else if constexpr (kSpheres) {
      for (std::uint32_t i = first; i < first + count && !found; ++i) {
        ++prims_tested;
        const StoredSphere& s = prims.spheres[i];
        float t;
        found = intersect_sphere(ray.org, ray.dir, s.center, s.radius, ray.tmin, ray.tmax, t);
      }
    }
    more = pop_next(stack, size, ray.tmax, index);
  }

  if (kCount && stats) {
    stats->nodes_visited += nodes_visited;
    stats->primitives_tested += prims_tested;
  }
  return found;
}

// The kernels (BvhKernels): the traversals above without an observer, and without the node and primitive
// counters when no QueryStats is given (every query but the statistics passes): the two counters are
// general-purpose registers that the traversal loop otherwise keeps in memory, beside the stack's size.
template <bool kTriangles, bool kSpheres>
TWINRAY_KERNEL bool bvh_intersect(const BvhView& bvh, const Ray& ray, Hit& hit, QueryStats* stats) {
  if (stats == nullptr)
    return bvh_intersect_observed<kTriangles, kSpheres, NoVisitObserver, false>(bvh, ray, hit, nullptr,
                                                                                NoVisitObserver{});
  return bvh_intersect_observed<kTriangles, kSpheres>(bvh, ray, hit, stats, NoVisitObserver{});
}

template <bool kTriangles, bool kSpheres>
TWINRAY_KERNEL bool bvh_occluded(const BvhView& bvh, const Ray& ray, QueryStats* stats) {
  if (stats == nullptr)
    return bvh_occluded_observed<kTriangles, kSpheres, NoVisitObserver, false>(bvh, ray, nullptr, NoVisitObserver{});
  return bvh_occluded_observed<kTriangles, kSpheres>(bvh, ray, stats, NoVisitObserver{});
}

// This unit's entry in bvh_kernels.h: the kernels for the primitive kinds a scene has.
BvhKernels kernels(bool triangles, bool spheres) {
  if (triangles && spheres) return {&bvh_intersect<true, true>, &bvh_occluded<true, true>};
  if (spheres) return {&bvh_intersect<false, true>, &bvh_occluded<false, true>};
  return {&bvh_intersect<true, false>, &bvh_occluded<true, false>};
}
