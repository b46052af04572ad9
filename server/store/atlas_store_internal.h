// Helpers shared by the files that implement AtlasStore (atlas_store.cc,
// atlas_store_locks.cc, atlas_store_snapshots.cc): how messages name things
// and show times. Not part of the store's interface.
#pragma once

#include <cstdint>
#include <cstdio>
#include <ctime>
#include <initializer_list>
#include <string>
#include <string_view>

#include "core/sha256.h"
#include "pba/status.h"
#include "store/atlas_store.h"
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

// "2026-01-01 00.00.00 UTC": how an unnamed snapshot is named (the CLI
// named them so before the server did).
inline std::string FormatSnapshotTime(int64_t us) {
  const std::time_t seconds = static_cast<std::time_t>(us / 1000000);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char buffer[48];
  std::strftime(buffer, sizeof(buffer), "%Y-%m-%d %H.%M.%S UTC", &tm);
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

// New geometry: not empty, at most AtlasStore::kMaxGeometryBytes.
inline Status CheckGeometry(std::string_view geometry) {
  constexpr size_t kMaxGeometryBytes = AtlasStore::kMaxGeometryBytes;
  if (geometry.empty()) return Status::InvalidArgument("geometry", "must not be empty");
  if (geometry.size() > kMaxGeometryBytes) {
    return Status::InvalidArgument(
        "geometry", "is larger than " + std::to_string(kMaxGeometryBytes) + " bytes");
  }
  return Status::Ok();
}

// A request id: empty (none) or at most 200 characters.
inline Status CheckRequestId(const std::string& request_id) {
  if (request_id.size() > 200) {
    return Status::InvalidArgument("request_id", "at most 200 characters");
  }
  return Status::Ok();
}

// The SHA-256 of a create's arguments, for telling a retry from a reused
// key. Each field is prefixed by its length, so no two lists of fields give
// the same text.
inline std::string CreateFingerprint(std::initializer_list<std::string_view> fields) {
  std::string text;
  for (std::string_view field : fields) {
    text.append(std::to_string(field.size())).append(":").append(field);
  }
  return Sha256Hex(text);
}

}  // namespace pba::atlas_internal
