#include "service/geometry_check.h"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <string>

namespace pba {
namespace {

constexpr size_t kNiftiHeaderBytes = 348;

// The first `want` bytes of gzip data, or fewer if it is shorter or broken.
std::string Gunzip(std::string_view gz, size_t want) {
  std::string out(want, '\0');
  z_stream stream{};
  // 16 + MAX_WBITS: expect a gzip header.
  if (inflateInit2(&stream, 16 + MAX_WBITS) != Z_OK) return "";
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(gz.data()));
  stream.avail_in = static_cast<uInt>(std::min<size_t>(gz.size(), UINT32_MAX));
  stream.next_out = reinterpret_cast<Bytef*>(out.data());
  stream.avail_out = static_cast<uInt>(want);
  int result = Z_OK;
  while (stream.avail_out > 0 && result == Z_OK) result = inflate(&stream, Z_NO_FLUSH);
  out.resize(want - stream.avail_out);
  inflateEnd(&stream);
  return out;
}

Status CheckNifti(std::string_view field, std::string_view content) {
  std::string inflated;
  if (content.size() >= 2 && static_cast<unsigned char>(content[0]) == 0x1f &&
      static_cast<unsigned char>(content[1]) == 0x8b) {
    inflated = Gunzip(content, kNiftiHeaderBytes);
    content = inflated;
  }
  if (content.size() < kNiftiHeaderBytes) {
    return Status::InvalidArgument(std::string(field),
                                   "is not NIfTI-1: shorter than the 348-byte header");
  }
  uint32_t sizeof_hdr = 0;
  std::memcpy(&sizeof_hdr, content.data(), 4);
  const uint32_t swapped = __builtin_bswap32(sizeof_hdr);
  if (sizeof_hdr != kNiftiHeaderBytes && swapped != kNiftiHeaderBytes) {
    return Status::InvalidArgument(std::string(field), "is not NIfTI-1: sizeof_hdr is not 348");
  }
  const std::string_view magic = content.substr(344, 4);
  if (magic != std::string_view("n+1\0", 4) && magic != std::string_view("ni1\0", 4)) {
    return Status::InvalidArgument(std::string(field),
                                   "is not NIfTI-1: the magic is not \"n+1\" or \"ni1\"");
  }
  return Status::Ok();
}

Status CheckContoursJson(std::string_view field, std::string_view content) {
  google::protobuf::Value value;
  const auto parsed = google::protobuf::util::JsonStringToMessage(
      google::protobuf::StringPiece(content.data(), content.size()), &value);
  if (!parsed.ok()) {
    return Status::InvalidArgument(std::string(field), "is not valid JSON: " + parsed.ToString());
  }
  const bool non_empty = (value.has_struct_value() && value.struct_value().fields_size() > 0) ||
                         (value.has_list_value() && value.list_value().values_size() > 0);
  if (!non_empty) {
    return Status::InvalidArgument(std::string(field),
                                   "contours JSON must be a non-empty object or array");
  }
  return Status::Ok();
}

}  // namespace

Status CheckGeometryContent(std::string_view field, GeometryFormat format,
                            std::string_view content) {
  if (content.empty()) return Status::InvalidArgument(std::string(field), "must not be empty");
  switch (format) {
    case GeometryFormat::kContoursJson:
      return CheckContoursJson(field, content);
    case GeometryFormat::kNifti:
      return CheckNifti(field, content);
    case GeometryFormat::kStl:
    case GeometryFormat::kObj:
    case GeometryFormat::kVtk:
      return Status::Ok();
  }
  return Status::InvalidArgument(std::string(field), "unknown geometry format");
}

}  // namespace pba
