#include "io/png_io.h"

#include <png.h>

#include <csetjmp>
#include <cstdio>

namespace pba {
namespace {

// libpng reports errors by longjmp; the message is kept here. Only plain C
// objects live between setjmp and a possible longjmp in the functions below.
struct ErrorSink {
  char message[256] = "";
};

void OnError(png_structp png, png_const_charp message) {
  auto* sink = static_cast<ErrorSink*>(png_get_error_ptr(png));
  std::snprintf(sink->message, sizeof sink->message, "%s", message);
  png_longjmp(png, 1);
}

void OnWarning(png_structp, png_const_charp) {}

// Returns an empty string on success, else libpng's message.
std::string WriteRaw(std::FILE* file, const RgbImage& image, png_textp texts, int num_texts,
                     png_bytepp rows) {
  ErrorSink sink;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &sink, OnError, OnWarning);
  if (png == nullptr) return "cannot create a libpng writer";
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return sink.message[0] ? sink.message : "libpng failed";
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, image.width, image.height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (num_texts > 0) png_set_text(png, info, texts, num_texts);
  png_set_rows(png, info, rows);
  png_write_png(png, info, PNG_TRANSFORM_IDENTITY, nullptr);
  png_destroy_write_struct(&png, &info);
  return {};
}

struct ReadResult {
  char message[256] = "";
  png_uint_32 width = 0, height = 0;
  int bit_depth = 0, colour_type = 0, interlace = 0;
};

// Reads the header into `result`, then, for 8-bit RGB, the pixels and the
// text chunks. Returns false on a libpng error (message in result).
// `pixels` and `text` belong to the caller, so a longjmp skips no destructor.
bool ReadRaw(std::FILE* file, ReadResult* result, std::vector<uint8_t>* pixels,
             std::vector<std::pair<std::string, std::string>>* text) {
  ErrorSink sink;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &sink, OnError, OnWarning);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    std::snprintf(result->message, sizeof result->message, "%s",
                  sink.message[0] ? sink.message : "libpng failed");
    return false;
  }
  png_init_io(png, file);
  png_read_info(png, info);
  png_get_IHDR(png, info, &result->width, &result->height, &result->bit_depth, &result->colour_type,
               &result->interlace, nullptr, nullptr);
  const bool rgb8 = result->bit_depth == 8 && result->colour_type == PNG_COLOR_TYPE_RGB &&
                    result->interlace == PNG_INTERLACE_NONE;
  if (rgb8) {
    pixels->resize(static_cast<size_t>(result->width) * result->height * 3);
    for (png_uint_32 r = 0; r < result->height; ++r) {
      png_read_row(png, pixels->data() + static_cast<size_t>(r) * result->width * 3, nullptr);
    }
    png_read_end(png, info);
    png_textp texts = nullptr;
    const int n = png_get_text(png, info, &texts, nullptr);
    for (int t = 0; t < n; ++t) {
      text->emplace_back(texts[t].key, std::string(texts[t].text, texts[t].text_length));
    }
  }
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

}  // namespace

Status WriteRgbPng(const std::filesystem::path& path, const RgbImage& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != static_cast<size_t>(image.width) * image.height * 3) {
    return Status::InvalidArgument("image", "bad image size for " + path.string());
  }
  std::vector<png_text> texts(image.text.size());
  for (size_t t = 0; t < texts.size(); ++t) {
    texts[t] = {};
    texts[t].compression = PNG_TEXT_COMPRESSION_NONE;
    texts[t].key = const_cast<char*>(image.text[t].first.c_str());
    texts[t].text = const_cast<char*>(image.text[t].second.c_str());
    texts[t].text_length = image.text[t].second.size();
  }
  std::vector<png_bytep> rows(image.height);
  for (int r = 0; r < image.height; ++r) {
    rows[r] = const_cast<png_bytep>(image.rgb.data() + static_cast<size_t>(r) * image.width * 3);
  }
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) return Status::Io("cannot open " + path.string() + " for writing");
  const std::string error =
      WriteRaw(file, image, texts.data(), static_cast<int>(texts.size()), rows.data());
  const bool closed = std::fclose(file) == 0;
  if (!error.empty()) return Status::Io("writing " + path.string() + ": " + error);
  if (!closed) return Status::Io("writing " + path.string() + " failed");
  return Status::Ok();
}

Status ReadRgbPng(const std::filesystem::path& path, RgbImage* image) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return Status::Io("cannot open " + path.string());
  ReadResult result;
  RgbImage read;
  const bool ok = ReadRaw(file, &result, &read.rgb, &read.text);
  std::fclose(file);
  if (!ok) return Status::InvalidArgument(path.filename().string(), result.message);
  if (result.bit_depth != 8 || result.colour_type != PNG_COLOR_TYPE_RGB ||
      result.interlace != PNG_INTERLACE_NONE) {
    return Status::InvalidArgument(path.filename().string(), "not an 8-bit RGB non-interlaced PNG");
  }
  read.width = static_cast<int>(result.width);
  read.height = static_cast<int>(result.height);
  *image = std::move(read);
  return Status::Ok();
}

}  // namespace pba
