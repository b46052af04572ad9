// Peak resident memory of committing one large upload, the way
// AtlasServiceImpl::CommitStructure does it: the complete upload is taken,
// given the geometry check, committed to the atlas store and removed. Two
// paths: --copy reads the upload into a string and writes the blob as a
// copy (the service before uploads were mapped); the default maps the
// upload read-only and renames it into the blob store. A measurement for
// docs/performance.md, not a test:
//   build/release/bin/upload_commit_rss [--copy] [--mib 200] [--dir DIR]
// The content is a NIfTI-1 file (a 352-byte header, then pseudo-random
// bytes), whose check reads only the header, so the figure is the upload
// path's own memory. The peak is VmHWM, reset (clear_refs 5) just before the
// commit, so it excludes setting up and writing the upload.
#include <openssl/evp.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "service/geometry_check.h"
#include "store/atlas_store.h"
#include "store/upload_store.h"

namespace {

namespace fs = std::filesystem;

// A field of /proc/self/status in KiB (VmHWM, VmRSS, ...).
long StatusKib(const char* field) {
  std::ifstream in("/proc/self/status");
  std::string line;
  const std::string prefix = std::string(field) + ":";
  while (std::getline(in, line)) {
    if (line.rfind(prefix, 0) == 0) return std::strtol(line.c_str() + prefix.size(), nullptr, 10);
  }
  return -1;
}

void Check(const pba::Status& status, const char* what) {
  if (status.ok()) return;
  std::fprintf(stderr, "upload_commit_rss: %s: %s\n", what, status.ToString().c_str());
  std::exit(1);
}

std::string Hex(const unsigned char* bytes, unsigned int count) {
  std::string hex;
  char buffer[3];
  for (unsigned int i = 0; i < count; ++i) {
    std::snprintf(buffer, sizeof buffer, "%02x", bytes[i]);
    hex += buffer;
  }
  return hex;
}

// Chunk `index` of the content: the NIfTI header first, then bytes from a
// xorshift generator (so the content does not compress or repeat).
void FillChunk(size_t index, std::string* chunk, uint64_t* state) {
  for (size_t i = 0; i < chunk->size(); i += 8) {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    std::memcpy(chunk->data() + i, state, std::min<size_t>(8, chunk->size() - i));
  }
  if (index == 0) {
    std::memset(chunk->data(), 0, 352);
    const int32_t sizeof_hdr = 348;
    std::memcpy(chunk->data(), &sizeof_hdr, 4);
    std::memcpy(chunk->data() + 344, "n+1", 4);
  }
}

}  // namespace

int main(int argc, char** argv) {
  bool copy = false;
  long mib = 200;
  fs::path dir;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--copy") {
      copy = true;
    } else if (arg == "--mib" && i + 1 < argc) {
      mib = std::strtol(argv[++i], nullptr, 10);
    } else if (arg == "--dir" && i + 1 < argc) {
      dir = argv[++i];
    } else {
      std::fprintf(stderr, "usage: upload_commit_rss [--copy] [--mib N] [--dir DIR]\n");
      return 2;
    }
  }
  if (dir.empty()) {
    dir = fs::temp_directory_path() / ("upload_commit_rss." + std::to_string(::getpid()));
  }
  fs::remove_all(dir);
  const size_t chunk_bytes = pba::UploadStore::kMaxChunkBytes;
  const size_t size = static_cast<size_t>(mib) << 20;

  std::unique_ptr<pba::AtlasStore> store;
  Check(pba::AtlasStore::Open(dir, &store), "opening the store");
  std::unique_ptr<pba::UploadStore> uploads;
  Check(pba::UploadStore::Open(dir / "uploads", &uploads), "opening the uploads");
  std::string token;
  Check(store->CreateUser("alice", &token), "creating a user");
  Check(store->CreateProject("alice", "bench"), "creating a project");
  const pba::StructureRef ref{"bench", "brain"};
  std::string first(352, '\0');
  uint64_t seed = 1;
  FillChunk(0, &first, &seed);
  pba::Revision revision;
  Check(store->CreateStructure("alice", ref, pba::StructureMetadata(), pba::StructureFormat::kNifti,
                               first, &revision),
        "creating a structure");
  pba::LockInfo lock;
  Check(store->AcquireLock("alice", ref, 600LL * 1000 * 1000, &lock), "locking");

  // The content's hash first (as a client announces it), then the upload.
  std::string chunk(chunk_bytes, '\0');
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> sha(EVP_MD_CTX_new(), EVP_MD_CTX_free);
  EVP_DigestInit_ex(sha.get(), EVP_sha256(), nullptr);
  uint64_t state = 88172645463325252ULL;
  for (size_t offset = 0, index = 0; offset < size; offset += chunk_bytes, ++index) {
    chunk.resize(std::min(chunk_bytes, size - offset));
    FillChunk(index, &chunk, &state);
    EVP_DigestUpdate(sha.get(), chunk.data(), chunk.size());
  }
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestFinal_ex(sha.get(), digest, &length);
  pba::UploadInfo info;
  Check(uploads->Begin("alice", static_cast<int64_t>(size), Hex(digest, length), &info), "begin");
  state = 88172645463325252ULL;
  for (size_t offset = 0, index = 0; offset < size; offset += chunk_bytes, ++index) {
    chunk.resize(std::min(chunk_bytes, size - offset));
    FillChunk(index, &chunk, &state);
    Check(uploads->Write("alice", info.id, static_cast<int64_t>(offset), chunk, &info), "write");
  }
  chunk = std::string();

  const long before_kib = StatusKib("VmRSS");
  std::ofstream("/proc/self/clear_refs") << "5";  // resets VmHWM to the current RSS
  const auto start = std::chrono::steady_clock::now();
  pba::CommitRequest request;
  request.structure = ref;
  request.lock_id = lock.lock_id;
  request.base_revision = 1;
  request.format = pba::StructureFormat::kNifti;
  request.message = "bench";
  std::string content;
  std::unique_ptr<pba::MappedFile> mapped;
  if (copy) {
    Check(uploads->Take("alice", info.id, &content), "take");
    request.geometry = content;
  } else {
    Check(uploads->Take("alice", info.id, &mapped), "take");
    request.geometry = mapped->bytes();
    request.geometry_file = mapped.get();
  }
  Check(pba::CheckGeometryContent("upload_id", request.format, request.geometry), "check");
  Check(store->Commit("alice", request, &revision), "commit");
  content = std::string();
  mapped.reset();
  Check(uploads->Remove("alice", info.id), "remove");
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const long peak_kib = StatusKib("VmHWM");
  std::printf(
      "%s path, %ld MiB commit: RSS before %.1f MiB, peak during the commit %.1f MiB "
      "(+%.1f MiB), %.2f s\n",
      copy ? "copy" : "mapped", mib, before_kib / 1024.0, peak_kib / 1024.0,
      (peak_kib - before_kib) / 1024.0, seconds);
  store.reset();
  fs::remove_all(dir);
  return 0;
}
