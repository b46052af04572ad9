#include "store/sha256.h"

#include <openssl/evp.h>
#include <openssl/rand.h>

#include <memory>
#include <vector>

namespace pba {

std::string HexOf(const unsigned char* bytes, size_t count) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string hex;
  hex.reserve(2 * count);
  for (size_t i = 0; i < count; ++i) {
    hex.push_back(kHex[bytes[i] >> 4]);
    hex.push_back(kHex[bytes[i] & 0xf]);
  }
  return hex;
}

Status Sha256Hex(std::string_view bytes, std::string* hex) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_Digest(bytes.data(), bytes.size(), digest, &length, EVP_sha256(), nullptr) != 1) {
    return Status::Internal("cannot compute SHA-256");
  }
  *hex = HexOf(digest, length);
  return Status::Ok();
}

bool IsSha256Hex(std::string_view text) {
  if (text.size() != 64) return false;
  for (char c : text) {
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  }
  return true;
}

Status RandomHex(int count, std::string* hex) {
  std::vector<unsigned char> bytes(static_cast<size_t>(count));
  if (RAND_bytes(bytes.data(), count) != 1) {
    return Status::Internal("the system random number generator failed");
  }
  *hex = HexOf(bytes.data(), bytes.size());
  return Status::Ok();
}

}  // namespace pba
