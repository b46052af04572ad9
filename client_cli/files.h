// Local file helpers of the client: checksums, and small files that appear
// whole or not at all.
#pragma once

#include <filesystem>
#include <string>

namespace pba::cli {

// Lowercase hex SHA-256 of the file; "" when it cannot be read.
std::string Sha256File(const std::filesystem::path& path);
// Lowercase hex SHA-256 of `text`.
std::string Sha256Text(const std::string& text);

// Writes `content` to a temporary sibling with `mode` permissions, then
// renames it over `path`. False (errno kept) on failure, leaving `path` as
// it was.
bool WriteFileAtomically(const std::filesystem::path& path, const std::string& content,
                         unsigned mode = 0644);

}  // namespace pba::cli
