#pragma once
// Waiting on a 32-bit word of memory shared between twinray and its plugin worker: spin briefly (yielding the
// processor), then sleep in the kernel (futex) until the other side changes the word and wakes us, or a
// timeout passes.
//
// The futexes are shared (no FUTEX_PRIVATE_FLAG): the word lives in a MAP_SHARED mapping of a memfd, and the
// kernel keys shared futexes by the underlying page, so a wake from either process reaches a waiter in the
// other.

#include <linux/futex.h>
#include <sched.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cstdint>
#include <ctime>

namespace twinray::plugin_worker {

// Waits up to `budget` for `done()` to become true without sleeping in the kernel; returns done().
//
// It yields the processor between checks rather than spinning on a pause instruction. Measured on the 2-core
// reference machine under load (docs/plugin-abi.md): the scheduler tends to put twinray's calling thread and
// the worker thread that answers it on the same core (the wake-up is affine to the waker), and a thread that
// spins there keeps the very thread it waits for off the processor for its whole spin; a round trip took
// twice the spin budget. Yielding hands the core over at once (1 to 4 us per round trip), and costs a
// system call per check (a fraction of a microsecond) when each side has a core of its own.
template <typename Done>
bool spin_yielding(Done&& done, std::chrono::nanoseconds budget) {
  const auto started = std::chrono::steady_clock::now();
  for (;;) {
    if (done()) return true;
    if (std::chrono::steady_clock::now() - started >= budget) return done();
    sched_yield();
  }
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
