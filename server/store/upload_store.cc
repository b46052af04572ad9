#include "store/upload_store.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstring>
#include <fstream>
#include <sstream>
#include <system_error>
#include <vector>

#include "core/atomic_write.h"
#include "core/sha256.h"
#include "store/atlas_types.h"
#include "store/random_hex.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

constexpr int kIdBytes = 16;
constexpr char kMetaSuffix[] = ".meta";

int64_t SystemMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

bool ParseInt(const std::string& text, int64_t* value) {
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), *value);
  return error == std::errc() && end == text.data() + text.size() && !text.empty();
}

Status NotFound(const std::string& id) {
  return Status::NotFound("upload " + id +
                          " does not exist (it was never begun by you, was used, or expired)");
}

}  // namespace

Status UploadStore::Open(const fs::path& root, std::unique_ptr<UploadStore>* out,
                         std::function<int64_t()> clock) {
  std::error_code ec;
  fs::create_directories(root, ec);
  if (ec) return Status::Io("cannot create " + root.string() + ": " + ec.message());
  if (!clock) clock = SystemMicros;
  out->reset(new UploadStore(root, std::move(clock)));
  (*out)->LoadIndex();
  return Status::Ok();
}

bool UploadStore::IsWellFormedId(std::string_view id) {
  if (id.size() != 2 * kIdBytes) return false;
  for (char c : id) {
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  }
  return true;
}

void UploadStore::LoadIndex() {
  std::lock_guard lock(mutex_);
  open_.clear();
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(root_, ec)) {
    const std::string name = entry.path().filename().string();
    if (!name.ends_with(kMetaSuffix)) continue;
    const std::string id = name.substr(0, name.size() - std::strlen(kMetaSuffix));
    if (!IsWellFormedId(id)) continue;
    std::ifstream meta(entry.path());
    std::string owner, size, sha256, expire;
    std::getline(meta, owner);
    std::getline(meta, size);
    std::getline(meta, sha256);
    std::getline(meta, expire);
    OpenUpload upload{owner, 0, 0};
    // A damaged one counts nothing; Load() reports it when it is used.
    if (ParseInt(size, &upload.size_bytes) && ParseInt(expire, &upload.expire_us)) {
      open_[id] = std::move(upload);
    }
  }
}

Status UploadStore::CheckQuota(const std::string& user, int64_t size_bytes) {
  const int64_t now = clock_();
  int64_t announced = 0;
  int count = 0;
  std::vector<std::string> expired;
  for (const auto& [id, upload] : open_) {
    if (upload.owner != user) continue;
    if (now >= upload.expire_us) {
      expired.push_back(id);
      continue;
    }
    announced += upload.size_bytes;
    ++count;
  }
  for (const std::string& id : expired) RemoveFiles(id);
  if (count >= kMaxOpenUploads) {
    return Status::ResourceExhausted(
        "upload_quota", "you have " + std::to_string(count) + " open uploads, the most one user " +
                            "may hold; finish or discard some (DiscardUpload) first");
  }
  if (quota_bytes_ > 0 && announced + size_bytes > quota_bytes_) {
    return Status::ResourceExhausted(
        "upload_quota", "your open uploads announce " + std::to_string(announced) + " bytes; " +
                            std::to_string(size_bytes) +
                            " more would pass the server's upload quota of " +
                            std::to_string(quota_bytes_) +
                            " bytes per user; finish or discard some (DiscardUpload) first");
  }
  return Status::Ok();
}

void UploadStore::RemoveFiles(const std::string& id) {
  open_.erase(id);
  std::error_code ec;
  fs::remove(root_ / id, ec);
  fs::remove(root_ / (id + kMetaSuffix), ec);
}

Status UploadStore::Load(const std::string& user, const std::string& id, UploadInfo* info,
                         bool data_may_be_gone) {
  if (id.empty()) return Status::InvalidArgument("upload_id", "must not be empty");
  // Checked before the id becomes part of a path.
  if (!IsWellFormedId(id)) return NotFound(id.size() <= 64 ? id : id.substr(0, 64) + "...");
  std::ifstream meta(root_ / (id + kMetaSuffix));
  if (!meta) return NotFound(id);
  std::string owner, size, sha256, expire;
  std::getline(meta, owner);
  std::getline(meta, size);
  std::getline(meta, sha256);
  std::getline(meta, expire);
  // Filled apart from *info: `id` may be info->id.
  UploadInfo loaded;
  loaded.id = id;
  loaded.owner = owner;
  loaded.sha256 = sha256;
  if (!ParseInt(size, &loaded.size_bytes) || !ParseInt(expire, &loaded.expire_us) ||
      !IsSha256Hex(sha256)) {
    return Status::Io("the metadata of upload " + id + " is damaged");
  }
  if (owner != user) return NotFound(id);
  if (clock_() >= loaded.expire_us) {
    RemoveFiles(id);
    return NotFound(id);
  }
  std::error_code ec;
  const auto received = fs::file_size(root_ / id, ec);
  if (ec && !(data_may_be_gone && ec == std::errc::no_such_file_or_directory)) {
    return Status::Io("the data of upload " + id + " is missing: " + ec.message());
  }
  loaded.received_bytes = ec ? 0 : static_cast<int64_t>(received);
  *info = std::move(loaded);
  return Status::Ok();
}

Status UploadStore::Begin(const std::string& user, int64_t size_bytes, const std::string& sha256,
                          UploadInfo* info) {
  PBA_RETURN_IF_ERROR(CheckName("user", user));
  if (size_bytes <= 0 || size_bytes > kMaxUploadBytes) {
    return Status::InvalidArgument("size_bytes", "must be 1 to " + std::to_string(kMaxUploadBytes) +
                                                     " bytes (1 GiB), not " +
                                                     std::to_string(size_bytes));
  }
  if (!IsSha256Hex(sha256)) {
    return Status::InvalidArgument("sha256", "must be 64 lowercase hex characters");
  }
  std::string id;
  PBA_RETURN_IF_ERROR(RandomHex(kIdBytes, &id));
  std::lock_guard lock(mutex_);
  PBA_RETURN_IF_ERROR(CheckQuota(user, size_bytes));
  *info = UploadInfo();
  info->id = id;
  info->owner = user;
  info->size_bytes = size_bytes;
  info->sha256 = sha256;
  info->expire_us = clock_() + kLifetimeMicros;
  // The data file first: a .meta always has its data file.
  const fs::path data = root_ / id;
  const int fd = ::open(data.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) return Status::Io("cannot create " + data.string() + ": " + std::strerror(errno));
  ::close(fd);
  std::ostringstream meta;
  meta << user << "\n" << size_bytes << "\n" << sha256 << "\n" << info->expire_us << "\n";
  const Status written = AtomicWriteText(root_ / (id + kMetaSuffix), meta.str());
  if (written.ok()) {
    open_[id] = OpenUpload{user, size_bytes, info->expire_us};
  } else {
    RemoveFiles(id);
  }
  return written;
}

Status UploadStore::Write(const std::string& user, const std::string& id, int64_t offset,
                          std::string_view data, UploadInfo* info) {
  if (data.size() > kMaxChunkBytes) {
    return Status::InvalidArgument(
        "data", "a chunk holds at most " + std::to_string(kMaxChunkBytes) + " bytes (1 MiB), not " +
                    std::to_string(data.size()));
  }
  std::lock_guard lock(mutex_);
  PBA_RETURN_IF_ERROR(Load(user, id, info));
  if (offset != info->received_bytes) {
    return Status::OutOfRange("offset", std::to_string(offset) +
                                            " is not the received size of upload " + id + ": " +
                                            std::to_string(info->received_bytes) +
                                            " bytes have arrived; send from there");
  }
  if (offset + static_cast<int64_t>(data.size()) > info->size_bytes) {
    return Status::InvalidArgument("data", "the chunk would grow upload " + id + " past its " +
                                               std::to_string(info->size_bytes) +
                                               " announced bytes");
  }
  if (data.empty()) return Status::Ok();
  const fs::path path = root_ / id;
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (fd < 0) return Status::Io("cannot open " + path.string() + ": " + std::strerror(errno));
  size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string error = std::strerror(errno);
      ::close(fd);
      // Cut back to what was there, so the received size stays a chunk boundary.
      std::error_code ec;
      fs::resize_file(path, static_cast<uintmax_t>(offset), ec);
      return Status::Io("cannot write " + path.string() + ": " + error);
    }
    done += static_cast<size_t>(n);
  }
  ::close(fd);
  info->received_bytes += static_cast<int64_t>(data.size());
  return Status::Ok();
}

Status UploadStore::Get(const std::string& user, const std::string& id, UploadInfo* info) {
  std::lock_guard lock(mutex_);
  return Load(user, id, info);
}

Status UploadStore::LoadComplete(const std::string& user, const std::string& id, UploadInfo* info) {
  {
    std::lock_guard lock(mutex_);
    PBA_RETURN_IF_ERROR(Load(user, id, info));
  }
  if (info->received_bytes != info->size_bytes) {
    return Status::FailedPrecondition(
        "upload " + id + " is incomplete: " + std::to_string(info->received_bytes) + " of " +
        std::to_string(info->size_bytes) + " bytes received");
  }
  return Status::Ok();
}

Status UploadStore::Discard(const UploadInfo& info, const std::string& hash) {
  {
    std::lock_guard lock(mutex_);
    RemoveFiles(info.id);
  }
  return Status::InvalidArgument("sha256", "the content of upload " + info.id + " hashes to " +
                                               hash + ", not the announced " + info.sha256 +
                                               "; the upload is discarded, begin again");
}

Status UploadStore::Take(const std::string& user, const std::string& id,
                         std::unique_ptr<MappedFile>* content) {
  UploadInfo info;
  PBA_RETURN_IF_ERROR(LoadComplete(user, id, &info));
  // Mapped and hashed without the mutex (up to 1 GiB: seconds), so other
  // uploads go on meanwhile. A complete upload takes no more writes.
  std::unique_ptr<MappedFile> file;
  PBA_RETURN_IF_ERROR(MappedFile::Open(root_ / id, &file));
  if (static_cast<int64_t>(file->size()) != info.size_bytes) {
    return Status::Io("upload " + id + " changed size while it was being read");
  }
  std::string hash;
  PBA_RETURN_IF_ERROR(file->Sha256Hex(&hash));
  if (hash != info.sha256) return Discard(info, hash);
  *content = std::move(file);
  return Status::Ok();
}

Status UploadStore::Take(const std::string& user, const std::string& id, std::string* content) {
  content->clear();
  UploadInfo info;
  PBA_RETURN_IF_ERROR(LoadComplete(user, id, &info));
  std::ifstream in(root_ / id, std::ios::binary);
  content->assign(static_cast<size_t>(info.size_bytes), '\0');
  if (!in.read(content->data(), info.size_bytes)) {
    content->clear();
    return Status::Io("cannot read upload " + id);
  }
  const std::string hash = Sha256Hex(*content);
  if (hash != info.sha256) {
    content->clear();
    return Discard(info, hash);
  }
  return Status::Ok();
}

Status UploadStore::Remove(const std::string& user, const std::string& id) {
  std::lock_guard lock(mutex_);
  UploadInfo info;
  const Status loaded = Load(user, id, &info, /*data_may_be_gone=*/true);
  if (loaded.code() == Status::Code::kNotFound) return Status::Ok();
  PBA_RETURN_IF_ERROR(loaded);
  RemoveFiles(id);
  return Status::Ok();
}

Status UploadStore::Sweep(int* removed) {
  *removed = 0;
  std::lock_guard lock(mutex_);
  const int64_t now = clock_();
  std::error_code ec;
  std::vector<fs::path> doomed;
  for (const fs::directory_entry& entry : fs::directory_iterator(root_, ec)) {
    const std::string name = entry.path().filename().string();
    std::string id = name;
    const bool is_meta = name.size() > std::strlen(kMetaSuffix) && name.ends_with(kMetaSuffix);
    if (is_meta) id = name.substr(0, name.size() - std::strlen(kMetaSuffix));
    if (!IsWellFormedId(id)) {
      // Temporary files of an interrupted atomic write, or strangers.
      if (name.starts_with(".")) doomed.push_back(entry.path());
      continue;
    }
    if (is_meta) {
      std::ifstream meta(entry.path());
      std::string line;
      int64_t expire = 0;
      for (int i = 0; i < 4; ++i) std::getline(meta, line);
      if (!ParseInt(line, &expire) || now >= expire || !fs::exists(root_ / id)) {
        doomed.push_back(entry.path());
        doomed.push_back(root_ / id);
      }
    } else if (!fs::exists(root_ / (id + kMetaSuffix))) {
      doomed.push_back(entry.path());
    }
  }
  if (ec) return Status::Io("cannot list " + root_.string() + ": " + ec.message());
  for (const fs::path& path : doomed) {
    std::string id = path.filename().string();
    if (id.ends_with(kMetaSuffix)) id.resize(id.size() - std::strlen(kMetaSuffix));
    open_.erase(id);
    if (fs::remove(path, ec)) ++*removed;
    if (ec) return Status::Io("cannot remove " + path.string() + ": " + ec.message());
  }
  return Status::Ok();
}

}  // namespace pba
