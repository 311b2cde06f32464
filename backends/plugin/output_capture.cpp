#include "backends/plugin/output_capture.h"

#include <fmt/core.h>

namespace twinray {

void OutputCapture::append(std::string_view bytes) {
  total_ += bytes.size();
  const std::size_t to_head = std::min(bytes.size(), head_limit_ - head_.size());
  head_.append(bytes.substr(0, to_head));
  bytes.remove_prefix(to_head);
  if (tail_limit_ == 0 || bytes.empty()) return;
  // Only the last tail_limit_ bytes of this piece can survive.
  if (bytes.size() > tail_limit_) bytes.remove_prefix(bytes.size() - tail_limit_);
  for (const char c : bytes) {
    if (tail_.size() < tail_limit_) {
      tail_.push_back(c);
    } else {
      tail_[tail_start_] = c;
      tail_start_ = (tail_start_ + 1) % tail_limit_;
    }
  }
}

std::string OutputCapture::text() const {
  std::string s = head_;
  const std::size_t kept = head_.size() + tail_.size();
  if (total_ > kept) s += fmt::format("\n[... {} bytes of output dropped ...]\n", total_ - kept);
  s.append(tail_, tail_start_, std::string::npos);
  s.append(tail_, 0, tail_start_);
  return s;
}

}  // namespace twinray
