#pragma once
// For the any-hit traversal's push of a node's hit inner children (wide_box_test_256.inl): for each 8-bit
// mask of child slots, the slots set in it, highest first, one byte each (unused bytes 0). Permuting the
// node's child row by these indices puts the children on the stack in one store, the lowest slot (the
// larger box: children are stored larger weight first, wide_collapse.h) on top, so it is popped first:
// the order the scalar push loop gave, without a branch per child.

#include <array>
#include <cstdint>

namespace twinray {

inline constexpr std::array<std::uint64_t, 256> kWideDescendingSlots = [] {
  std::array<std::uint64_t, 256> table{};
  for (unsigned mask = 0; mask < 256; ++mask) {
    std::uint64_t bytes = 0;
    unsigned position = 0;
    for (int slot = 7; slot >= 0; --slot)
      if ((mask >> slot) & 1u) bytes |= static_cast<std::uint64_t>(slot) << (8 * position++);
    table[mask] = bytes;
  }
  return table;
}();

}  // namespace twinray
