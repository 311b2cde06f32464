#pragma once
// How an isolated plugin's failure reaches the caller: a PluginFailure thrown by the isolated backend's
// build, intersect and occluded (isolated_plugin_backend.h). A crash, abort, exit, escaping exception,
// timeout, exhausted memory or sandbox violation of the plugin becomes a result the caller can report,
// with the exact ray that was being traced; twinray itself never crashes or hangs because of a plugin.
//
// Vocabulary (stable: `twinray grade` and its JSON use these words):
//   kind   Crash | Timeout | ContractViolation
//   cause  "signal"        killed by a signal (signal_name), e.g. SIGSEGV, SIGBUS, SIGFPE, SIGILL
//          "abort"         SIGABRT (abort(), a failed assert, std::terminate)
//          "exit"          the plugin called exit() or _exit() (exit_code)
//          "out-of-memory" an allocation failed at the memory limit (std::bad_alloc, or a fatal signal in a
//                          call in which an allocation had failed, see docs/plugin-abi.md)
//          "sandbox"       a forbidden system call (syscall), stopped by the seccomp filter: SIGSYS
//          "timeout"       one call over PluginLimits::query_seconds / build_seconds, or past the deadline
//          "exception"     a C++ exception escaped through the C ABI
//          "bad-hit"       a hit on a geometry or primitive that does not exist (kind ContractViolation)
//          "fp-environment" a call returned with other floating-point control bits (flush-to-zero,
//                          denormals-are-zero, rounding, exception masks) than it was called with (kind
//                          ContractViolation; isolated plugins only: the worker compares them)
//          "out-of-bounds-write" a batch call wrote past the answers it was given (kind ContractViolation;
//                          isolated plugins only: guard bytes after the worker's answer arrays)
//          "corrupted"     an answer in the shared memory that the worker cannot give (a sequence number,
//                          status, count or flag outside the protocol of worker_protocol.h): the plugin, which
//                          runs in the worker's process, wrote over it (kind Crash)
//          "load"          reserved: a plugin that cannot be loaded is an InputError (missing file, not a
//                          library, no entry point, wrong ABI, NULL function, create() NULL), and one that
//                          crashes or hangs while loading gets one of the causes above with stage "load"
//   stage  "load" (dlopen, static constructors, create), "build", "intersect", "occluded", "destroy",
//          "intersect_batch", "occluded_batch" (a call of the plugin's batch function: ray_index is its first ray)

#include "core/geometry/ray.h"

#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>

namespace twinray {

enum class PluginFailureKind { Crash, Timeout, ContractViolation };

std::string_view to_string(PluginFailureKind kind);

// Everything known about a failure; PluginFailure is this plus the message built from it.
struct PluginFailureDetails {
  PluginFailureKind kind = PluginFailureKind::Crash;
  std::string cause;
  std::string signal_name;  // "SIGSEGV", "SIGABRT", "SIGSYS", ... (empty when not a signal)
  int exit_code = 0;        // for cause "exit"
  std::string stage;
  std::string syscall;      // cause "sandbox": the system call the plugin attempted, by name (e.g. "openat")
  std::optional<std::size_t> ray_index;  // index into the span the caller passed (0 for single-ray calls)
  std::optional<Ray> ray;                // the exact ray that was being traced
  // cause "timeout": the caller's deadline for all work passed (PluginLimits::deadline), rather than one call
  // running over its own limit. The ray in flight then only happened to be the last one: it does not hang.
  bool deadline_passed = false;
  // cause "timeout": how long the call in flight (the ray above) had at least been running when the time ran
  // out, in seconds (from when twinray first saw the worker on that ray; 0 when not measured). Past the
  // deadline, a call that had only just begun is not the one that hangs.
  double call_seconds = 0.0;
  std::string output;       // the worker's captured stdout + stderr, truncated to PluginLimits::output_bytes
  // For the message: which plugin ("plugin:NAME (PATH)", or the path before the name is known) and what else
  // is worth saying (the exception's what(), the limit that was exceeded, ...).
  std::string plugin;
  std::string detail;
};

// The plugin's build() returned TWINRAY_ERROR: it declined the scene, with its own message. Not a crash, and
// not bad input either (the scene is fine: the plugin under test failed), so commands stop with exit code 1,
// as for a PluginFailure (docs/cli.md). Thrown by the in-process and the isolated plugin backend alike.
struct PluginBuildError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct PluginFailure : std::runtime_error, PluginFailureDetails {
  explicit PluginFailure(PluginFailureDetails details);

  // The same fields as named in the contract of issue 10, via PluginFailureDetails:
  //   kind, cause, signal_name, exit_code, stage, syscall, ray_index, ray, output.
};

// One line saying what happened, e.g. "plugin:mybvh (/x/libmybvh.so) crashed with SIGSEGV in intersect,
// ray 1234 (0x1p+0 0x1p+0 0x1p+0 0x0p+0 -0x1p+0 0x0p+0 0x0p+0 inf)". The captured output is not part of it.
std::string describe(const PluginFailureDetails& failure);

// The eight floats of a ray in hexadecimal, exactly: "ox oy oz dx dy dz tmin tmax" (C's %a, "inf", "nan"),
// the order a ray is given to `twinray trace --ray`.
std::string exact_ray_text(const Ray& ray);

}  // namespace twinray
