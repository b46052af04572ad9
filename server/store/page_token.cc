#include "store/page_token.h"

#include <algorithm>
#include <charconv>
#include <cstdio>

namespace pba {
namespace {

// Long enough for any kind name and two 19-digit numbers.
constexpr size_t kMaxTokenLength = 160;

int HexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

}  // namespace

Status NormalisePageSize(int page_size, int* normalised) {
  if (page_size < 0) return Status::InvalidArgument("page_size", "must not be negative");
  *normalised = page_size == 0 ? kDefaultPageSize : std::min(page_size, kMaxPageSize);
  return Status::Ok();
}

std::string EncodePageToken(std::string_view kind, int64_t scope, int64_t key) {
  std::string plain(kind);
  plain.append(".v1:").append(std::to_string(scope)).append(":").append(std::to_string(key));
  std::string hex;
  char buffer[3];
  for (unsigned char c : plain) {
    std::snprintf(buffer, sizeof(buffer), "%02x", c);
    hex += buffer;
  }
  return hex;
}

Status DecodePageToken(std::string_view token, std::string_view kind, int64_t scope, int64_t* key) {
  const Status refused =
      Status::InvalidArgument("page_token", "not a token from a previous " + std::string(kind) +
                                                " listing of this resource");
  if (token.size() % 2 != 0 || token.size() > kMaxTokenLength) return refused;
  std::string plain;
  for (size_t i = 0; i < token.size(); i += 2) {
    const int high = HexValue(token[i]);
    const int low = HexValue(token[i + 1]);
    if (high < 0 || low < 0) return refused;
    plain.push_back(static_cast<char>(high * 16 + low));
  }
  std::string prefix(kind);
  prefix.append(".v1:").append(std::to_string(scope)).append(":");
  if (plain.rfind(prefix, 0) != 0) return refused;
  const std::string_view digits = std::string_view(plain).substr(prefix.size());
  int64_t value = 0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (error != std::errc() || end != digits.data() + digits.size() || digits.empty() ||
      digits[0] == '-' || digits[0] == '+') {
    return refused;
  }
  *key = value;
  return Status::Ok();
}

}  // namespace pba
