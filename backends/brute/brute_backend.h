#pragma once
// The brute-force oracle: every query tests every primitive. Slow on purpose and simple enough to trust;
// the other backends are checked against it (bvh bit for bit).

#include "core/backend/backend.h"

#include <memory>

namespace twinray {

// name() == "brute". Closest hits are chosen by the total order `precedes` (core/geometry/hit.h), so
// equidistant hits resolve to the lowest (geom_id, prim_id) whatever the loop order.
std::unique_ptr<Backend> make_brute_backend();

}  // namespace twinray
