#pragma once
// A one-line progress indicator with ETA for long work.
//
// Shown only when stderr is a terminal and CI is not set, so logs and pipes stay clean. Thread-safe:
// workers call advance() from any thread; the line is redrawn at most every 100 ms.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace twinray {

class Progress {
 public:
  Progress(std::string label, std::uint64_t total);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void advance(std::uint64_t amount = 1);
  void finish();  // clears the line; called by the destructor too
  bool enabled() const { return enabled_; }

  // True when progress lines should be drawn (stderr is a terminal and CI is unset or "false").
  static bool terminal_wanted();

 private:
  void draw(std::uint64_t done, bool force);

  std::string label_;
  std::uint64_t total_;
  std::atomic<std::uint64_t> done_{0};
  bool enabled_;
  bool finished_ = false;
  std::mutex draw_mutex_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace twinray
