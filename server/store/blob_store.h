// BlobStore: immutable content-addressed files under <data>/blobs/. A blob is
// named by the lowercase hex SHA-256 of its content, split after two
// characters (blobs/ab/cdef...) so no directory grows past 256 entries of
// subdirectories. Writes go through AtomicWriteText (temporary sibling,
// fsync, rename), so a crash leaves a whole blob or none, plus at worst a
// stray temporary file that Sweep() removes; PutFile() instead fsyncs and
// renames the caller's own file, with the same guarantee.
//
// Content addressing makes blobs immutable by construction: the same name
// always means the same bytes, and Get() checks that it still does, so a file
// damaged on disk is an error naming the hash, never silently returned.
//
// Thread-safe (one mutex). Another process writing the same directory is not
// supported: Sweep() would take its temporary files for strays.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <string_view>

#include "pba/status.h"
#include "store/mapped_file.h"

namespace pba {

// What Sweep() removed and kept.
struct BlobSweepReport {
  int removed_blobs = 0;
  int removed_temp_files = 0;
  int64_t removed_bytes = 0;
  int kept_blobs = 0;
};

class BlobStore {
 public:
  // Blobs live under `root` (normally <data>/blobs), created if absent.
  static Status Open(const std::filesystem::path& root, std::unique_ptr<BlobStore>* out);

  // Stores `bytes` and sets *hash to their SHA-256. Idempotent: content
  // already stored intact is not written again; a stored copy that no longer
  // matches its name is replaced.
  Status Put(std::string_view bytes, std::string* hash);

  // Stores the content of `file` by moving the file itself into place
  // instead of writing a copy: it is fsynced, then renamed to its
  // content-addressed name (a rename is atomic, so the name appears only
  // with the whole content behind it), and the directories are fsynced. The
  // file must be complete and no longer written by anyone (a finished
  // upload). Afterwards its old path names nothing, so whatever wrote it
  // cannot write into the blob. When the content is already stored intact,
  // the file is left where it is. Across file systems (rename fails with
  // EXDEV), or if the path no longer names the mapped file, the mapped
  // bytes are copied as Put() does.
  Status PutFile(const MappedFile& file, std::string* hash);

  // Reads the blob `hash` and checks its content against the name. A missing
  // blob is kNotFound; a damaged one (hash mismatch, truncation) is kIo naming
  // the hash; a malformed hash is kInvalidArgument.
  Status Get(const std::string& hash, std::string* bytes);

  // Whether the blob file exists (its content is not checked).
  Status Has(const std::string& hash, bool* has);

  // Removes every blob not in `referenced` and every leftover temporary file.
  // Only for when no Put() is in flight: at start-up, or under the lock of the
  // owner that also reads `referenced` (AtlasStore::SweepBlobs), so a blob
  // written for a row not yet committed is never taken for an orphan.
  Status Sweep(const std::set<std::string>& referenced, BlobSweepReport* report);

  // Where the blob `hash` is stored (whether or not it exists).
  std::filesystem::path PathOf(const std::string& hash) const;

 private:
  explicit BlobStore(std::filesystem::path root) : root_(std::move(root)) {}

  Status ReadVerified(const std::string& hash, std::string* bytes, bool* intact);
  // Whether the blob `hash` is stored and its content hashes to its name.
  bool StoredIntact(const std::string& hash);

  std::mutex mutex_;
  const std::filesystem::path root_;
};

}  // namespace pba
