// A content-addressed cache of built atlas meshes. Meshing an atlas with
// CGAL takes seconds to minutes and a batch of jobs on the same atlas would
// rebuild the same mesh for each; the cache keys a mesh by everything that
// decides it (the build options, the solver's version and the bytes of the
// atlas source), so a job that finds its key reuses the mesh another built.
//
// An entry is one file, <dir>/<key>.mesh, written atomically (jobs building
// the same key at once each write a whole file; the last rename wins and
// both are the same mesh). A damaged entry (truncated, foreign, bad
// checksum) is a miss and is removed: the cache can cost a rebuild, never
// a wrong mesh. The directory is bounded in size, least recently used
// entries (by modification time, which a hit renews) going first.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "atlas/atlas_build.h"
#include "mesh/mesh.h"
#include "pba/status.h"

namespace pba {

// The default bound of a cache directory [bytes]: 2 GiB.
inline constexpr std::uint64_t kDefaultAtlasMeshCacheBytes = std::uint64_t{2} << 30;

// The key of the mesh `options` build: the lowercase hex SHA-256 of a
// canonical text of the options that shape the mesh, the solver's version
// and the content of the source (a directory's regular files by relative
// name and digest, a label volume's and its colour table's digests; the
// synthetic atlas by name). Modification times and paths do not count, so
// a copy of an atlas has the key of the original. kIo when the source
// cannot be read.
Status AtlasMeshCacheKey(const AtlasBuildOptions& options, std::string* key);

struct CachedAtlasMesh {
  Mesh mesh;
  // What the build reported (the model builder's mesh note).
  std::string description;
};

// The entry of `key` in `dir`. *hit false when there is none, or it was
// damaged (then it is removed); on a hit the entry's modification time is
// renewed. Errors only for a key that is not one (kInvalidArgument).
Status LoadCachedAtlasMesh(const std::filesystem::path& dir, const std::string& key,
                           CachedAtlasMesh* entry, bool* hit);

// Writes the entry of `key` into `dir` (created if absent), then removes
// the least recently used entries while the directory's entries take more
// than `max_bytes` (the new one stays even if it alone is larger). kIo when
// the entry cannot be written.
Status StoreCachedAtlasMesh(const std::filesystem::path& dir, const std::string& key,
                            const CachedAtlasMesh& entry,
                            std::uint64_t max_bytes = kDefaultAtlasMeshCacheBytes);

// Removes least recently used entries of `dir` until they take at most
// `max_bytes`, never `keep` (a key; may be empty). Also removes temporary
// files left by writers that died more than a day ago.
void EvictAtlasMeshCache(const std::filesystem::path& dir, std::uint64_t max_bytes,
                         const std::string& keep = "");

}  // namespace pba
