#include "core/scene/shared_data.h"

#include <cstdlib>
#include <system_error>

namespace twinray {

std::optional<std::filesystem::path> find_shared_data(const std::filesystem::path& near) {
  if (const char* env = std::getenv("TWINRAY_SHARED"); env != nullptr && env[0] != '\0') return std::filesystem::path(env);
  std::error_code ec;
  std::filesystem::path dir = std::filesystem::absolute(near, ec);
  if (ec) return std::nullopt;
  for (; !dir.empty(); dir = dir.parent_path()) {
    const std::filesystem::path candidate = dir / "shared";
    if (std::filesystem::is_directory(candidate / "data", ec)) return candidate;
    if (dir == dir.parent_path()) break;
  }
  return std::nullopt;
}

}  // namespace twinray
