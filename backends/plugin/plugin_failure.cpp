#include "backends/plugin/plugin_failure.h"

#include "core/geometry/ray_text.h"

#include <fmt/core.h>

#include <utility>

namespace twinray {

namespace {

std::string what_happened(const PluginFailureDetails& f) {
  if (f.cause == "signal") return fmt::format("crashed with {}", f.signal_name);
  if (f.cause == "abort") return fmt::format("aborted ({})", f.signal_name.empty() ? "SIGABRT" : f.signal_name);
  if (f.cause == "exit") return fmt::format("called exit({})", f.exit_code);
  if (f.cause == "out-of-memory")
    return f.signal_name.empty() ? std::string("ran out of memory")
                                 : fmt::format("ran out of memory ({} after a failed allocation)", f.signal_name);
  if (f.cause == "sandbox")
    return fmt::format("was stopped by the sandbox: system call '{}' is not allowed ({})",
                       f.syscall.empty() ? "?" : f.syscall, f.signal_name.empty() ? "SIGSYS" : f.signal_name);
  if (f.cause == "timeout") return "timed out";
  if (f.cause == "exception") return "let a C++ exception escape";
  if (f.cause == "bad-hit") return "broke the plugin contract";
  if (f.cause == "fp-environment") return "left the floating-point environment changed";
  if (f.cause == "out-of-bounds-write") return "wrote past its answers";
  if (f.cause == "corrupted") return "wrote over the worker's shared memory";
  if (f.cause == "load") return "failed while loading";
  return f.cause;
}

}  // namespace

std::string_view to_string(PluginFailureKind kind) {
  switch (kind) {
    case PluginFailureKind::Crash: return "crash";
    case PluginFailureKind::Timeout: return "timeout";
    case PluginFailureKind::ContractViolation: return "contract-violation";
  }
  return "crash";
}

std::string exact_ray_text(const Ray& r) { return format_ray_hex(r); }

std::string describe(const PluginFailureDetails& f) {
  std::string s = fmt::format("{} {}", f.plugin.empty() ? std::string("plugin") : f.plugin, what_happened(f));
  if (!f.stage.empty()) s += fmt::format(" in {}", f.stage);
  if (f.ray) {
    const Ray& r = *f.ray;
    s += f.ray_index ? fmt::format(", ray {}", *f.ray_index) : std::string(", ray");
    s += fmt::format(": org ({:.9g}, {:.9g}, {:.9g}) dir ({:.9g}, {:.9g}, {:.9g}) t [{:.9g}, {:.9g}], exactly '{}'", r.org.x,
                     r.org.y, r.org.z, r.dir.x, r.dir.y, r.dir.z, r.tmin, r.tmax, exact_ray_text(r));
  }
  if (!f.detail.empty()) s += fmt::format(" ({})", f.detail);
  return s;
}

PluginFailure::PluginFailure(PluginFailureDetails details)
    : std::runtime_error(describe(details)), PluginFailureDetails(std::move(details)) {}

}  // namespace twinray
