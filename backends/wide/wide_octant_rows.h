#pragma once
// The row offsets (WideNode::lo_row / hi_row) of the near and far planes of each axis, for each of the eight
// octants of a ray direction: octant bit a set when the direction's reciprocal on axis a has its sign bit
// set (-0 included, as std::signbit in ray_box.h). The slab test reads its rows through the ray's entry.

#include "backends/wide/wide_node.h"

#include <array>
#include <cstddef>

namespace twinray {

struct WideOctantRows {
  std::size_t near_row[3], far_row[3];
};

inline constexpr std::array<WideOctantRows, 8> kWideOctantRows = [] {
  std::array<WideOctantRows, 8> table{};
  for (unsigned octant = 0; octant < 8; ++octant)
    for (int a = 0; a < 3; ++a) {
      const bool negative = ((octant >> a) & 1u) != 0;
      table[octant].near_row[a] = negative ? WideNode::hi_row(a) : WideNode::lo_row(a);
      table[octant].far_row[a] = negative ? WideNode::lo_row(a) : WideNode::hi_row(a);
    }
  return table;
}();

}  // namespace twinray
