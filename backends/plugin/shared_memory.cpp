#include "backends/plugin/shared_memory.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <fmt/core.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace twinray {

namespace {
std::runtime_error memory_error(const char* what) {
  return std::runtime_error(fmt::format("plugin worker shared memory: {} failed: {}", what, std::strerror(errno)));
}
}  // namespace

std::size_t page_size() { return static_cast<std::size_t>(sysconf(_SC_PAGESIZE)); }

SharedMemoryFile::SharedMemoryFile(std::size_t bytes) {
  fd_ = memfd_create("twinray-plugin", MFD_CLOEXEC | MFD_ALLOW_SEALING);
  if (fd_ < 0) throw memory_error("memfd_create");
  grow(bytes);
  if (fcntl(fd_, F_ADD_SEALS, F_SEAL_SHRINK) != 0) {
    const std::runtime_error e = memory_error("sealing the memfd");
    close(fd_);
    throw e;
  }
}

SharedMemoryFile::~SharedMemoryFile() {
  if (fd_ >= 0) close(fd_);
}

void SharedMemoryFile::grow(std::size_t bytes) {
  if (bytes <= size_) return;
  if (ftruncate(fd_, static_cast<off_t>(bytes)) != 0) throw memory_error("ftruncate");
  size_ = bytes;
}

SharedMapping::SharedMapping(const SharedMemoryFile& file, std::uint64_t offset, std::size_t bytes) : bytes_(bytes) {
  data_ = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED, file.fd(), static_cast<off_t>(offset));
  if (data_ == MAP_FAILED) {
    data_ = nullptr;
    throw memory_error("mmap");
  }
}

SharedMapping::~SharedMapping() {
  if (data_ != nullptr) munmap(data_, bytes_);
}

}  // namespace twinray
