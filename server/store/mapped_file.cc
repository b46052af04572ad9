#include "store/mapped_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "core/sha256.h"

namespace pba {
namespace {

// Hashed (and then released) this much at a time: large enough that the
// madvise calls cost nothing, small enough to bound what hashing keeps
// resident.
constexpr size_t kWindowBytes = size_t{16} << 20;

}  // namespace

Status MappedFile::Open(const std::filesystem::path& path, std::unique_ptr<MappedFile>* out) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Status::Io("cannot open " + path.string() + ": " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const std::string error = std::strerror(errno);
    ::close(fd);
    return Status::Io("cannot stat " + path.string() + ": " + error);
  }
  const size_t size = static_cast<size_t>(st.st_size);
  void* data = nullptr;
  if (size > 0) {
    data = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
    if (data == MAP_FAILED) {
      const std::string error = std::strerror(errno);
      ::close(fd);
      return Status::Io("cannot map " + path.string() + ": " + error);
    }
    // Read front to back by the hash and most checks: let the kernel read ahead.
    ::madvise(data, size, MADV_SEQUENTIAL);
  }
  out->reset(new MappedFile(path, fd, data, size));
  return Status::Ok();
}

MappedFile::~MappedFile() {
  if (data_ != nullptr) ::munmap(data_, size_);
  ::close(fd_);
}

Status MappedFile::Sha256Hex(std::string* hex) const {
  pba::Sha256 sha;
  char* const base = static_cast<char*>(data_);
  for (size_t offset = 0; offset < size_; offset += kWindowBytes) {
    const size_t length = std::min(kWindowBytes, size_ - offset);
    if (!sha.Update(base + offset, length)) break;  // Finish reports it
    // Windows start at multiples of kWindowBytes, so page-aligned.
    ::madvise(base + offset, length, MADV_DONTNEED);
  }
  Sha256Digest digest{};
  PBA_RETURN_IF_ERROR(sha.Finish(&digest));
  *hex = HexOf(digest);
  return Status::Ok();
}

Status Sha256HexOfFile(const std::filesystem::path& path, std::string* hex) {
  std::unique_ptr<MappedFile> file;
  PBA_RETURN_IF_ERROR(MappedFile::Open(path, &file));
  return file->Sha256Hex(hex);
}

}  // namespace pba
