// Random identifiers from OpenSSL's CSPRNG: access tokens, lock ids,
// upload ids. (Their hashes and every other SHA-256: core/sha256.h.)
#pragma once

#include <string>

#include "pba/status.h"

namespace pba {

// `count` bytes from OpenSSL's CSPRNG as lowercase hex (2 * count characters).
Status RandomHex(int count, std::string* hex);

}  // namespace pba
