#include "harness/grade/timed_query.h"

#include <chrono>
#include <vector>

namespace twinray::grade {

double time_one_run(const Backend& backend, std::span<const Ray> rays, bool any_hit, QueryStats& stats) {
  std::vector<Hit> hits(any_hit ? 0 : rays.size());
  std::vector<std::uint8_t> occluded(any_hit ? rays.size() : 0);
  stats = {};
  const auto start = std::chrono::steady_clock::now();
  if (any_hit) backend.occluded(rays, std::span<std::uint8_t>(occluded), &stats);
  else backend.intersect(rays, std::span<Hit>(hits), &stats);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace twinray::grade
