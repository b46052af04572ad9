// UploadStore: resumable uploads of geometry, the files under <data>/uploads
// that the atlas service fills chunk by chunk before a structure is created
// or committed from them (proto pba.v1.AtlasService, BeginUpload..).
//
// An upload is two files named by its id (32 random lowercase hex
// characters, checked before any path is built, so an id from a client can
// never name another file): <id> holds the bytes received so far and
// <id>.meta (written atomically at Begin) the owner, announced size,
// announced SHA-256 and expiry. The received size is the data file's size,
// so an upload survives a server restart. Chunks are appended in order
// without fsync: a crash may lose the tail (the client resumes from the
// received size GetUpload reports) or, on some file systems, leave garbage
// in it, which the hash check at Take() catches.
//
// An upload belongs to the user who began it; anyone else is told it does
// not exist. It expires kLifetime after Begin (fixed, not extended by
// writes); expired uploads are removed by Sweep() (the server runs it at
// start) and whenever one is touched.
//
// Refusals: kInvalidArgument naming the field; an out-of-order chunk is
// kInvalidArgument with field "offset" (the service reports it as
// OUT_OF_RANGE: pba::Status has no such code); an unknown, foreign or
// expired upload kNotFound; an incomplete one at Take() kFailedPrecondition;
// content whose hash is not the announced one kInvalidArgument (field
// "sha256"), after which the upload is removed (it can never succeed).
//
// Quota: a user's open uploads (begun, not yet removed or expired) may
// announce at most quota_bytes() together (0: no quota) and number at most
// kMaxOpenUploads; a Begin past either is refused before any file is made,
// as kFailedPrecondition with field "upload_quota" (the service reports it
// as RESOURCE_EXHAUSTED). The store keeps an index of open uploads in
// memory, read from the .meta files at Open(), so the check costs no disk
// scan; expired uploads leave it when they are touched, swept, or when
// their owner begins another.
//
// Thread-safe: one mutex around every file operation but Take()'s mapping
// and hashing. Writes of different uploads therefore take turns; a chunk is
// at most kMaxChunkBytes.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>

#include "pba/status.h"
#include "store/mapped_file.h"

namespace pba {

struct UploadInfo {
  std::string id;
  std::string owner;
  int64_t size_bytes = 0;  // announced
  std::string sha256;      // announced, lowercase hex
  int64_t received_bytes = 0;
  int64_t expire_us = 0;  // microseconds since the Unix epoch
};

class UploadStore {
 public:
  static constexpr int64_t kMaxUploadBytes = int64_t{1} << 30;
  static constexpr size_t kMaxChunkBytes = size_t{1} << 20;
  static constexpr int64_t kLifetimeMicros = 24LL * 3600 * 1000 * 1000;
  // Open uploads one user may hold at once, whatever their size: each is two
  // files, and 1-byte uploads would otherwise pass any byte quota.
  static constexpr int kMaxOpenUploads = 1000;

  // Uploads live under `root` (normally <data>/uploads), created if absent.
  // `clock` gives microseconds since the Unix epoch (the system clock when
  // null).
  static Status Open(const std::filesystem::path& root, std::unique_ptr<UploadStore>* out,
                     std::function<int64_t()> clock = nullptr);

  // Whether `id` has the form of an upload id (32 characters 0-9 a-f).
  static bool IsWellFormedId(std::string_view id);

  // Bytes a user's open uploads may announce together; 0 (the default): no
  // quota. Set before the store is shared.
  void set_quota_bytes(int64_t bytes) { quota_bytes_ = bytes; }
  int64_t quota_bytes() const { return quota_bytes_; }

  // Starts an upload of `size_bytes` (1 .. kMaxUploadBytes) whose content
  // hashes to `sha256` (64 lowercase hex characters).
  Status Begin(const std::string& user, int64_t size_bytes, const std::string& sha256,
               UploadInfo* info);
  // Appends `data` (at most kMaxChunkBytes) at `offset`, which must be the
  // received size; the upload must not grow past its announced size.
  Status Write(const std::string& user, const std::string& id, int64_t offset,
               std::string_view data, UploadInfo* info);
  Status Get(const std::string& user, const std::string& id, UploadInfo* info);
  // The complete upload's data file, mapped read-only and checked against
  // the announced size and hash, so that a large upload is never copied onto
  // the heap. The upload stays until Remove(): the caller removes it once the
  // content is safely stored elsewhere, so a refused commit can be retried.
  // The caller may move the data file away (BlobStore::PutFile renames it
  // into the blob store): a complete upload takes no more writes, and once
  // moved its path names nothing, so no later Write() can reach the bytes;
  // Remove() then removes what is left.
  Status Take(const std::string& user, const std::string& id, std::unique_ptr<MappedFile>* content);
  // As above, read into a string (the whole upload on the heap: for small
  // uploads, tests, and measuring what the mapping saves).
  Status Take(const std::string& user, const std::string& id, std::string* content);
  // Removes the upload (also one whose data file was moved away); an upload
  // already gone is not an error.
  Status Remove(const std::string& user, const std::string& id);
  // Removes expired uploads and stray files (a data file without its .meta,
  // temporary files). *removed counts the files removed.
  Status Sweep(int* removed);

 private:
  UploadStore(std::filesystem::path root, std::function<int64_t()> clock)
      : root_(std::move(root)), clock_(std::move(clock)) {}

  // Loads `id`'s metadata and received size; kNotFound unless it exists,
  // belongs to `user` and has not expired (an expired one is removed). A
  // missing data file is kIo, unless `data_may_be_gone` (then received 0).
  Status Load(const std::string& user, const std::string& id, UploadInfo* info,
              bool data_may_be_gone = false);
  void RemoveFiles(const std::string& id);
  // Load(), then kFailedPrecondition unless every byte has arrived.
  Status LoadComplete(const std::string& user, const std::string& id, UploadInfo* info);
  // Removes an upload whose content hashes to `hash`, not the announced
  // hash: it can never succeed. Returns the refusal.
  Status Discard(const UploadInfo& info, const std::string& hash);
  // Fills open_ from the .meta files (at Open()).
  void LoadIndex();
  // kFailedPrecondition (field "upload_quota") unless `user` may begin an
  // upload of `size_bytes`; forgets (and removes) the user's expired ones
  // first. Called with the mutex held.
  Status CheckQuota(const std::string& user, int64_t size_bytes);

  struct OpenUpload {
    std::string owner;
    int64_t size_bytes = 0;
    int64_t expire_us = 0;
  };

  std::mutex mutex_;
  // Open uploads by id (see Quota above); guarded by mutex_.
  std::map<std::string, OpenUpload> open_;
  int64_t quota_bytes_ = 0;
  const std::filesystem::path root_;
  std::function<int64_t()> clock_;
};

}  // namespace pba
