#pragma once
// Catching what an isolated plugin backend throws, for tests of its failures.

#include "backends/plugin/plugin_failure.h"

#include <optional>
#include <utility>

namespace twinray::test {

// Runs `call`, which should throw a PluginFailure, and returns it; nullopt when `call` returned normally.
template <typename F>
std::optional<PluginFailure> failure_of(F&& call) {
  try {
    std::forward<F>(call)();
  } catch (const PluginFailure& f) {
    return f;
  }
  return std::nullopt;
}

}  // namespace twinray::test
