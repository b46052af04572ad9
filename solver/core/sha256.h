// SHA-256 (OpenSSL's EVP interface) for the solver: structure-set files
// and their manifests, the atlas mesh cache's keys and entries.
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <string>

#include "pba/status.h"

namespace pba {

using Sha256Digest = std::array<unsigned char, 32>;

Sha256Digest Sha256Of(const void* data, std::size_t size);

// Lowercase hex, 64 characters.
std::string HexOf(const Sha256Digest& digest);

// Lowercase hex SHA-256 of a file's bytes, read in blocks (a label volume
// may be hundreds of megabytes). kIo naming the file when it cannot be read.
Status FileSha256Hex(const std::filesystem::path& path, std::string* hex);

}  // namespace pba
