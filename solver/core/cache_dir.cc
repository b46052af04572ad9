#include "core/cache_dir.h"

#include <algorithm>
#include <chrono>
#include <system_error>
#include <vector>

#include "core/atomic_write.h"

namespace pba {
namespace fs = std::filesystem;

void EvictLeastRecentlyUsed(const fs::path& dir, const std::string& suffix, std::uint64_t max_bytes,
                            const std::string& keep) {
  struct Entry {
    fs::file_time_type used;
    std::uint64_t bytes;
    fs::path path;
  };
  std::vector<Entry> entries;
  std::uint64_t total = 0;
  const auto stale = fs::file_time_type::clock::now() - std::chrono::hours(24);
  std::error_code ec;
  fs::directory_iterator it(dir, ec), end;
  for (; !ec && it != end; it.increment(ec)) {
    std::error_code entry_ec;
    if (!it->is_regular_file(entry_ec)) continue;
    const std::string name = it->path().filename().string();
    const fs::file_time_type used = it->last_write_time(entry_ec);
    if (entry_ec) continue;  // removed meanwhile
    if (name.front() == '.') {
      // AtomicWrite's temporary files: in progress, or left by a writer
      // that died (no write takes a day). Other hidden files are not ours.
      if (IsAtomicWriteTemporary(name) && used < stale) fs::remove(it->path(), entry_ec);
      continue;
    }
    if (name.size() <= suffix.size() ||
        name.compare(name.size() - suffix.size(), std::string::npos, suffix) != 0) {
      continue;  // not an entry
    }
    const std::uint64_t bytes = it->file_size(entry_ec);
    if (entry_ec) continue;
    total += bytes;
    if (!keep.empty() && name == keep) continue;
    entries.push_back({used, bytes, it->path()});
  }
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.used < b.used; });
  for (const Entry& e : entries) {
    if (total <= max_bytes) break;
    std::error_code ignored;
    fs::remove(e.path, ignored);
    total -= e.bytes;  // removed here or by another process evicting too
  }
}

}  // namespace pba
