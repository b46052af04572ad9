// Helpers shared by the files that implement AtlasStore (atlas_store.cc,
// atlas_store_locks.cc, atlas_store_snapshots.cc): how messages name things
// and show times. Not part of the store's interface.
#pragma once

#include <cstdint>
#include <cstdio>
#include <ctime>
#include <string>

#include "store/atlas_types.h"

namespace pba::atlas_internal {

// ISO 8601 UTC with microseconds, as messages and audit details show times.
inline std::string FormatTime(int64_t us) {
  const std::time_t seconds = static_cast<std::time_t>(us / 1000000);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char date[32];
  std::strftime(date, sizeof(date), "%Y-%m-%dT%H:%M:%S", &tm);
  char buffer[48];
  std::snprintf(buffer, sizeof(buffer), "%s.%06lldZ", date, static_cast<long long>(us % 1000000));
  return buffer;
}

inline std::string Quoted(const std::string& name) { return "'" + name + "'"; }

inline std::string ProjectTarget(const std::string& project) { return "projects/" + project; }

inline std::string StructureTarget(const StructureRef& ref) {
  return ProjectTarget(ref.project) + "/structures/" + ref.structure;
}

inline std::string Describe(const StructureRef& ref) {
  return "structure " + Quoted(ref.structure) + " of project " + Quoted(ref.project);
}

inline bool AllDigits(const std::string& text) {
  if (text.empty()) return false;
  for (char c : text) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

}  // namespace pba::atlas_internal
