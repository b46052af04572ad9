#include "store/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

namespace pba {
namespace fs = std::filesystem;

Status WriteFileAtomically(const fs::path& path, std::string_view content) {
  // Built with append(): GCC 12 warns falsely (-Wrestrict) on "." + string.
  std::string temp_name = ".";
  temp_name.append(path.filename().string()).append(".tmp-").append(std::to_string(::getpid()));
  const fs::path temp = path.parent_path() / temp_name;
  const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return Status::Io("cannot create " + temp.string() + ": " + std::strerror(errno));
  size_t written = 0;
  while (written < content.size()) {
    const ssize_t n = ::write(fd, content.data() + written, content.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const std::string error = std::strerror(errno);
      ::close(fd);
      ::unlink(temp.c_str());
      return Status::Io("cannot write " + temp.string() + ": " + error);
    }
    written += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string error = std::strerror(errno);
    ::unlink(temp.c_str());
    return Status::Io("cannot flush " + temp.string() + ": " + error);
  }
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    const std::string error = std::strerror(errno);
    ::unlink(temp.c_str());
    return Status::Io("cannot rename " + temp.string() + " to " + path.string() + ": " + error);
  }
  // The rename is only durable once the directory entry is.
  SyncDirectory(path.parent_path());
  return Status::Ok();
}

void SyncDirectory(const std::filesystem::path& dir) {
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace pba
