#pragma once
// The shared data folder: real meshes, HDR maps and reference renders that live beside the repository
// (`../shared`), never inside it. Scenes name files in it as `$TWINRAY_SHARED/data/meshes/...`, so one scene
// file works wherever the folder is.

#include <filesystem>
#include <optional>
#include <string_view>

namespace twinray {

// $TWINRAY_SHARED when set; otherwise the first folder named `shared` beside `near` or beside one of its
// ancestors (the layout `../shared` next to the repository), recognised by its `data/` subfolder.
std::optional<std::filesystem::path> find_shared_data(const std::filesystem::path& near);

// The prefixes a scene path may start with to name a file in the shared folder.
inline constexpr std::string_view kSharedDataPrefixes[] = {"$TWINRAY_SHARED/", "${TWINRAY_SHARED}/"};

}  // namespace twinray
