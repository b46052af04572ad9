// A directory of cache entries bounded in bytes: the atlas mesh cache
// (atlas/atlas_mesh_cache.h) and the server's structures' surfaces
// (server/service/surface_views.h). An entry is a regular file whose name
// ends in the cache's suffix; a use renews its modification time, so the
// oldest is the least recently used.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace pba {

// Removes the least recently used entries of `dir` (files named *`suffix`)
// until they take at most `max_bytes`, never the one named `keep` (a file
// name; may be empty). Also removes AtomicWrite's temporary files
// (".NAME.partial-...") left by writers that died more than a day ago.
// Best effort: an entry removed meanwhile by another process is skipped.
void EvictLeastRecentlyUsed(const std::filesystem::path& dir, const std::string& suffix,
                            std::uint64_t max_bytes, const std::string& keep);

}  // namespace pba
