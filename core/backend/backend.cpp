#include "core/backend/backend.h"

#include <cassert>

namespace twinray {

void Backend::intersect(std::span<const Ray> rays, std::span<Hit> hits, QueryStats* stats) const {
  assert(rays.size() == hits.size());
  for (std::size_t i = 0; i < rays.size(); ++i) intersect(rays[i], hits[i], stats);
}

void Backend::occluded(std::span<const Ray> rays, std::span<std::uint8_t> result, QueryStats* stats) const {
  assert(rays.size() == result.size());
  for (std::size_t i = 0; i < rays.size(); ++i) result[i] = occluded(rays[i], stats) ? 1 : 0;
}

}  // namespace twinray
