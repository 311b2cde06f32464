#pragma once
// Writing result files so that a reader never sees a half-written one: write a temporary file in the same
// folder, then rename it over the target (atomic on POSIX file systems). On failure the temporary file is
// removed and InputError names the target.

#include <filesystem>
#include <string_view>

namespace twinray {

void write_file_atomically(const std::filesystem::path& path, std::string_view contents);

// A temporary name beside `path` (same folder, so rename() stays on one file system).
std::filesystem::path temporary_path_for(const std::filesystem::path& path);

}  // namespace twinray
