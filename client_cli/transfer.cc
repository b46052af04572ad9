#include "transfer.h"

#include <unistd.h>

#include <cstdio>
#include <fstream>

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

int DownloadTo(Connection& connection, const fs::path& target, int64_t size,
               const std::string& sha256, const std::string& what,
               const std::function<ChunkStream(grpc::ClientContext*, int64_t offset)>& open) {
  const fs::path part = target.string() + ".part";
  std::error_code ec;
  int64_t offset = fs::exists(part) ? static_cast<int64_t>(fs::file_size(part, ec)) : 0;
  if (ec || offset > size) offset = 0;
  std::ofstream out(part, std::ios::binary | (offset > 0 ? std::ios::app : std::ios::trunc));
  if (!out) {
    std::fprintf(stderr, "pba: cannot write %s\n", part.c_str());
    return kExitError;
  }
  Progress progress("downloading " + what, size);
  auto context = connection.StreamContext();
  ChunkStream reader = open(context.get(), offset);
  v1::DataChunk chunk;
  while (reader->Read(&chunk)) {
    if (chunk.offset() != offset) {
      std::fprintf(stderr, "pba: %s: chunk at byte %lld, expected %lld\n", what.c_str(),
                   static_cast<long long>(chunk.offset()), static_cast<long long>(offset));
      return kExitError;
    }
    out.write(chunk.data().data(), static_cast<std::streamsize>(chunk.data().size()));
    offset += static_cast<int64_t>(chunk.data().size());
    progress.Update(offset);
  }
  out.close();
  grpc::Status status = reader->Finish();
  if (!status.ok()) return connection.Fail("downloading " + what, status);
  if (!out) {
    std::fprintf(stderr, "pba: writing %s failed (disk full?)\n", part.c_str());
    return kExitError;
  }
  if (!sha256.empty() && Sha256File(part) != sha256) {
    fs::remove(part, ec);
    std::fprintf(stderr, "pba: %s arrived damaged (checksum mismatch); run the command again\n",
                 what.c_str());
    return kExitError;
  }
  fs::rename(part, target, ec);
  if (ec) {
    std::fprintf(stderr, "pba: cannot move %s into place: %s\n", target.c_str(),
                 ec.message().c_str());
    return kExitError;
  }
  return kExitOk;
}

}  // namespace pba::cli
