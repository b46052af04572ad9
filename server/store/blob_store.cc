#include "store/blob_store.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <system_error>
#include <vector>

#include "core/atomic_write.h"
#include "core/sha256.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

Status CheckHash(const std::string& hash) {
  if (!IsSha256Hex(hash)) {
    return Status::InvalidArgument("hash", "'" + hash + "' is not a lowercase hex SHA-256");
  }
  return Status::Ok();
}

bool IsLowerHex(char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); }

// The fan-out directories: two lowercase hex characters.
bool IsFanOutName(const std::string& name) {
  return name.size() == 2 && IsLowerHex(name[0]) && IsLowerHex(name[1]);
}

// AtomicWriteText's temporary files, and ".<name>.tmp-<pid>", the names an
// earlier version of the store gave them (a data directory may still hold
// one from a crash).
bool IsTempName(const std::string& name) {
  return IsAtomicWriteTemporary(name) ||
         (!name.empty() && name[0] == '.' && name.find(".tmp-") != std::string::npos);
}

}  // namespace

Status BlobStore::Open(const fs::path& root, std::unique_ptr<BlobStore>* out) {
  std::error_code ec;
  fs::create_directories(root, ec);
  if (ec) return Status::Io("cannot create " + root.string() + ": " + ec.message());
  out->reset(new BlobStore(root));
  return Status::Ok();
}

fs::path BlobStore::PathOf(const std::string& hash) const {
  return root_ / hash.substr(0, 2) / hash.substr(2);
}

Status BlobStore::ReadVerified(const std::string& hash, std::string* bytes, bool* intact) {
  const fs::path path = PathOf(hash);
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Io("cannot open blob " + hash + " (" + path.string() + ")");
  std::ostringstream content;
  content << in.rdbuf();
  if (in.bad()) return Status::Io("cannot read blob " + hash + " (" + path.string() + ")");
  *bytes = std::move(content).str();
  *intact = Sha256Hex(*bytes) == hash;
  return Status::Ok();
}

Status BlobStore::Put(std::string_view bytes, std::string* hash) {
  const std::string computed = Sha256Hex(bytes);
  std::lock_guard lock(mutex_);
  const fs::path path = PathOf(computed);
  std::error_code ec;
  if (StoredIntact(computed)) {
    *hash = std::move(computed);
    return Status::Ok();
  }
  fs::create_directories(path.parent_path(), ec);
  if (ec) return Status::Io("cannot create " + path.parent_path().string() + ": " + ec.message());
  PBA_RETURN_IF_ERROR(AtomicWriteText(path, bytes));
  *hash = std::move(computed);
  return Status::Ok();
}

bool BlobStore::StoredIntact(const std::string& hash) {
  // Hashing the stored copy is cheaper than a second fsynced write, and it
  // repairs a copy damaged on disk instead of trusting the name. Through a
  // mapping: a blob may be 1 GiB.
  std::error_code ec;
  if (!fs::exists(PathOf(hash), ec)) return false;
  std::string actual;
  return Sha256HexOfFile(PathOf(hash), &actual).ok() && actual == hash;
}

Status BlobStore::PutFile(const MappedFile& file, std::string* hash) {
  std::string computed;
  PBA_RETURN_IF_ERROR(file.Sha256Hex(&computed));
  std::lock_guard lock(mutex_);
  if (StoredIntact(computed)) {
    *hash = std::move(computed);
    return Status::Ok();
  }
  const fs::path path = PathOf(computed);
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  if (ec) return Status::Io("cannot create " + path.parent_path().string() + ": " + ec.message());
  // The upload's chunks were written without fsync: the content must be on
  // disk before any name says it is there. Blobs, like every file of the
  // data directory, are the server user's alone (0600): geometry may be
  // unpublished work (docs/design.md, "Trust boundaries").
  if (::fsync(file.fd()) != 0) {
    return Status::Io("cannot flush " + file.path().string() + ": " + std::strerror(errno));
  }
  ::fchmod(file.fd(), 0600);
  // The path must still name the file that was hashed: a name is only ever
  // given to bytes whose hash was checked. Otherwise (never seen: uploads
  // are created exclusively and only appended to) the checked bytes are
  // copied from the mapping.
  struct stat mapped {};
  struct stat named {};
  const bool same_file = ::fstat(file.fd(), &mapped) == 0 &&
                         ::stat(file.path().c_str(), &named) == 0 &&
                         mapped.st_dev == named.st_dev && mapped.st_ino == named.st_ino;
  if (!same_file || ::rename(file.path().c_str(), path.c_str()) != 0) {
    if (same_file && errno != EXDEV) {
      return Status::Io("cannot move " + file.path().string() + " to " + path.string() + ": " +
                        std::strerror(errno));
    }
    // Across file systems a rename cannot move it: a copy, as Put() writes.
    PBA_RETURN_IF_ERROR(AtomicWriteText(path, file.bytes()));
  } else {
    SyncDirectory(path.parent_path());
    SyncDirectory(file.path().parent_path());
  }
  *hash = std::move(computed);
  return Status::Ok();
}

Status BlobStore::Get(const std::string& hash, std::string* bytes) {
  PBA_RETURN_IF_ERROR(CheckHash(hash));
  std::lock_guard lock(mutex_);
  std::error_code ec;
  if (!fs::exists(PathOf(hash), ec)) return Status::NotFound("blob " + hash + " does not exist");
  bool intact = false;
  PBA_RETURN_IF_ERROR(ReadVerified(hash, bytes, &intact));
  if (!intact) {
    const size_t size = bytes->size();
    bytes->clear();
    return Status::Io("blob " + hash + " is damaged: its " + std::to_string(size) +
                      " bytes on disk do not hash to its name");
  }
  return Status::Ok();
}

Status BlobStore::Has(const std::string& hash, bool* has) {
  PBA_RETURN_IF_ERROR(CheckHash(hash));
  std::lock_guard lock(mutex_);
  std::error_code ec;
  *has = fs::is_regular_file(PathOf(hash), ec);
  if (ec && ec != std::errc::no_such_file_or_directory) {
    return Status::Io("cannot stat blob " + hash + ": " + ec.message());
  }
  return Status::Ok();
}

Status BlobStore::Sweep(const std::set<std::string>& referenced, BlobSweepReport* report) {
  *report = BlobSweepReport();
  std::lock_guard lock(mutex_);
  std::vector<fs::path> doomed_blobs;
  std::vector<fs::path> doomed_temps;
  std::error_code ec;
  fs::directory_iterator dirs(root_, ec);
  for (; !ec && dirs != fs::directory_iterator(); dirs.increment(ec)) {
    const fs::path& dir = dirs->path();
    const std::string dir_name = dir.filename().string();
    std::error_code type_ec;
    if (!fs::is_directory(dir, type_ec) || !IsFanOutName(dir_name)) {
      // Anything else that is not a temporary file is not ours: it is left
      // for a person to look at.
      if (IsTempName(dir_name)) doomed_temps.push_back(dir);
      continue;
    }
    std::error_code files_ec;
    fs::directory_iterator files(dir, files_ec);
    for (; !files_ec && files != fs::directory_iterator(); files.increment(files_ec)) {
      const std::string name = files->path().filename().string();
      if (IsTempName(name)) {
        doomed_temps.push_back(files->path());
      } else if (IsSha256Hex(dir_name + name)) {
        if (referenced.count(dir_name + name) > 0) {
          ++report->kept_blobs;
        } else {
          doomed_blobs.push_back(files->path());
        }
      }
    }
    if (files_ec) return Status::Io("cannot list " + dir.string() + ": " + files_ec.message());
  }
  if (ec) return Status::Io("cannot list " + root_.string() + ": " + ec.message());
  for (const fs::path& path : doomed_blobs) {
    std::error_code size_ec;
    const uintmax_t size = fs::file_size(path, size_ec);
    if (!fs::remove(path, ec) || ec) {
      return Status::Io("cannot remove " + path.string() + ": " + ec.message());
    }
    ++report->removed_blobs;
    if (!size_ec) report->removed_bytes += static_cast<int64_t>(size);
  }
  for (const fs::path& path : doomed_temps) {
    if (!fs::remove(path, ec) || ec) {
      return Status::Io("cannot remove " + path.string() + ": " + ec.message());
    }
    ++report->removed_temp_files;
  }
  return Status::Ok();
}

}  // namespace pba
