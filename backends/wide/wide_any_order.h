#pragma once
// Chooses a built tree's any-hit order (AnyHitOrder, wide_kernels.h) by probing: a fixed sample of shadow-like
// segments is traced with both any-hit kernels, counting the work, and the nearest-first order is taken only
// when it is clearly cheaper.
//
// Why per tree: neither order wins everywhere (docs/bvh-backend.md, "Tenth round"). In volumes of small
// primitives (soups, the hairball) the child the ray enters first is the cheaper way to an occluder (soup-1M
// shadow rays: 206 node boxes per ray stored-first, 123 nearest-first); in a building the larger child, a wall
// or a floor, is (Sponza interior camera rays: 36 against 54). A segment of the probe joins the first hit of a
// ray from outside the scene to a random point of the scene's padded box, like a shadow ray toward a light
// somewhere in it. The answers are the same whichever order is chosen; only the work differs.

#include "backends/bvh/primitive_store.h"
#include "backends/wide/wide_kernels.h"
#include "backends/wide/wide_node.h"

#include <cstdint>
#include <span>

namespace twinray {

struct AnyHitProbe {
  // The work of each order on the probe: node boxes tested plus kWideProbePrimitiveWeight per primitive.
  double stored_cost = 0.0, nearest_cost = 0.0;
  std::uint32_t segments = 0;
  AnyHitOrder chosen = AnyHitOrder::kStored;
};

// Segments in the probe, and the share of the stored order's cost below which the nearest-first order is chosen:
// tuned on the issue-12 scenes (the docs list every tree's ratio) to keep the Sponza interior's mesh (0.92),
// whose own lamp-lit rays lose with nearest first, on the stored order.
inline constexpr std::uint32_t kWideProbeSegments = 256;
inline constexpr double kWideProbeMargin = 0.875;
// A node box test is about 6 instructions (eight boxes in about 45), a triangle's share of a block test about 24.
inline constexpr double kWideProbePrimitiveWeight = 4.0;

// `stored` and `nearest`: both orders' kernels for this tree's primitive kinds. Deterministic (a fixed generator),
// and the same on every instruction set (the kernels count the same boxes and primitives).
AnyHitProbe probe_any_hit_order(std::span<const WideNode> nodes, const PrimitiveStore& prims,
                                const WideKernels& stored, const WideKernels& nearest);

}  // namespace twinray
