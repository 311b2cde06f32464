#pragma once
// An anonymous file in memory (memfd) shared with the plugin worker, and mappings of parts of it.
//
// The file can grow but never shrink (F_SEAL_SHRINK): the worker holds the same file, and if it could truncate
// it, twinray's next access to a mapping would fault (SIGBUS) in twinray instead of failing in the worker.

#include <cstddef>
#include <cstdint>

namespace twinray {

class SharedMemoryFile {
 public:
  explicit SharedMemoryFile(std::size_t bytes);  // zero-filled; throws std::runtime_error
  ~SharedMemoryFile();
  SharedMemoryFile(const SharedMemoryFile&) = delete;
  SharedMemoryFile& operator=(const SharedMemoryFile&) = delete;

  int fd() const { return fd_; }
  std::size_t size() const { return size_; }
  void grow(std::size_t bytes);  // to at least `bytes`; new bytes are zero

 private:
  int fd_ = -1;
  std::size_t size_ = 0;
};

// A read-write shared mapping of [offset, offset + bytes) of a SharedMemoryFile; offset page aligned.
class SharedMapping {
 public:
  SharedMapping(const SharedMemoryFile& file, std::uint64_t offset, std::size_t bytes);
  ~SharedMapping();
  SharedMapping(const SharedMapping&) = delete;
  SharedMapping& operator=(const SharedMapping&) = delete;

  void* data() const { return data_; }
  std::size_t size() const { return bytes_; }

 private:
  void* data_ = nullptr;
  std::size_t bytes_ = 0;
};

std::size_t page_size();
inline std::size_t round_up(std::size_t n, std::size_t multiple) { return (n + multiple - 1) / multiple * multiple; }

}  // namespace twinray
