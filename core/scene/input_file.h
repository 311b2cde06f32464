#pragma once
// Reading a user-supplied file whole, with the same clear diagnostics for every loader: a missing file,
// a directory where a file was expected and an unreadable file each get their own message.

#include <filesystem>
#include <string>

namespace twinray {

// Throws InputError(path, "", ...) unless `path` names a readable regular file (or a symlink to one).
void require_regular_file(const std::filesystem::path& path);

// The file's bytes. Loaders parse from memory: one read() is much faster than stream extraction, and a
// size known up front lets binary readers check declared element counts before allocating anything.
std::string read_input_file(const std::filesystem::path& path);

// `path` if it is absolute, otherwise `path` relative to `base_dir` (the folder of the referring file).
std::filesystem::path resolve_relative(const std::filesystem::path& base_dir, const std::filesystem::path& path);

// Lower-case extension including the dot (".obj"), so "Bunny.OBJ" is recognised too.
std::string lower_extension(const std::filesystem::path& path);

}  // namespace twinray
