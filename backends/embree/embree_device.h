#pragma once
// One Embree device with its two callbacks: errors are never silent, and memory is accounted.
//
// Errors. Embree reports problems through a per-device callback, possibly from TBB worker threads during a
// build. Throwing through Embree's frames is not an option, so the callback records the first error, and
// the owner calls throw_if_error() after every group of API calls (a build): the error surfaces as a
// std::runtime_error on the calling thread. An error raised outside such a group (during queries, where a
// check per ray would cost too much) is printed to stderr the moment it happens.
//
// Memory. The memory monitor callback is invoked for every large allocation and release the device makes
// (BVH nodes, primitive blocks, private buffer copies), from any thread: a positive byte count for an
// allocation, a negative one for a release. Each event is reported exactly once, so a plain running sum is
// the device's current footprint. The sum does not include shared buffers (they are ours, not Embree's).

#include <embree3/rtcore.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>

namespace twinray {

class EmbreeDevice {
 public:
  EmbreeDevice();
  ~EmbreeDevice();
  EmbreeDevice(const EmbreeDevice&) = delete;
  EmbreeDevice& operator=(const EmbreeDevice&) = delete;

  RTCDevice get() const { return device_; }

  // Bytes currently allocated by the device, and the high-water mark since construction.
  std::size_t allocated_bytes() const;
  std::size_t peak_allocated_bytes() const;

  // Throws std::runtime_error naming `what` and the first recorded Embree error, if any, and clears it.
  void throw_if_error(const char* what);
  // From now on errors are printed to stderr as they happen (nobody will call throw_if_error again).
  void report_errors_immediately() { report_immediately_.store(true); }

 private:
  static void on_error(void* self, RTCError code, const char* message);
  static bool on_memory(void* self, ssize_t bytes, bool post);

  RTCDevice device_ = nullptr;
  std::atomic<std::int64_t> allocated_{0};
  std::atomic<std::int64_t> peak_{0};
  std::atomic<bool> report_immediately_{false};
  std::mutex error_mutex_;
  std::string first_error_;  // empty: no error since the last throw_if_error()
};

}  // namespace twinray
