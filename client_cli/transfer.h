// Downloads of the client: a stream of DataChunk into a file that appears
// under its name only once it is whole and its checksum matches.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "connection.h"

namespace pba::cli {

// Shows a transfer's progress on a terminal (stderr), nothing otherwise.
class Progress {
 public:
  Progress(std::string what, int64_t total);
  ~Progress();
  void Update(int64_t done);

 private:
  std::string what_;
  int64_t total_;
  bool shown_;
};

using ChunkStream = std::unique_ptr<grpc::ClientReader<v1::DataChunk>>;

// Downloads `size` bytes into `target` through target.part, resuming a
// .part an interrupted download left; `open` starts the server's stream at
// a byte offset. The file is moved into place only when its SHA-256 is
// `sha256` (an empty `sha256` skips the check). `what` names it in messages.
// Symbolic links are never followed: a .part that is one (or anything but
// a regular file) is refused, and `target` is replaced, not written
// through. Without `overwrite` an existing `target` is refused (exit 9,
// kExitConflict) before anything is downloaded.
int DownloadTo(Connection& connection, const std::filesystem::path& target, int64_t size,
               const std::string& sha256, const std::string& what, bool overwrite,
               const std::function<ChunkStream(grpc::ClientContext*, int64_t offset)>& open);
// The same, replacing an existing `target`: for files whose name the
// client chose itself.
inline int DownloadTo(
    Connection& connection, const std::filesystem::path& target, int64_t size,
    const std::string& sha256, const std::string& what,
    const std::function<ChunkStream(grpc::ClientContext*, int64_t offset)>& open) {
  return DownloadTo(connection, target, size, sha256, what, /*overwrite=*/true, open);
}

}  // namespace pba::cli
