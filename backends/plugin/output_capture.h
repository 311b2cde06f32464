#pragma once
// What a plugin printed, kept within a byte limit: the first half of the limit and the last half, with a
// marker saying how much was dropped in between. The beginning shows what the plugin said while loading and
// building; the end shows what it said just before it failed (an assertion, a last debug line).

#include <cstddef>
#include <string>
#include <string_view>

namespace twinray {

class OutputCapture {
 public:
  explicit OutputCapture(std::size_t limit) : head_limit_(limit / 2), tail_limit_(limit - limit / 2) {}

  void append(std::string_view bytes);
  std::string text() const;
  std::size_t total_bytes() const { return total_; }

 private:
  std::size_t head_limit_;
  std::size_t tail_limit_;
  std::string head_;
  std::string tail_;  // a ring buffer once full: tail_start_ is its oldest byte
  std::size_t tail_start_ = 0;
  std::size_t total_ = 0;
};

}  // namespace twinray
