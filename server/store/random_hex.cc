#include "store/random_hex.h"

#include <openssl/rand.h>

#include <vector>

#include "core/sha256.h"

namespace pba {

Status RandomHex(int count, std::string* hex) {
  std::vector<unsigned char> bytes(static_cast<size_t>(count));
  if (RAND_bytes(bytes.data(), count) != 1) {
    return Status::Internal("the system random number generator failed");
  }
  *hex = HexOf(bytes.data(), bytes.size());
  return Status::Ok();
}

}  // namespace pba
