// MappedFile: a whole file mapped read-only, so that large uploads and blobs
// are checked and hashed without a heap copy of their bytes (an upload may be
// 1 GiB). The mapping keeps its own descriptor, so the file may be renamed or
// unlinked while it is open and the bytes stay readable.
//
// Hashing releases each window of pages from the process once it is hashed
// (madvise MADV_DONTNEED on a read-only file mapping only drops this
// process's reference: the bytes stay in the page cache and are read back if
// touched again), so hashing a large file does not leave it all counted in
// the server's resident set.
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "pba/status.h"

namespace pba {

class MappedFile {
 public:
  // Maps `path` read-only. An empty file maps to an empty view.
  static Status Open(const std::filesystem::path& path, std::unique_ptr<MappedFile>* out);

  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  ~MappedFile();

  std::string_view bytes() const { return {static_cast<const char*>(data_), size_}; }
  size_t size() const { return size_; }
  int fd() const { return fd_; }
  // Where the file was when it was opened.
  const std::filesystem::path& path() const { return path_; }

  // Lowercase hex SHA-256 of the content, hashed window by window.
  Status Sha256Hex(std::string* hex) const;

 private:
  MappedFile(std::filesystem::path path, int fd, void* data, size_t size)
      : path_(std::move(path)), fd_(fd), data_(data), size_(size) {}

  const std::filesystem::path path_;
  const int fd_;
  void* const data_;
  const size_t size_;
};

// The SHA-256 of a file's content through a mapping (MappedFile::Sha256Hex).
Status Sha256HexOfFile(const std::filesystem::path& path, std::string* hex);

}  // namespace pba
