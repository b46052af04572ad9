#include "store/job_id.h"

#include <cstdint>
#include <mutex>
#include <random>

namespace pba {
namespace {

constexpr int kHexDigits = 10;

}  // namespace

std::string NewJobId() {
  // One seeded engine for the process: std::random_device may be slow or
  // block on some systems, so it only provides the seed.
  static std::mutex mutex;
  static std::mt19937_64 engine{[] {
    std::random_device device;
    return (static_cast<uint64_t>(device()) << 32) ^ device();
  }()};
  uint64_t bits;
  {
    std::lock_guard lock(mutex);
    bits = engine();
  }
  static constexpr char kHex[] = "0123456789abcdef";
  std::string id = "j";
  for (int i = 0; i < kHexDigits; ++i) id.push_back(kHex[(bits >> (4 * i)) & 0xf]);
  return id;
}

bool IsWellFormedJobId(std::string_view id) {
  if (id.size() != 1 + kHexDigits || id[0] != 'j') return false;
  for (char c : id.substr(1)) {
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  }
  return true;
}

}  // namespace pba
