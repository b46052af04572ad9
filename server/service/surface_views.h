// SurfaceViews: the surfaces of a project's structures as the web view
// draws them (AtlasService.DownloadSurfaces): each structure's outer and
// interface triangles as glTF 2.0 binary (solver/results/surface_gltf.h),
// meshed by `pba-solve --atlas-surfaces` from the structures' geometry, the
// same atlas build a job on them runs, and kept in a cache keyed by the
// content of what was meshed.
//
// The key is the SHA-256 of the solver's version, the facet size and, per
// structure in order, its name, format and content hash: revisions, colours
// and materials do not count (a colour set, a snapshot of the same heads
// or the same revisions under two tags share one entry), a commit that
// changes a shape makes a new one. An entry is one file <dir>/<key>.glb,
// renamed into place whole; the directory is bounded in bytes, the least
// recently used entries (by modification time, which a hit renews) going
// first. A damaged or foreign file at a key's name costs a rebuild, never
// a wrong view: an entry must be a whole glTF binary (its header's magic,
// version and length).
//
// Bounds: builds run one at a time (others wait for their turn up to
// `patience`, then RESOURCE_EXHAUSTED), each a child process with an
// address-space limit and a wall-time limit, killed when the caller goes
// or the server stops. Two callers asking for the same key build it once:
// the second finds the first's entry when its turn comes.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "pba/status.h"
#include "service/diff_slots.h"
#include "store/atlas_store.h"

namespace pba {

struct SurfaceViewOptions {
  std::filesystem::path solver;     // pba-solve
  std::filesystem::path cache_dir;  // created if absent
  std::uint64_t cache_bytes = std::uint64_t{512} << 20;
  double facet_mm = 3;
  int64_t memory_bytes = int64_t{4} << 30;  // the child's address space
  std::chrono::seconds time_limit{300};
  std::chrono::milliseconds patience{60000};  // waiting for a turn
};

// What Get found or made.
struct SurfaceView {
  std::string bytes;          // the glTF binary
  std::filesystem::path glb;  // its cache entry (which a prune may remove)
  std::string key;
  bool cached = false;  // found, not built
  double build_s = 0;   // the build's wall time (0 when cached)
};

class SurfaceViews {
 public:
  explicit SurfaceViews(SurfaceViewOptions options);

  // The surfaces of `files` (a snapshot's members, the heads, or one
  // revision of one structure), of `project`. `cancelled` (may be empty)
  // is asked while waiting and building. Errors: kResourceExhausted when no
  // turn comes within the patience; kCancelled; kInvalidArgument (with the
  // solver's own message) when the structures cannot be meshed, or take
  // more memory or time than the bounds (named); kInternal or kIo when the
  // solver cannot run or the cache cannot be written.
  Status Get(const std::string& project, int64_t snapshot, const std::vector<SnapshotFile>& files,
             const std::function<bool()>& cancelled, SurfaceView* view);

  // The key `files` have (what Get looks up).
  std::string KeyOf(const std::vector<SnapshotFile>& files) const;

  // Removes the least recently used entries until the cache holds at most
  // options.cache_bytes; the entry `keep` stays whatever its age.
  void Prune(const std::filesystem::path& keep);

 private:
  Status Build(const std::string& project, int64_t snapshot, const std::vector<SnapshotFile>& files,
               const std::function<bool()>& cancelled, const std::filesystem::path& entry,
               std::string* bytes);

  SurfaceViewOptions options_;
  DiffSlots turns_{1, "surface_builds", "meshing other structures' surfaces"};
  std::atomic<uint64_t> builds_{0};  // names of the builds' scratch folders
};

}  // namespace pba
