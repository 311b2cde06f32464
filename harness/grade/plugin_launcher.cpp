#include "harness/grade/plugin_launcher.h"

#include "backends/registry.h"
#include "core/util/input_error.h"

#include <fmt/core.h>

namespace twinray::grade {

PluginLauncher::PluginLauncher(std::filesystem::path so) : path_(std::filesystem::absolute(so)) {
  const std::unique_ptr<Backend> probe = make_backend("plugin:" + path_.string());
  name_ = std::string(probe->name());
  traits_ = probe->traits();
}

std::unique_ptr<Backend> PluginLauncher::launch(const LaunchLimits& /*limits*/) const {
  return make_backend("plugin:" + path_.string());
}

FailureReport classify_failure(const std::exception_ptr& failure) {
  try {
    std::rethrow_exception(failure);
  } catch (const InputError&) {
    throw;
  } catch (const std::runtime_error& e) {
    // The in-process plugin backend reports contract violations (a failed build, a hit on a primitive that
    // does not exist, an escaping C++ exception) as runtime_error.
    return {Outcome::Fail, e.what(), std::nullopt};
  }
}

}  // namespace twinray::grade
