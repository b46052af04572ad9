// Local file helpers of the client: checksums, and small files that appear
// whole or not at all.
#pragma once

#include <cstddef>
#include <filesystem>
#include <string>

namespace pba::cli {

// Lowercase hex SHA-256 of the file (core/sha256.h); "" when it cannot be
// read.
std::string Sha256File(const std::filesystem::path& path);

// AtomicWriteText (core/atomic_write.h) with `mode` permissions: a new
// hidden temporary sibling, synced and renamed over `path` (a link there is
// replaced, never followed). False on failure, leaving `path` as it was.
bool WriteFileAtomically(const std::filesystem::path& path, const std::string& content,
                         unsigned mode = 0644);

// The longest file name the client writes for a name a server sent [bytes]
// (the limit of ext4, XFS and APFS).
inline constexpr size_t kMaxFileNameBytes = 255;

// Why `name`, a file name a server sent, must not become a file in a
// directory the user named; "" when it may. It may only be a plain
// relative name: not empty, "." or "..", no '/', '\\', NUL or other
// control character, at most kMaxFileNameBytes bytes. A hostile or broken
// server could otherwise write anywhere the user can ("../x", "/etc/x").
std::string UnsafeFileNameReason(const std::string& name);

// `name` quoted for a message, control characters as \xNN: a hostile name
// cannot move the cursor or recolour the terminal.
std::string QuotedName(const std::string& name);

// ASCII letters lowercased: two names that differ only in case are one file
// on macOS and Windows file systems.
std::string FoldCase(const std::string& name);

// Moves `from` to `to` unless `to` exists (a symbolic link counts, even a
// dangling one): MoveIntoPlace (core/atomic_write.h), never replacing. False
// with errno EEXIST when it does, EIO on any other failure.
bool RenameNoReplace(const std::filesystem::path& from, const std::filesystem::path& to);

}  // namespace pba::cli
