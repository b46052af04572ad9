// printf-style formatting into a std::string, for messages and summaries.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace pba {

// Formats like snprintf; messages longer than 511 characters are cut.
template <typename... Args>
std::string Format(const char* format, Args... args) {
  char buffer[512];
  std::snprintf(buffer, sizeof buffer, format, args...);
  return buffer;
}

// `s` as a JSON string literal: quoted, with '"' and the backslash escaped
// and control characters as \u00XX.
inline std::string JsonQuoted(std::string_view s) {
  std::string out = "\"";
  for (unsigned char ch : s) {
    if (ch == '"' || ch == '\\') {
      out += '\\';
      out += static_cast<char>(ch);
    } else if (ch < 0x20) {
      char buffer[8];
      std::snprintf(buffer, sizeof buffer, "\\u%04x", ch);
      out += buffer;
    } else {
      out += static_cast<char>(ch);
    }
  }
  return out + "\"";
}

}  // namespace pba
