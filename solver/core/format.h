// printf-style formatting into a std::string, for messages and summaries.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace pba {

// Formats like snprintf, whatever the length: a short message from a stack
// buffer, a longer one formatted again into a string of its exact size
// (a message naming many structures, or a path, must never be cut).
template <typename... Args>
std::string Format(const char* format, Args... args) {
  char buffer[512];
  const int length = std::snprintf(buffer, sizeof buffer, format, args...);
  if (length < 0) return "(unformattable message: " + std::string(format) + ")";
  if (static_cast<size_t>(length) < sizeof buffer) return std::string(buffer, length);
  std::string out(static_cast<size_t>(length), '\0');
  std::snprintf(out.data(), out.size() + 1, format, args...);
  return out;
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

// `s` as a CSV field: as it is, or in double quotes (with each quote
// doubled) when it holds a comma, a quote or a line break.
inline std::string CsvQuoted(std::string_view s) {
  if (s.find_first_of(",\"\r\n") == std::string_view::npos) return std::string(s);
  std::string out = "\"";
  for (char ch : s) {
    if (ch == '"') out += '"';
    out += ch;
  }
  return out + "\"";
}

}  // namespace pba
