#include "store/mapped_file.h"

#include <fcntl.h>
#include <openssl/evp.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "store/sha256.h"

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
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> context(EVP_MD_CTX_new(),
                                                                  EVP_MD_CTX_free);
  if (!context || EVP_DigestInit_ex(context.get(), EVP_sha256(), nullptr) != 1) {
    return Status::Internal("cannot compute SHA-256");
  }
  char* const base = static_cast<char*>(data_);
  for (size_t offset = 0; offset < size_; offset += kWindowBytes) {
    const size_t length = std::min(kWindowBytes, size_ - offset);
    if (EVP_DigestUpdate(context.get(), base + offset, length) != 1) {
      return Status::Internal("cannot compute SHA-256");
    }
    // Windows start at multiples of kWindowBytes, so page-aligned.
    ::madvise(base + offset, length, MADV_DONTNEED);
  }
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_DigestFinal_ex(context.get(), digest, &length) != 1) {
    return Status::Internal("cannot compute SHA-256");
  }
  *hex = HexOf(digest, length);
  return Status::Ok();
}

Status Sha256HexOfFile(const std::filesystem::path& path, std::string* hex) {
  std::unique_ptr<MappedFile> file;
  PBA_RETURN_IF_ERROR(MappedFile::Open(path, &file));
  return file->Sha256Hex(hex);
}

}  // namespace pba
