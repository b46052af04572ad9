// 8-bit RGB PNG files with tEXt chunks, through libpng: the pixel format of
// the atlas plates.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "pba/status.h"

namespace pba {

struct RgbImage {
  int width = 0;
  int height = 0;
  // Row-major from the top row, 3 bytes (R, G, B) per pixel: width * height * 3.
  std::vector<uint8_t> rgb;
  // tEXt chunks as (keyword, text); keywords 1-79 Latin-1 characters.
  std::vector<std::pair<std::string, std::string>> text;
};

Status WriteRgbPng(const std::filesystem::path& path, const RgbImage& image);

// Reads an 8-bit RGB, non-interlaced PNG (the only kind WriteRgbPng makes);
// anything else is kInvalidArgument naming the file.
Status ReadRgbPng(const std::filesystem::path& path, RgbImage* image);

}  // namespace pba
