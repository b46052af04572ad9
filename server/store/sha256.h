// SHA-256 of bytes in memory (OpenSSL), for content-addressed blobs and for
// storing access tokens only as hashes.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "pba/status.h"

namespace pba {

// Lowercase hex of `count` bytes (2 * count characters), e.g. a digest.
std::string HexOf(const unsigned char* bytes, size_t count);

// Lowercase hex SHA-256 (64 characters) of `bytes`.
Status Sha256Hex(std::string_view bytes, std::string* hex);

// Whether `text` has the form of Sha256Hex's output: 64 characters 0-9 a-f.
bool IsSha256Hex(std::string_view text);

// `count` bytes from OpenSSL's CSPRNG as lowercase hex (2 * count characters).
Status RandomHex(int count, std::string* hex);

}  // namespace pba
