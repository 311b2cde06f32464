#include "core/scene/input_file.h"

#include "core/util/input_error.h"

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <system_error>

namespace twinray {

void require_regular_file(const std::filesystem::path& path) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (status.type() == std::filesystem::file_type::not_found)
    throw InputError(path, "", "file not found");
  if (ec) throw InputError(path, "", "cannot access file: " + ec.message());
  if (status.type() == std::filesystem::file_type::directory)
    throw InputError(path, "", "is a directory, expected a file");
  if (status.type() != std::filesystem::file_type::regular)
    throw InputError(path, "", "is not a regular file");
}

std::string read_input_file(const std::filesystem::path& path) {
  require_regular_file(path);
  // stdio rather than ifstream: errno then tells *why* a read failed (permission denied, I/O error).
  struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  errno = 0;
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file) throw InputError(path, "", std::string("cannot open file: ") + std::strerror(errno));

  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path, "", "cannot determine file size: " + ec.message());

  std::string bytes(static_cast<std::size_t>(size), '\0');
  const std::size_t got = size ? std::fread(bytes.data(), 1, bytes.size(), file.get()) : 0;
  if (got != bytes.size() || std::ferror(file.get()))
    throw InputError(path, "", std::string("cannot read file: ") + (errno ? std::strerror(errno) : "short read"));
  return bytes;
}

std::filesystem::path resolve_relative(const std::filesystem::path& base_dir, const std::filesystem::path& path) {
  if (path.is_absolute() || base_dir.empty()) return path;
  return base_dir / path;
}

std::string lower_extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace twinray
