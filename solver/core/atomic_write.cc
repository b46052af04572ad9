#include "core/atomic_write.h"

#include <fcntl.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace pba {
namespace fs = std::filesystem;

Status AtomicWrite(const fs::path& file, const std::string& suffix,
                   const std::function<Status(int, const std::string&)>& write) {
  const fs::path dir = file.parent_path().empty() ? fs::path(".") : file.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return Status::Io(dir.string() + " is not a directory");
  std::string temporary =
      (dir / ("." + file.filename().string() + ".partial-XXXXXX" + suffix)).string();
  const int fd = mkstemps(temporary.data(), static_cast<int>(suffix.size()));
  if (fd < 0) return Status::Io("cannot create a temporary file in " + dir.string());
  Status status = write(fd, temporary);
  if (status.ok() && fsync(fd) != 0) status = Status::Io("cannot sync " + temporary);
  if (close(fd) != 0 && status.ok()) status = Status::Io("cannot close " + temporary);
  if (status.ok() && std::rename(temporary.c_str(), file.c_str()) != 0) {
    status = Status::Io("cannot rename " + temporary + " to " + file.string());
  }
  if (!status.ok()) {
    unlink(temporary.c_str());
    return status;
  }
  SyncDirectory(dir);
  return Status::Ok();
}

void SyncDirectory(const fs::path& dir) {
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

bool IsAtomicWriteTemporary(std::string_view name) {
  constexpr std::string_view kMark = ".partial-";
  if (name.size() < 2 || name[0] != '.') return false;
  const size_t mark = name.rfind(kMark);
  return mark != std::string_view::npos && mark > 1 &&
         name.size() >= mark + kMark.size() + 6;  // mkstemps's six characters
}

Status WriteAll(int fd, const void* data, std::size_t size, const std::string& path) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return Status::Io("writing " + path + " failed: " + std::strerror(errno));
    p += n;
    size -= static_cast<std::size_t>(n);
  }
  return Status::Ok();
}

Status AtomicWriteText(const fs::path& file, std::string_view text, unsigned mode) {
  return AtomicWrite(file, "", [&](int fd, const std::string& temporary) {
    if (mode != 0600 && ::fchmod(fd, mode) != 0) {
      return Status::Io("cannot set the mode of " + temporary + ": " + std::strerror(errno));
    }
    return WriteAll(fd, text.data(), text.size(), temporary);
  });
}

Status AtomicWriteDirectory(const std::filesystem::path& dir,
                            const std::function<Status(const std::filesystem::path&)>& fill) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(dir, ec) && !(fs::is_directory(dir, ec) && fs::is_empty(dir, ec))) {
    return Status::Io(dir.string() + " already exists and is not an empty directory");
  }
  const fs::path target = dir.has_filename() ? dir : dir.parent_path();
  const fs::path parent = target.parent_path().empty() ? fs::path(".") : target.parent_path();
  if (!fs::is_directory(parent, ec)) return Status::Io(parent.string() + " is not a directory");
  std::string pattern = (parent / ("." + target.filename().string() + ".partial-XXXXXX")).string();
  if (::mkdtemp(pattern.data()) == nullptr) {
    return Status::Io("cannot create a temporary directory in " + parent.string());
  }
  const fs::path temporary = pattern;
  Status status = fill(temporary);
  if (status.ok()) {
    // The entries first, then the name: a crash leaves the whole directory
    // or a temporary one that sweeps recognise.
    SyncDirectory(temporary);
    fs::rename(temporary, target, ec);  // replaces an empty directory
    if (ec) status = Status::Io("cannot rename into " + target.string() + ": " + ec.message());
  }
  if (!status.ok()) {
    fs::remove_all(temporary, ec);
    return status;
  }
  SyncDirectory(parent);
  return status;
}

}  // namespace pba
