// The values the atlas store takes and returns (AtlasStore), and the checks
// every name and field passes before it reaches SQL. Names are what users
// type and what later becomes resource names (projects/{p}/structures/{s}),
// file names in exports and labels in tables, so the allowed alphabet is
// deliberately small; the store binds every value as an SQL parameter anyway.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "atlas/structure_format.h"
#include "pba/status.h"

namespace pba {

// Ordered: a higher role can do everything a lower one can.
enum class Role { kViewer = 0, kEditor = 1, kAdmin = 2 };
const char* RoleName(Role role);
bool ParseRole(std::string_view name, Role* role);

// A revision's geometry format is the solver's StructureFormat: its names
// ("contours_json", "nifti", "stl", "obj", "vtk") are what pba.db stores.

// Display colour, sRGB components 0..255.
struct Colour {
  int r = 0;
  int g = 0;
  int b = 0;
  bool operator==(const Colour&) const = default;
};

// Everything about a structure except its geometry. Versioned with it: every
// revision carries the metadata in force at that revision.
struct StructureMetadata {
  Colour colour;
  // "" (no group) or names joined by '/', outermost first, e.g. "cerebrum/cortex".
  std::string group_path;
  // A JSON object with the material parameters, stored verbatim (the service
  // layer parses it into the scene's material message).
  std::string material_json = "{}";
  bool operator==(const StructureMetadata&) const = default;
};

// A structure is addressed by its project's name and its own name.
struct StructureRef {
  std::string project;
  std::string structure;
};

// One immutable revision of a structure. Numbers count 1, 2, 3, ... within
// the structure; the parent of revision n is n - 1.
struct Revision {
  std::string project;
  std::string structure;
  int64_t number = 0;
  int64_t parent = 0;  // 0 for revision 1
  std::string author;
  int64_t time_us = 0;  // microseconds since the Unix epoch, UTC
  std::string kind;     // "create", "commit", "metadata" or "revert"
  std::string message;
  std::string content_sha256;  // the geometry blob
  StructureFormat format = StructureFormat::kContours;
  int64_t size_bytes = 0;  // of the geometry blob
  StructureMetadata metadata;
};

struct LockInfo {
  std::string lock_id;  // a secret of the holder: renew, release and commit name it
  std::string owner;
  int64_t acquired_us = 0;
  int64_t lease_expiry_us = 0;
  // AcquireLock only: the structure was locked by someone whose lease had lapsed.
  std::string took_over_from;
  // The structure locked (AcquireLock, RenewLock, and the lock of a
  // StructureInfo).
  StructureRef structure;
};

struct StructureInfo {
  std::string project;
  std::string name;
  int64_t head = 0;  // the head revision's number
  // Changes whenever the metadata changes (not on a geometry-only commit);
  // UpdateMetadata must be given the current one.
  std::string metadata_etag;
  StructureMetadata metadata;  // the head's
  int64_t created_us = 0;
  // The lock on the structure, lapsed or not, if any; its lock_id is always
  // empty here (only the holder knows it).
  std::optional<LockInfo> lock;
};

struct ProjectInfo {
  std::string name;
  int64_t created_us = 0;
  std::string created_by;
  Role role = Role::kViewer;  // the listing user's role
};

struct SnapshotInfo {
  int64_t id = 0;
  std::string project;
  std::string name;
  std::string author;
  int64_t created_us = 0;
  std::vector<std::string> tags;  // sorted
  // Structure name -> pinned revision number.
  std::map<std::string, int64_t> revisions;
};

struct AuditEntry {
  int64_t seq = 0;
  int64_t time_us = 0;
  std::string user;  // "" for the server itself
  std::string action;
  std::string target;    // a resource name, e.g. "projects/p/structures/s"
  int64_t revision = 0;  // the revision number it made or named; 0 for none
  std::string detail;
};

// Limits of the fields below; the messages quote them.
inline constexpr size_t kMaxNameLength = 128;
inline constexpr size_t kMaxGroupPathLength = 1024;
inline constexpr size_t kMaxMaterialJsonBytes = 64 * 1024;
inline constexpr size_t kMaxMessageBytes = 4096;

// A name of a user, project, structure, snapshot or tag: 1 to 128 characters
// from letters, digits, space, '_', '-', '.', '(' and ')', not starting or
// ending with a space, and not "." or "..". A refusal is kInvalidArgument for
// `field` naming the first bad character and its position.
Status CheckName(std::string_view field, std::string_view name);

// "" or CheckName-valid names joined by single '/'.
Status CheckGroupPath(std::string_view field, std::string_view path);

// 0..255 each, fields "<field>.r" etc.
Status CheckColour(std::string_view field, const Colour& colour);

// A JSON object: well-formed JSON (RFC 8259) whose top level is an object.
Status CheckMaterialJson(std::string_view field, std::string_view json);

// A commit message: up to kMaxMessageBytes, no control characters but
// newline and tab.
Status CheckMessage(std::string_view field, std::string_view message);

Status CheckMetadata(const StructureMetadata& metadata);

}  // namespace pba
