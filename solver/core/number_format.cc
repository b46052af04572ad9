#include "core/number_format.h"

#include <charconv>
#include <cstdio>
#include <system_error>

namespace pba {
namespace {

std::string ToChars(double value, int precision) {
  char text[64];
  const auto [end, error] = precision < 0 ? std::to_chars(text, text + sizeof text, value)
                                          : std::to_chars(text, text + sizeof text, value,
                                                          std::chars_format::general, precision);
  // 64 characters hold any double, so to_chars cannot run out of room.
  return error == std::errc() ? std::string(text, end) : std::string("?");
}

}  // namespace

std::string RoundTripNumber(double value) { return ToChars(value, -1); }

std::string RoundTripNumber(double value, int max_width) {
  std::string text = ToChars(value, -1);
  for (int digits = 17; static_cast<int>(text.size()) > max_width && digits > 1; --digits) {
    text = ToChars(value, digits);
  }
  if (static_cast<int>(text.size()) > max_width) text = ToChars(value, 1);
  return text;
}

std::string ShortNumber(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

}  // namespace pba
