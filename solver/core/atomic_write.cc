#include "core/atomic_write.h"

#include <fcntl.h>
#include <stdio.h>  // renameat2
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace pba {
namespace fs = std::filesystem;
namespace {

fs::path DirectoryOf(const fs::path& file) {
  return file.parent_path().empty() ? fs::path(".") : file.parent_path();
}

// rename(2), or with `never_replace` a rename that fails with EEXIST when
// anything is at `to`; 0 or the errno of the failure.
int Rename(const fs::path& from, const fs::path& to, bool never_replace) {
  if (!never_replace) return std::rename(from.c_str(), to.c_str()) == 0 ? 0 : errno;
  if (::renameat2(AT_FDCWD, from.c_str(), AT_FDCWD, to.c_str(), RENAME_NOREPLACE) == 0) return 0;
  if (errno != EINVAL && errno != ENOSYS) return errno;
  // A file system without RENAME_NOREPLACE: link() refuses an existing
  // name too, and the source is then unlinked.
  if (::link(from.c_str(), to.c_str()) != 0) return errno;
  ::unlink(from.c_str());
  return 0;
}

// Moves whatever is at `target` to a new hidden name beside it (*aside).
Status MoveAside(const fs::path& target, fs::path* aside) {
  const fs::path parent = DirectoryOf(target);
  std::error_code ec;
  const bool directory = fs::is_directory(fs::symlink_status(target, ec));
  // The name is reserved with an entry of the same kind, which the rename
  // then replaces: a directory over an empty directory, a file over a file.
  std::string reserved = (parent / ("." + target.filename().string() + ".old-XXXXXX")).string();
  if (directory) {
    if (::mkdtemp(reserved.data()) == nullptr) {
      return Status::Io("cannot replace " + target.string() + ": " + std::strerror(errno));
    }
  } else {
    const int fd = ::mkstemp(reserved.data());
    if (fd < 0) {
      return Status::Io("cannot replace " + target.string() + ": " + std::strerror(errno));
    }
    ::close(fd);
  }
  fs::rename(target, reserved, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(reserved, ignored);
    return Status::Io("cannot replace " + target.string() + ": " + ec.message());
  }
  *aside = reserved;
  return Status::Ok();
}

}  // namespace

Status AtomicWrite(const fs::path& file, const std::string& suffix,
                   const std::function<Status(int, const std::string&)>& write,
                   const AtomicWriteOptions& options) {
  const fs::path dir = DirectoryOf(file);
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return Status::Io(dir.string() + " is not a directory");
  std::string temporary =
      (dir / ("." + file.filename().string() + ".partial-XXXXXX" + suffix)).string();
  const int fd = mkstemps(temporary.data(), static_cast<int>(suffix.size()));
  if (fd < 0) return Status::Io("cannot create a temporary file in " + dir.string());
  Status status = Status::Ok();
  // mkstemps made it 0600.
  if (options.mode != 0600 && ::fchmod(fd, options.mode) != 0) {
    status = Status::Io("cannot set the mode of " + temporary + ": " + std::strerror(errno));
  }
  if (status.ok()) status = write(fd, temporary);
  if (status.ok() && fsync(fd) != 0) status = Status::Io("cannot sync " + temporary);
  if (close(fd) != 0 && status.ok()) status = Status::Io("cannot close " + temporary);
  if (status.ok()) {
    const int error = Rename(temporary, file, options.never_replace);
    if (error == EEXIST && options.never_replace) {
      status = Status::AlreadyExists(file.string() + " already exists");
    } else if (error != 0) {
      status = Status::Io("cannot rename " + temporary + " to " + file.string());
    }
  }
  if (!status.ok()) {
    unlink(temporary.c_str());
    return status;
  }
  SyncDirectory(dir);
  return Status::Ok();
}

Status MoveIntoPlace(const fs::path& from, const fs::path& to, bool never_replace) {
  const int error = Rename(from, to, never_replace);
  if (error == EEXIST && never_replace) {
    return Status::AlreadyExists(to.string() + " already exists");
  }
  if (error != 0) {
    return Status::Io("cannot move " + to.string() + " into place: " + std::strerror(error));
  }
  SyncDirectory(DirectoryOf(to));
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
  AtomicWriteOptions options;
  options.mode = mode;
  return AtomicWriteText(file, text, options);
}

Status AtomicWriteText(const fs::path& file, std::string_view text,
                       const AtomicWriteOptions& options) {
  return AtomicWrite(
      file, "",
      [&](int fd, const std::string& temporary) {
        return WriteAll(fd, text.data(), text.size(), temporary);
      },
      options);
}

Status AtomicWriteDirectory(const fs::path& dir, const std::function<Status(const fs::path&)>& fill,
                            bool replace) {
  std::error_code ec;
  if (!replace && fs::exists(dir, ec) && !(fs::is_directory(dir, ec) && fs::is_empty(dir, ec))) {
    return Status::Io(dir.string() + " already exists and is not an empty directory");
  }
  const fs::path target = dir.has_filename() ? dir : dir.parent_path();
  const fs::path parent = DirectoryOf(target);
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
    status = MoveDirectoryIntoPlace(temporary, target, replace);
  }
  if (!status.ok()) fs::remove_all(temporary, ec);
  return status;
}

Status MoveDirectoryIntoPlace(const fs::path& filled, const fs::path& dir, bool replace) {
  const fs::path target = dir.has_filename() ? dir : dir.parent_path();
  std::error_code ec;
  fs::path old;
  if (replace && fs::symlink_status(target, ec).type() != fs::file_type::not_found) {
    PBA_RETURN_IF_ERROR(MoveAside(target, &old));
  }
  fs::rename(filled, target, ec);  // replaces an empty directory
  if (ec) {
    std::error_code ignored;
    if (!old.empty()) fs::rename(old, target, ignored);
    return Status::Io("cannot move " + target.string() + " into place: " + ec.message());
  }
  SyncDirectory(DirectoryOf(target));
  if (!old.empty()) fs::remove_all(old, ec);
  return Status::Ok();
}

}  // namespace pba
