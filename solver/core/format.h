// printf-style formatting into a std::string, for messages and summaries.
#pragma once

#include <cstdio>
#include <string>

namespace pba {

// Formats like snprintf; messages longer than 511 characters are cut.
template <typename... Args>
std::string Format(const char* format, Args... args) {
  char buffer[512];
  std::snprintf(buffer, sizeof buffer, format, args...);
  return buffer;
}

}  // namespace pba
