#include "transfer.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "core/atomic_write.h"
#include "exit_codes.h"
#include "files.h"

namespace pba::cli {
namespace fs = std::filesystem;

Progress::Progress(std::string what, int64_t total)
    : what_(std::move(what)), total_(total), shown_(::isatty(STDERR_FILENO) != 0) {}

Progress::~Progress() {
  if (shown_ && total_ > 0) std::fputc('\n', stderr);
}

void Progress::Update(int64_t done) {
  if (!shown_ || total_ <= 0) return;
  std::fprintf(
      stderr, "\r\033[K%s: %3d %%", what_.c_str(),
      static_cast<int>(100.0 * static_cast<double>(done) / static_cast<double>(total_) + 0.5));
}

namespace {

// Writes all of `data` to `fd`; false on a failure (errno kept).
bool WriteAll(int fd, const std::string& data) {
  size_t written = 0;
  while (written < data.size()) {
    const ssize_t n = ::write(fd, data.data() + written, data.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    written += static_cast<size_t>(n);
  }
  return true;
}

// Closes a descriptor when it goes out of scope.
class FdCloser {
 public:
  explicit FdCloser(int fd) : fd_(fd) {}
  ~FdCloser() {
    if (fd_ >= 0) ::close(fd_);
  }
  FdCloser(const FdCloser&) = delete;
  FdCloser& operator=(const FdCloser&) = delete;
  // Closes now; false when close() reports a failure (a delayed write error).
  bool Close() {
    const int fd = fd_;
    fd_ = -1;
    return ::close(fd) == 0;
  }

 private:
  int fd_;
};

}  // namespace

int DownloadTo(Connection& connection, const fs::path& target, int64_t size,
               const std::string& sha256, const std::string& what, bool overwrite,
               const std::function<ChunkStream(grpc::ClientContext*, int64_t offset)>& open) {
  struct stat info;
  if (!overwrite && ::lstat(target.c_str(), &info) == 0) {
    std::fprintf(stderr, "pba: %s already exists; not overwriting it (pass --force to)\n",
                 target.c_str());
    return kExitConflict;
  }
  const fs::path part = target.string() + ".part";
  // O_NOFOLLOW: a .part planted as a link to another file must not have
  // the download appended to that file.
  const int fd = ::open(part.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) {
    if (errno == ELOOP) {
      std::fprintf(stderr, "pba: %s is a symbolic link; not writing through it\n", part.c_str());
    } else {
      std::fprintf(stderr, "pba: cannot write %s: %s\n", part.c_str(), std::strerror(errno));
    }
    return kExitError;
  }
  FdCloser closer(fd);
  if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode)) {
    std::fprintf(stderr, "pba: %s is not a regular file; not writing into it\n", part.c_str());
    return kExitError;
  }
  // A .part an interrupted download left is resumed where it stopped.
  int64_t offset = static_cast<int64_t>(info.st_size);
  if (offset > size) {
    if (::ftruncate(fd, 0) != 0) {
      std::fprintf(stderr, "pba: cannot truncate %s: %s\n", part.c_str(), std::strerror(errno));
      return kExitError;
    }
    offset = 0;
  }
  Progress progress("downloading " + what, size);
  auto context = connection.StreamContext();
  ChunkStream reader = open(context.get(), offset);
  v1::DataChunk chunk;
  bool written = true;
  while (written && reader->Read(&chunk)) {
    if (chunk.offset() != offset) {
      std::fprintf(stderr, "pba: %s: chunk at byte %lld, expected %lld\n", what.c_str(),
                   static_cast<long long>(chunk.offset()), static_cast<long long>(offset));
      context->TryCancel();
      return kExitError;
    }
    written = WriteAll(fd, chunk.data());
    offset += static_cast<int64_t>(chunk.data().size());
    progress.Update(offset);
  }
  if (!written) context->TryCancel();
  grpc::Status status = reader->Finish();
  // Whole: synced before it gets its name, which a crash must not outlive.
  if (written && status.ok() && ::fsync(fd) != 0) written = false;
  written = closer.Close() && written;
  if (!written) {
    std::fprintf(stderr, "pba: writing %s failed (disk full?)\n", part.c_str());
    return kExitError;
  }
  if (!status.ok()) return connection.Fail("downloading " + what, status);
  std::error_code ec;
  if (!sha256.empty() && Sha256File(part) != sha256) {
    fs::remove(part, ec);
    std::fprintf(stderr, "pba: %s arrived damaged (checksum mismatch); run the command again\n",
                 what.c_str());
    return kExitError;
  }
  // A rename replaces a link at `target` itself, never the file it points to.
  const Status moved = MoveIntoPlace(part, target, /*never_replace=*/!overwrite);
  if (moved.code() == Status::Code::kAlreadyExists) {
    std::fprintf(stderr,
                 "pba: %s appeared while it was downloading; not overwriting it (pass --force "
                 "to); the download is in %s\n",
                 target.c_str(), part.c_str());
    return kExitConflict;
  }
  if (!moved.ok()) {
    std::fprintf(stderr, "pba: %s\n", moved.message().c_str());  // cannot move ... into place
    return kExitError;
  }
  return kExitOk;
}

}  // namespace pba::cli
