#pragma once
// Waiting on a 32-bit word of memory shared between twinray and its plugin worker: spin briefly, then sleep
// in the kernel (futex) until the other side changes the word and wakes us, or a timeout passes.
//
// The futexes are shared (no FUTEX_PRIVATE_FLAG): the word lives in a MAP_SHARED mapping of a memfd, and the
// kernel keys shared futexes by the underlying page, so a wake from either process reaches a waiter in the
// other.

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cstdint>
#include <ctime>

namespace twinray::plugin_worker {

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

// Sleeps while *word == expected, at most `timeout` (none: forever). Returns early on a wake, a change, a
// signal or a spurious wake-up: callers re-check their condition in a loop.
inline void futex_wait(std::atomic<std::uint32_t>* word, std::uint32_t expected,
                       std::chrono::nanoseconds timeout = std::chrono::nanoseconds::max()) {
  timespec ts{};
  timespec* tsp = nullptr;
  if (timeout != std::chrono::nanoseconds::max()) {
    const auto ns = timeout.count() < 0 ? 0 : timeout.count();
    ts.tv_sec = static_cast<time_t>(ns / 1'000'000'000);
    ts.tv_nsec = static_cast<long>(ns % 1'000'000'000);
    tsp = &ts;
  }
  // std::atomic<uint32_t> is a plain 32-bit word (lock-free, address-free), which is what the futex reads.
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(word), FUTEX_WAIT, expected, tsp, nullptr, 0);
}

inline void futex_wake_all(std::atomic<std::uint32_t>* word) {
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(word), FUTEX_WAKE, INT_MAX, nullptr, nullptr, 0);
}

}  // namespace twinray::plugin_worker
