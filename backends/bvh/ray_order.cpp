#include "backends/bvh/ray_order.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace twinray {

namespace {

// Spreads the low 10 bits of v so that there are two zero bits between each.
std::uint32_t spread_bits(std::uint32_t v) {
  v &= 0x3ffu;
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

std::uint32_t quantize(float x, float lo, float scale) {
  const float q = (x - lo) * scale;
  // Written so that NaN (an invalid ray, which the traversal rejects anyway) lands on 0.
  return q > 0.0f ? static_cast<std::uint32_t>(std::min(q, 1023.0f)) : 0u;
}

}  // namespace

std::vector<std::uint32_t> morton_ray_order(std::span<const Ray> rays, const Bounds3& bounds) {
  const glm::vec3 extent = bounds.hi - bounds.lo;
  glm::vec3 scale(0.0f);
  for (int a = 0; a < 3; ++a) scale[a] = extent[a] > 0.0f ? 1024.0f / extent[a] : 0.0f;

  // (code << 32 | index), sorted by an LSD radix sort on the code's 30 bits: stable, so ties keep the
  // input order, and linear, so ordering costs little next to tracing.
  std::vector<std::uint64_t> keys(rays.size()), scratch(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const glm::vec3& o = rays[i].org;
    const std::uint32_t code = (spread_bits(quantize(o.x, bounds.lo.x, scale.x)) << 2) |
                               (spread_bits(quantize(o.y, bounds.lo.y, scale.y)) << 1) |
                               spread_bits(quantize(o.z, bounds.lo.z, scale.z));
    keys[i] = (std::uint64_t{code} << 32) | i;
  }
  constexpr int kDigitBits = 10;
  for (int shift = 32; shift < 32 + 30; shift += kDigitBits) {
    std::array<std::size_t, (1u << kDigitBits) + 1> start{};
    for (const std::uint64_t k : keys) ++start[((k >> shift) & ((1u << kDigitBits) - 1)) + 1];
    for (std::size_t d = 1; d < start.size(); ++d) start[d] += start[d - 1];
    for (const std::uint64_t k : keys) scratch[start[(k >> shift) & ((1u << kDigitBits) - 1)]++] = k;
    keys.swap(scratch);
  }
  std::vector<std::uint32_t> order(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) order[i] = static_cast<std::uint32_t>(keys[i] & 0xffffffffu);
  return order;
}

}  // namespace twinray
