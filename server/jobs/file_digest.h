// SHA-256 of a file, for the result_files table and for clients to check a
// download against.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

#include "pba/status.h"

namespace pba {

// Lowercase hex SHA-256 of the file at `path` and its size in bytes.
Status Sha256File(const std::filesystem::path& path, std::string* hex, int64_t* size);

}  // namespace pba
