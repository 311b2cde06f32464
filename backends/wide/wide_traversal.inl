// Closest-hit and any-hit traversal of the 8-wide BVH (wide_node.h).
//
// Closest hit: at a node, the eight child boxes are tested at once; the hit children are visited nearest
// entry first, the others pushed farthest first with their entry distances, and popped entries that start
// beyond the best hit so far are dropped without touching their node. As in the binary bvh, the interval
// [tmin, best t] stays closed and ties go through `precedes`, so the answer is bit-identical to the brute
// force loop whatever the visiting order.
//
// Any hit: the first hit ends the query, so the order is chosen to find one early and cheaply. The hit
// leaf children of a node are tested right away (a leaf test can end the query; a node can only lead to
// one), then the inner children are visited in stored order, larger area first (SATO, see
// wide_collapse.h), with no sorting at all; or, on trees of high depth complexity (soups, the hairball:
// wide_any_order.h), the nearest hit inner child first on segments (finite tmax) and the others in stored order.
//
// Leaves are tested by the same watertight block test as the binary bvh (triangle_block.h), and boxes by the
// same bounds of the near and far distances (ray_box.h's scales) against the ray's own interval, so coplanar
// ties and hits at the ends of the interval are decided exactly as by brute force.
//
// No include guard: wide_kernels_<isa>.cpp includes this file once, inside its own namespace, after the
// headers it needs and after defining TWINRAY_KERNEL (the target attribute), WideBoxRay, test_boxes(),
// leaf_children() and push_children() for its instruction set; it defines the namespace's kernels()
// (wide_kernels.h), or, compiled again by wide_kernels_<isa>_nearest.cpp with TWINRAY_WIDE_NEAREST_UNIT defined,
// only nearest_occluded() (why in their own unit: wide_kernels_avx2_nearest.cpp).

namespace wide_detail {

// push_children may store a full row of eight children from the stack's top: room for the lanes past the
// ones it pushes.
inline constexpr std::size_t kWideStackSlack = kWideWidth;

struct StackEntry {
  std::uint32_t ref;
  float entry;  // where the ray enters the child's box
};

// Boxes a node visit tests: its filled slots (empty ones have lo > hi). Only for statistics.
TWINRAY_KERNEL inline std::uint64_t filled_slots(const WideNode& node) {
  std::uint64_t n = 0;
  for (int s = 0; s < kWideWidth; ++s) n += node.lo[0][s] <= node.hi[0][s] ? 1u : 0u;
  return n;
}

// The node with reference `ref`, its byte offset (wide_node.h): one addition from a popped reference to the node's
// address, where an index took a multiplication by 224 as well (three cycles more on the path from one node to
// the next, and one instruction).
TWINRAY_KERNEL inline const WideNode& node_at(const WideNode* nodes, std::uint32_t ref) {
  return *reinterpret_cast<const WideNode*>(reinterpret_cast<const char*>(nodes) + ref);
}

// Pops the next entry worth visiting (entry <= tmax). False when the stack is exhausted.
TWINRAY_KERNEL inline bool pop_next(const StackEntry* stack, std::size_t& size, float tmax, std::uint32_t& ref) {
  while (size > 0) {
    const StackEntry& e = stack[--size];
    if (e.entry <= tmax) {
      ref = e.ref;
      return true;
    }
  }
  return false;
}

// Two or more hit children: returns the nearest and pushes the others, farthest first.
TWINRAY_KERNEL inline std::uint32_t order_children(const WideNode& node, unsigned mask, const float* entry,
                                                   StackEntry* stack, std::size_t& size) {
  const unsigned a = static_cast<unsigned>(__builtin_ctz(mask));
  mask &= mask - 1;
  const unsigned b = static_cast<unsigned>(__builtin_ctz(mask));
  mask &= mask - 1;
  if (mask == 0) {  // the common case: exactly two
    const bool a_first = entry[a] <= entry[b];
    const unsigned near = a_first ? a : b, far = a_first ? b : a;
    stack[size++] = StackEntry{node.child[far], entry[far]};
    return node.child[near];
  }
  // Three or more: the nearest is visited now and the second nearest pushed last, so that it is the next
  // popped; the others go below it in slot order. A full sort costs more than it saves (docs/bvh-backend.md).
  mask |= (1u << a) | (1u << b);
  unsigned near = a, second = b;
  if (entry[b] < entry[a]) near = b, second = a;
  for (unsigned m = mask & ~((1u << a) | (1u << b)); m != 0; m &= m - 1) {
    const unsigned s = static_cast<unsigned>(__builtin_ctz(m));
    if (entry[s] < entry[near]) second = near, near = s;
    else if (entry[s] < entry[second]) second = s;
  }
  for (unsigned m = mask & ~((1u << near) | (1u << second)); m != 0; m &= m - 1) {
    const unsigned s = static_cast<unsigned>(__builtin_ctz(m));
    stack[size++] = StackEntry{node.child[s], entry[s]};
  }
  stack[size++] = StackEntry{node.child[second], entry[second]};
  return node.child[near];
}

}  // namespace wide_detail

namespace wide_detail {

// The triangle test's ray: the sheared frame, and the ray in double by this instruction set's set_refine_ray.
TWINRAY_KERNEL inline TriangleRay make_wide_triangle_ray(const Ray& ray) {
  TriangleRay r = make_triangle_ray_frame(ray.org, ray.dir);
  set_refine_ray(r.refine, ray);
  return r;
}

// Tells the compiler that the ray's broadcast vectors may have changed in memory, so it reads them from
// there at their next uses instead of keeping copies in registers.
TWINRAY_KERNEL inline void reread_vectors(WideBoxRay& r) {
  r.reread();
}

// Closest hit; kStats: whether to count boxes and primitives into `stats` (non-null then). The timed queries
// run the copy without counting, so the bookkeeping costs them nothing. kAttributes: whether the winner's u, v
// and ng are computed (Backend::intersect) or left as a miss has them (Backend::intersect_ids); the traversal,
// and so t and the ids, is the same either way.
template <bool kTriangles, bool kSpheres, bool kStats, bool kAttributes>
[[gnu::always_inline]] TWINRAY_KERNEL inline bool intersect_impl(const WideView& bvh, const Ray& ray, Hit& hit,
                                                                 QueryStats* stats) {
  hit = Hit{};
  WideBoxRay box_ray(ray);
  [[maybe_unused]] const TriangleRay tri_ray = make_wide_triangle_ray(ray);
  const PrimitiveStore& prims = *bvh.prims;

  StackEntry stack[kWideStackSize];
  std::size_t size = 0;
  std::uint64_t boxes_tested = 0, prims_tested = 0;
  float tmax = ray.tmax;  // shrinks to the best hit's t
  bool best_is_sphere = false;
  std::uint32_t best_index = 0;  // into the store's array of the best hit's kind
  // The best triangle's crossing as its t test computed it, for its u, v at the end (triangle_block.h).
  [[maybe_unused]] refine_detail::Crossing best_crossing;
  [[maybe_unused]] bool best_crossing_kept = false;
  alignas(32) float entry[kWideWidth];

  // Boxes and primitives are tested against the ray's own interval: the slab distances are bounds of the
  // exact ones (ray_box.h), so a box holding a hit whose rounded t is tmin or tmax is not culled.
  std::uint32_t ref = 0;  // the root node
  for (;;) {
    if (!WideRef::is_leaf(ref)) {
      const WideNode& node = node_at(bvh.nodes, ref);
      if constexpr (kStats) boxes_tested += filled_slots(node);
      reread_vectors(box_ray);  // as in occluded_impl: no copies live across the leaf tests
      const unsigned mask = test_boxes(node, box_ray, ray.tmin, tmax, entry);
      if (mask != 0) {
        if ((mask & (mask - 1)) == 0) ref = node.child[__builtin_ctz(mask)];
        else ref = order_children(node, mask, entry, stack, size);
        continue;
      }
    } else {
      if constexpr (kStats) prims_tested += WideRef::count(ref);
      if (kTriangles && (!kSpheres || !WideRef::is_sphere_leaf(ref))) {
        const WideTriangleLeaf leaf = wide_triangle_leaf(ref);  // its blocks and lanes (wide_leaf_ref.h)
        // Block by block, walked by pointer: a leaf has at least one lane, so the test comes before the check.
        const TriangleBlock* block = prims.triangle_blocks.data() + leaf.block;
        std::uint32_t block_slot = leaf.block * kTriangleBlockLanes;
        for (std::uint32_t lanes = leaf.lanes;; ++block, block_slot += kTriangleBlockLanes) {
          // t only: the winner's u, v are computed once, at the end, from its kept crossing.
          // The triangle a secondary ray leaves is dropped before the quotient (kBehindFirst).
          intersect_triangle_block_closest</*kBehindFirst=*/true>(
              tri_ray, *block, lanes & kWideBlockLaneMask, ray.tmin, tmax,
              [&](unsigned lane, float t, const refine_detail::Crossing* crossing) {
                const std::uint32_t slot = block_slot + lane;
                const PrimitiveKey key = prims.triangle_keys[slot];
                if (!precedes(t, key.geom_id, key.prim_id, hit)) return tmax;
                hit.t = tmax = t;
                hit.geom_id = key.geom_id;
                hit.prim_id = key.prim_id;
                best_is_sphere = false;
                best_index = slot;
                if constexpr (kAttributes) {
                  best_crossing_kept = crossing != nullptr;
                  if (crossing != nullptr) best_crossing = *crossing;
                }
                return tmax;
              });
          lanes >>= kTriangleBlockLanes;
          if (lanes == 0) break;
        }
      } else if constexpr (kSpheres) {
        const std::uint32_t first = WideRef::first_sphere(ref), count = WideRef::count(ref);
        for (std::uint32_t i = first; i < first + count; ++i) {
          const StoredSphere& s = prims.spheres[i];
          float t;
          if (!intersect_sphere(ray.org, ray.dir, s.center, s.radius, ray.tmin, tmax, t)) continue;
          const PrimitiveKey key = prims.sphere_keys[i];
          if (!precedes(t, key.geom_id, key.prim_id, hit)) continue;
          hit.t = tmax = t;
          hit.geom_id = key.geom_id;
          hit.prim_id = key.prim_id;
          best_is_sphere = true;
          best_index = i;
        }
      }
    }
    if (!pop_next(stack, size, tmax, ref)) break;
  }

  if constexpr (kStats) {
    stats->nodes_visited += boxes_tested;
    stats->primitives_tested += prims_tested;
  }
  if (!hit.found()) return false;
  if constexpr (!kAttributes) return true;
  if (kSpheres && best_is_sphere) {
    const StoredSphere& s = prims.spheres[best_index];
    sphere_hit_attributes(ray.org, ray.dir, hit.t, s.center, s.radius, hit.ng, hit.u, hit.v);
  } else if constexpr (kTriangles) {
    triangle_block_hit_attributes(tri_ray, prims.triangle_blocks[best_index / kTriangleBlockLanes],
                                  best_index % kTriangleBlockLanes, hit.t, hit.u, hit.v, hit.ng,
                                  best_crossing_kept ? &best_crossing : nullptr);
  }
  return true;
}

// Any hit in one block: triangle_block.h's any-hit test (Report::kAny), with the candidates' vertices gathered
// by this instruction set's block_vertex and their crossings decided by the sign of t first (kBySign,
// triangle_refine.h): the same answers.
// Forced inline: GCC called it out of line, which cost 21 instructions per dragon shadow query.
[[gnu::always_inline]] TWINRAY_KERNEL inline bool block_occluded(const TriangleRay& ray, const TriangleBlock& block,
                                                                 unsigned lanes, float tmin, float tmax) {
  using namespace triangle_block_detail;
  const EdgeLanes edges = edge_test(ray, block, lanes);
  if ((edges.candidates | edges.exact_zero) == 0) return false;  // the ray passes beside all four
  for (unsigned m = edges.candidates; m != 0; m &= m - 1) {
    const unsigned lane = static_cast<unsigned>(__builtin_ctz(m));
    const auto exact = [&ray, &block, lane](float& te, float& ue, float& ve) {
      return exact_crossing_of_lane(ray, block, lane, te, ue, ve);
    };
    if (refine_detail::refine_in_interval_v</*kDivisionFreeFirst=*/false, /*kBySign=*/true>(
            ray.refine, block_vertex(block, 0, lane), block_vertex(block, 1, lane), block_vertex(block, 2, lane), tmin,
            tmax, exact))
      return true;
  }
  if (edges.exact_zero == 0) return false;
  BlockHits unused;
  return decide_in_double<Report::kAny>(ray, block, edges.exact_zero, tmin, tmax, unused) != 0;
}

// Any hit in one leaf. Counts the primitives it tests when kStats. kCopy only makes one function per caller
// (occluded_impl's kCopy): GCC inlines a function called once into its caller late, after both are optimised
// on their own, which gives the timed traversal main's code; called from two traversals it inlined neither
// (+25 instructions per Sponza interior camera ray, tenth round), and forced inline (always_inline, inlined
// early) it gave code with the edge test's broadcasts hoisted into the query's set-up (+6 per dragon shadow
// query: docs/bvh-backend.md, eleventh round).
template <bool kTriangles, bool kSpheres, bool kStats, int kCopy>
TWINRAY_KERNEL inline bool leaf_occluded(const PrimitiveStore& prims, std::uint32_t ref, const Ray& ray,
                                         const TriangleRay& tri_ray, std::uint64_t& prims_tested) {
  if (kTriangles && (!kSpheres || !WideRef::is_sphere_leaf(ref))) {
    const WideTriangleLeaf leaf = wide_triangle_leaf(ref);  // its blocks and lanes (wide_leaf_ref.h)
    // Block by block, walked by pointer: most leaves are one block, tested without a loop counter or an index.
    const TriangleBlock* block = prims.triangle_blocks.data() + leaf.block;
    for (std::uint32_t lanes = leaf.lanes;; ++block) {
      const unsigned in_block = lanes & kWideBlockLaneMask;
      if constexpr (kStats) prims_tested += static_cast<unsigned>(__builtin_popcount(in_block));
      // Membership in [tmin, tmax] only: no t is certified unless it lies at an end of the interval.
      // Crossings behind the origin (the triangle a secondary ray leaves) and well inside are decided without
      // the quotient (block_occluded).
      if (block_occluded(tri_ray, *block, in_block, ray.tmin, ray.tmax)) return true;
      lanes >>= kTriangleBlockLanes;
      if (lanes == 0) break;
    }
  } else if constexpr (kSpheres) {
    const std::uint32_t first = WideRef::first_sphere(ref), count = WideRef::count(ref);
    for (std::uint32_t i = first; i < first + count; ++i) {
      if constexpr (kStats) ++prims_tested;
      const StoredSphere& s = prims.spheres[i];
      float t;
      if (intersect_sphere(ray.org, ray.dir, s.center, s.radius, ray.tmin, ray.tmax, t)) return true;
    }
  }
  return false;
}

// Any hit; kStats as for intersect_impl; kNearFirst: the inner child to visit first (AnyHitOrder, wide_kernels.h);
// kCopy: which copy of the leaf test it calls (leaf_occluded).
template <bool kTriangles, bool kSpheres, bool kStats, bool kNearFirst, int kCopy>
[[gnu::always_inline]] TWINRAY_KERNEL inline bool occluded_impl(const WideView& bvh, const Ray& ray,
                                                                QueryStats* stats) {
  WideBoxRay box_ray(ray);
  WideBoxInterval interval(ray);  // [tmin, tmax] as the box test reads it
  const TriangleRay tri_ray = make_wide_triangle_ray(ray);
  const PrimitiveStore& prims = *bvh.prims;

  std::uint32_t stack[kWideStackSize + kWideStackSlack];
  std::size_t size = 0;
  std::uint64_t boxes_tested = 0, prims_tested = 0;
  bool found = false;
  alignas(32) float entry[kWideWidth];

  // The ray's own interval: a leaf whose only hit lies at the rounded tmin or tmax is not culled by the box
  // test's own rounding, whose near and far distances are bounds of the exact ones (ray_box.h).
  std::uint32_t ref = 0;  // a node (the root), by its byte offset (wide_node.h): leaves never go on the stack
  for (;;) {
    const WideNode& node = node_at(bvh.nodes, ref);
    if constexpr (kStats) boxes_tested += filled_slots(node);
    // The box test reads the ray's broadcast vectors as memory operands (the load is part of the
    // arithmetic instruction): kept in registers instead, they are live across the leaf test's call,
    // which clobbers every vector register, and GCC spills and reloads all of them at each node with a
    // hit leaf (docs/bvh-backend.md, "Any-hit, sixth round").
    reread_vectors(box_ray);
    interval.reread();
    const unsigned mask = test_boxes_in(node, box_ray, interval, entry);
    const unsigned leaves = mask & leaf_children(node);
    for (unsigned m = leaves; m != 0; m &= m - 1) {
      if (leaf_occluded<kTriangles, kSpheres, kStats, kCopy>(prims, node.child[__builtin_ctz(m)], ray, tri_ray, prims_tested)) {
        found = true;
        break;
      }
    }
    if (found) break;
    const unsigned inner = mask & ~leaves;
    if (inner != 0) {
      if constexpr (!kNearFirst) {
        // Visit the lowest slot (largest area) now; push the others so the next lowest pops first. (The slot
        // straight from __builtin_ctz as main had it: through an unsigned variable GCC adds a zero extension.)
        ref = node.child[__builtin_ctz(inner)];
        size += push_children(node, inner & (inner - 1), stack + size);
      } else {
        // The nearest entry (the lowest slot among equals) now; the others pushed as above.
        unsigned now = static_cast<unsigned>(__builtin_ctz(inner)), others = inner & (inner - 1);
        if (others != 0) {
          float best = entry[now];  // kept in a register: no reload of entry[now] per child
          for (unsigned m = others; m != 0; m &= m - 1) {
            const unsigned s = static_cast<unsigned>(__builtin_ctz(m));
            const float e = entry[s];
            const bool nearer = e < best;
            now = nearer ? s : now;
            best = nearer ? e : best;
          }
          others = inner & ~(1u << now);
        }
        ref = node.child[now];
        size += push_children(node, others, stack + size);
      }
      continue;
    }
    if (size == 0) break;
    ref = stack[--size];
  }

  if constexpr (kStats) {
    stats->nodes_visited += boxes_tested;
    stats->primitives_tested += prims_tested;
  }
  return found;
}

}  // namespace wide_detail

template <bool kTriangles, bool kSpheres, bool kAttributes>
TWINRAY_KERNEL bool wide_intersect(WideView bvh, const Ray& ray, Hit& hit, QueryStats* stats) {
  if (!wide_ray_is_valid(ray)) {  // an invalid ray must not sweep the tree
    hit = Hit{};
    return false;
  }
  if (stats != nullptr)
    return wide_detail::intersect_impl<kTriangles, kSpheres, true, kAttributes>(bvh, ray, hit, stats);
  return wide_detail::intersect_impl<kTriangles, kSpheres, false, kAttributes>(bvh, ray, hit, nullptr);
}

#ifndef TWINRAY_WIDE_NEAREST_UNIT

template <bool kTriangles, bool kSpheres>
TWINRAY_KERNEL bool wide_occluded(WideView bvh, const Ray& ray, QueryStats* stats) {
  if (!wide_ray_is_valid(ray)) return false;
  if (stats != nullptr) return wide_detail::occluded_impl<kTriangles, kSpheres, true, false, 0>(bvh, ray, stats);
  return wide_detail::occluded_impl<kTriangles, kSpheres, false, false, 0>(bvh, ray, nullptr);
}

// The entry points of this instruction set's kernels (wide_kernels.h), the any-hit one in stored order.
WideKernels kernels(bool triangles, bool spheres) {
  if (triangles && spheres)
    return {&wide_intersect<true, true, true>, &wide_intersect<true, true, false>, &wide_occluded<true, true>};
  if (spheres)
    return {&wide_intersect<false, true, true>, &wide_intersect<false, true, false>, &wide_occluded<false, true>};
  return {&wide_intersect<true, false, true>, &wide_intersect<true, false, false>, &wide_occluded<true, false>};
}

#else  // the nearest-first any-hit kernels' own unit (wide_kernels_<isa>_nearest.cpp)

// Any hit with the nearest hit inner child first on segments (a finite tmax: shadow rays). Rays without an end
// take the stored order: on the trees that choose nearest first they visit as many nodes either way and would
// only pay for the search (docs/bvh-backend.md, tenth round), so the choice is made once per query here, not
// at every node.
template <bool kTriangles, bool kSpheres>
TWINRAY_KERNEL bool wide_occluded_nearest(WideView bvh, const Ray& ray, QueryStats* stats) {
  if (!wide_ray_is_valid(ray)) return false;
  const bool segment = ray.tmax < std::numeric_limits<float>::infinity();
  if (stats != nullptr) {
    if (segment) return wide_detail::occluded_impl<kTriangles, kSpheres, true, true, 1>(bvh, ray, stats);
    return wide_detail::occluded_impl<kTriangles, kSpheres, true, false, 2>(bvh, ray, stats);
  }
  if (segment) return wide_detail::occluded_impl<kTriangles, kSpheres, false, true, 1>(bvh, ray, nullptr);
  return wide_detail::occluded_impl<kTriangles, kSpheres, false, false, 2>(bvh, ray, nullptr);
}

WideOccludedKernel nearest_occluded(bool triangles, bool spheres) {
  if (triangles && spheres) return &wide_occluded_nearest<true, true>;
  if (spheres) return &wide_occluded_nearest<false, true>;
  return &wide_occluded_nearest<true, false>;
}

#endif
