#include "solve/staging_dir.h"

#include <fcntl.h>
#include <unistd.h>

#include <string>
#include <system_error>

#include "core/atomic_write.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

bool FsyncPath(const fs::path& path, bool directory) {
  const int fd = ::open(path.c_str(), (directory ? O_RDONLY | O_DIRECTORY : O_RDONLY) | O_CLOEXEC);
  if (fd < 0) return false;
  const bool ok = ::fsync(fd) == 0;
  ::close(fd);
  return ok;
}

std::string Hidden(const fs::path& destination, const char* what) {
  return "." + destination.filename().string() + "." + what + "-" + std::to_string(::getpid());
}

}  // namespace

Status CheckOutputDir(const fs::path& out, bool force, const std::string& tool,
                      const OutputEntryTest& ours) {
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(out, ec);
  if (status.type() == fs::file_type::not_found) return Status::Ok();
  if (fs::is_symlink(status)) {
    return Status::InvalidArgument("--out", out.string() + " is a symbolic link; " + tool +
                                                " writes a new directory there, so name one "
                                                "that does not exist");
  }
  if (!fs::is_directory(status)) {
    return Status::InvalidArgument(
        "--out", out.string() + " is a file, not a directory " + tool +
                     " wrote; not replacing it (name a directory that does not exist)");
  }
  std::string foreign;
  bool empty = true;
  for (const fs::directory_entry& entry : fs::directory_iterator(out, ec)) {
    empty = false;
    if (!ours(entry)) {
      foreign = entry.path().filename().string();
      break;
    }
  }
  if (ec) return Status::Io("cannot list " + out.string() + ": " + ec.message());
  if (empty) return Status::Ok();
  if (!foreign.empty()) {
    return Status::InvalidArgument("--out", out.string() + " holds '" + foreign + "', which " +
                                                tool +
                                                " did not write; not replacing the directory, "
                                                "even with --force (name a new one)");
  }
  if (!force) {
    return Status::InvalidArgument("--out", out.string() + " holds an earlier " + tool +
                                                " result; pass --force to replace it, or name a "
                                                "new directory");
  }
  return Status::Ok();
}

Status StagingDir::Create(const fs::path& destination, StagingDir* out) {
  fs::path dest = fs::absolute(destination).lexically_normal();
  if (dest.filename().empty()) dest = dest.parent_path();
  std::error_code ec;
  fs::create_directories(dest.parent_path(), ec);
  if (ec) return Status::Io("cannot create " + dest.parent_path().string() + ": " + ec.message());
  StagingDir staging;
  staging.destination_ = dest;
  staging.staging_ = dest.parent_path() / Hidden(dest, "partial");
  fs::remove_all(staging.staging_, ec);
  if (!fs::create_directory(staging.staging_, ec) || ec) {
    return Status::Io("cannot create " + staging.staging_.string() + ": " +
                      (ec ? ec.message() : "already exists"));
  }
  *out = std::move(staging);
  return Status::Ok();
}

StagingDir::StagingDir(StagingDir&& other) noexcept { *this = std::move(other); }

StagingDir& StagingDir::operator=(StagingDir&& other) noexcept {
  if (this != &other) {
    Discard();
    destination_ = std::move(other.destination_);
    staging_ = std::move(other.staging_);
    committed_ = other.committed_;
    other.staging_.clear();
  }
  return *this;
}

StagingDir::~StagingDir() { Discard(); }

void StagingDir::Discard() {
  if (!committed_ && !staging_.empty()) {
    std::error_code ec;
    fs::remove_all(staging_, ec);
  }
  staging_.clear();
}

Status StagingDir::Commit() {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(staging_, ec)) {
    if (!FsyncPath(entry.path(), entry.is_directory())) {
      return Status::Io("cannot flush " + entry.path().string() + " to disk");
    }
  }
  if (ec) return Status::Io("cannot list " + staging_.string() + ": " + ec.message());
  if (!FsyncPath(staging_, true)) return Status::Io("cannot flush " + staging_.string());

  // An older result is moved aside first, so the destination never holds a
  // mix, and put back when the new one cannot be moved in.
  PBA_RETURN_IF_ERROR(MoveDirectoryIntoPlace(staging_, destination_, /*replace=*/true));
  committed_ = true;
  staging_ = destination_;
  return Status::Ok();
}

}  // namespace pba
