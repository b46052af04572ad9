#include "atlas/plates.h"

#include <stdlib.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <system_error>
#include <unordered_map>

#include "core/atomic_write.h"
#include "core/format.h"
#include "core/number_format.h"
#include "core/yaml_guard.h"
#include "io/png_io.h"

namespace pba {
namespace fs = std::filesystem;
namespace {

constexpr char kIndexFile[] = "plates.json";
constexpr char kColourFile[] = "colour_table.csv";
constexpr char kFormat[] = "pba-atlas-plates";

std::string PlateFileName(int index, int count) {
  std::string number = std::to_string(index + 1);
  const size_t digits = std::max<size_t>(2, std::to_string(count).size());
  number.insert(0, digits - std::min(digits, number.size()), '0');
  return "plate_" + number + ".png";
}

struct Grid {
  double pixel = 0;
  Eigen::Vector2d origin;
  int width = 0, height = 0;
};

// Pixels tile the volume's x-y extent from face to face.
Grid PlateGrid(const LabelVolume& v, double pixel) {
  const Eigen::Vector3d lo = v.origin_mm() - 0.5 * v.spacing_mm();
  const Eigen::Vector3d hi =
      v.VoxelCentreMm(v.nx() - 1, v.ny() - 1, v.nz() - 1) + 0.5 * v.spacing_mm();
  Grid g;
  g.pixel = pixel;
  g.width = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / pixel - 1e-9)));
  g.height = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / pixel - 1e-9)));
  g.origin = Eigen::Vector2d(lo.x() + 0.5 * pixel, hi.y() - 0.5 * pixel);
  return g;
}

std::string IndexJson(const Grid& g, const std::vector<double>& z,
                      const std::vector<std::string>& files) {
  std::string json = "{\n";
  json += "  \"notice\": " + JsonQuoted(kSyntheticAtlasNotice) + ",\n";
  json += "  \"format\": " + JsonQuoted(kFormat) + ",\n  \"version\": 1,\n";
  json += "  \"colour_table\": " + JsonQuoted(kColourFile) + ",\n";
  json += "  \"pixel_size_mm\": " + RoundTripNumber(g.pixel) + ",\n";
  json += "  \"origin_mm\": [" + RoundTripNumber(g.origin.x()) + ", " +
          RoundTripNumber(g.origin.y()) + "],\n";
  json += Format("  \"width\": %d,\n  \"height\": %d,\n  \"plates\": [\n", g.width, g.height);
  for (size_t p = 0; p < z.size(); ++p) {
    json += "    {\"file\": " + JsonQuoted(files[p]) + ", \"z_mm\": " + RoundTripNumber(z[p]) +
            "}" + (p + 1 < z.size() ? ",\n" : "\n");
  }
  return json + "  ]\n}\n";
}

Status WriteAll(const LabelVolume& volume, const ColourTable& colours, const PlateOptions& options,
                const fs::path& dir) {
  const Grid g = PlateGrid(volume, options.pixel_size_mm);
  std::vector<const ColourEntry*> colour_of(65536, nullptr);
  for (const ColourEntry& e : colours.entries()) colour_of[e.label] = &e;
  std::vector<std::string> files;
  const int count = static_cast<int>(options.z_mm.size());
  for (int p = 0; p < count; ++p) {
    files.push_back(PlateFileName(p, count));
    RgbImage image;
    image.width = g.width;
    image.height = g.height;
    image.rgb.assign(static_cast<size_t>(g.width) * g.height * 3, 0);
    image.text = {{"Comment", kSyntheticAtlasNotice},
                  {"Title", Format("PBA synthetic atlas plate %d of %d, z = ", p + 1, count) +
                                RoundTripNumber(options.z_mm[p]) + " mm"}};
    for (int r = 0; r < g.height; ++r) {
      for (int c = 0; c < g.width; ++c) {
        const Eigen::Vector3d point(g.origin.x() + c * g.pixel, g.origin.y() - r * g.pixel,
                                    options.z_mm[p]);
        const uint16_t label = volume.SampleNearest(point);
        if (label == 0) continue;
        const ColourEntry* e = colour_of[label];
        if (e == nullptr) {
          return Status::InvalidArgument(
              "colours", Format("label %d (at x %g, y %g, z %g mm, plate %s) has no colour in the "
                                "colour table",
                                label, point.x(), point.y(), point.z(), files.back().c_str()));
        }
        uint8_t* px = &image.rgb[(static_cast<size_t>(r) * g.width + c) * 3];
        px[0] = e->r;
        px[1] = e->g;
        px[2] = e->b;
      }
    }
    PBA_RETURN_IF_ERROR(WriteRgbPng(dir / files.back(), image));
  }
  PBA_RETURN_IF_ERROR(WriteColourTableCsv(colours, dir / kColourFile));
  return AtomicWriteText(dir / kIndexFile, IndexJson(g, options.z_mm, files));
}

// A plain file name inside the plate directory.
bool SafeFileName(const std::string& name) {
  return !name.empty() && name != "." && name != ".." && name.find('/') == std::string::npos &&
         name.find('\\') == std::string::npos;
}

Status ReadIndex(const fs::path& dir, PlateStack* stack, std::string* colour_file) {
  const fs::path path = dir / kIndexFile;
  if (!fs::exists(path)) return Status::Io("missing " + path.string());
  const auto bad = [](const std::string& field, const std::string& what) {
    return Status::InvalidArgument(std::string(kIndexFile) + ":" + field, what);
  };
  // Aliases refused and the size capped before loading (core/yaml_guard.h).
  std::string text;
  PBA_RETURN_IF_ERROR(ReadYamlFileText(path, kIndexFile, &text));
  try {
    const YAML::Node root = YAML::Load(text);
    if (!root.IsMap()) return bad("", "not a JSON object");
    if (!root["format"] || root["format"].as<std::string>() != kFormat) {
      return bad("format", std::string("expected \"") + kFormat + "\"");
    }
    *colour_file = root["colour_table"] ? root["colour_table"].as<std::string>() : kColourFile;
    if (!SafeFileName(*colour_file)) return bad("colour_table", "not a plain file name");
    stack->pixel_size_mm = root["pixel_size_mm"].as<double>();
    if (!(stack->pixel_size_mm > 0) || !std::isfinite(stack->pixel_size_mm)) {
      return bad("pixel_size_mm", "must be positive");
    }
    const YAML::Node origin = root["origin_mm"];
    if (!origin.IsSequence() || origin.size() != 2) return bad("origin_mm", "expected [x, y]");
    stack->origin_mm = Eigen::Vector2d(origin[0].as<double>(), origin[1].as<double>());
    stack->width = root["width"].as<int>();
    stack->height = root["height"].as<int>();
    if (stack->width <= 0 || stack->height <= 0)
      return bad("width", "width and height must be positive");
    const YAML::Node plates = root["plates"];
    if (!plates.IsSequence() || plates.size() == 0)
      return bad("plates", "expected a non-empty list");
    for (size_t p = 0; p < plates.size(); ++p) {
      const std::string field = Format("plates[%d]", static_cast<int>(p));
      const std::string file = plates[p]["file"].as<std::string>();
      if (!SafeFileName(file))
        return bad(field + ".file", "'" + file + "' is not a plain file name");
      const double z = plates[p]["z_mm"].as<double>();
      if (!std::isfinite(z)) return bad(field + ".z_mm", "not a finite number");
      if (p > 0 && !(z > stack->z_mm.back())) {
        return bad(field + ".z_mm",
                   Format("plate '%s' at z %g mm is not above the previous plate '%s' at z %g mm",
                          file.c_str(), z, stack->files.back().c_str(), stack->z_mm.back()));
      }
      stack->files.push_back(file);
      stack->z_mm.push_back(z);
    }
  } catch (const YAML::Exception& e) {
    return bad("", std::string("malformed: ") + e.what());
  }
  return Status::Ok();
}

}  // namespace

std::vector<double> DefaultPlateHeightsMm() {
  std::vector<double> z = {-48, -43, -38, -33, -28, -24, -20};
  for (double h = -16; h <= 20; h += 3) z.push_back(h);
  for (double h : {24, 28, 33, 38, 43, 48, 53}) z.push_back(h);
  return z;
}

Status PlateOptions::Validate() const {
  if (!(pixel_size_mm > 0 && pixel_size_mm <= 10)) {
    return Status::InvalidArgument("pixel_size_mm",
                                   Format("%g is outside (0, 10] mm", pixel_size_mm));
  }
  if (z_mm.empty()) return Status::InvalidArgument("z_mm", "no plate heights");
  for (size_t p = 0; p < z_mm.size(); ++p) {
    if (!std::isfinite(z_mm[p]) || (p > 0 && !(z_mm[p] > z_mm[p - 1]))) {
      return Status::InvalidArgument(Format("z_mm[%d]", static_cast<int>(p)),
                                     Format("%g is not above the previous height", z_mm[p]));
    }
  }
  return Status::Ok();
}

Status ValidatePlateStack(const PlateStack& stack, const std::string& name, int min_plates) {
  if (stack.num_plates() < min_plates) {
    return Status::InvalidArgument(
        name + ".z_mm", Format("%d plate(s); at least %d needed", stack.num_plates(), min_plates));
  }
  if (!(stack.pixel_size_mm > 0) || !std::isfinite(stack.pixel_size_mm)) {
    return Status::InvalidArgument(name + ".pixel_size_mm",
                                   Format("%g is not a positive size", stack.pixel_size_mm));
  }
  if (stack.width < 1 || stack.height < 1) {
    return Status::InvalidArgument(name + ".width",
                                   Format("plates of %d x %d pixels", stack.width, stack.height));
  }
  if (!stack.origin_mm.allFinite())
    return Status::InvalidArgument(name + ".origin_mm", "not finite");
  if (stack.labels.size() != stack.z_mm.size()) {
    return Status::InvalidArgument(
        name + ".labels",
        Format("%zu plates of labels for %zu heights", stack.labels.size(), stack.z_mm.size()));
  }
  const size_t pixels = static_cast<size_t>(stack.width) * stack.height;
  for (int p = 0; p < stack.num_plates(); ++p) {
    if (stack.labels[p].size() != pixels) {
      return Status::InvalidArgument(Format("%s.labels[%d]", name.c_str(), p),
                                     Format("%zu labels for %d x %d pixels", stack.labels[p].size(),
                                            stack.width, stack.height));
    }
    if (!std::isfinite(stack.z_mm[p]) || (p > 0 && !(stack.z_mm[p] > stack.z_mm[p - 1]))) {
      return Status::InvalidArgument(Format("%s.z_mm[%d]", name.c_str(), p),
                                     Format("%g is not above the previous plate", stack.z_mm[p]));
    }
  }
  return Status::Ok();
}

Status WritePlates(const LabelVolume& volume, const ColourTable& colours,
                   const PlateOptions& options, const fs::path& dir) {
  PBA_RETURN_IF_ERROR(options.Validate());
  if (volume.num_voxels() == 0) return Status::InvalidArgument("volume", "empty label volume");
  return AtomicWriteDirectory(dir, [&](const fs::path& temporary) {
    return WriteAll(volume, colours, options, temporary);
  });
}

Status ReadPlateColours(const fs::path& dir, ColourTable* colours) {
  PlateStack read;
  std::string colour_file;
  PBA_RETURN_IF_ERROR(ReadIndex(dir, &read, &colour_file));
  return ReadColourTableCsv(dir / colour_file, colours);
}

Status ReadPlates(const fs::path& dir, PlateStack* stack) {
  PlateStack read;
  std::string colour_file;
  PBA_RETURN_IF_ERROR(ReadIndex(dir, &read, &colour_file));
  PBA_RETURN_IF_ERROR(ReadColourTableCsv(dir / colour_file, &read.colours));
  std::unordered_map<uint32_t, uint16_t> label_of = {{0u, uint16_t{0}}};
  for (const ColourEntry& e : read.colours.entries()) {
    label_of[(uint32_t{e.r} << 16) | (uint32_t{e.g} << 8) | e.b] = e.label;
  }
  for (int p = 0; p < read.num_plates(); ++p) {
    const std::string& file = read.files[p];
    RgbImage image;
    if (!fs::exists(dir / file)) return Status::Io("missing plate " + (dir / file).string());
    PBA_RETURN_IF_ERROR(ReadRgbPng(dir / file, &image));
    if (image.width != read.width || image.height != read.height) {
      return Status::InvalidArgument(
          file, Format("plate is %d x %d pixels, %s says %d x %d", image.width, image.height,
                       kIndexFile, read.width, read.height));
    }
    std::vector<uint16_t> labels(static_cast<size_t>(read.width) * read.height);
    // Colours not in the table, in order of appearance: first pixel, count.
    std::vector<std::pair<uint32_t, std::pair<size_t, int64_t>>> unknown;
    for (size_t i = 0; i < labels.size(); ++i) {
      const uint8_t* px = &image.rgb[3 * i];
      const uint32_t rgb = (uint32_t{px[0]} << 16) | (uint32_t{px[1]} << 8) | px[2];
      const auto it = label_of.find(rgb);
      if (it != label_of.end()) {
        labels[i] = it->second;
        continue;
      }
      const auto seen = std::find_if(unknown.begin(), unknown.end(),
                                     [rgb](const auto& u) { return u.first == rgb; });
      if (seen == unknown.end()) {
        unknown.push_back({rgb, {i, 1}});
      } else {
        ++seen->second.second;
      }
    }
    if (!unknown.empty()) {
      // Every colour is listed (up to kListed), none is matched to a near
      // one: an anti-aliased or recoloured plate must be fixed at its source.
      constexpr std::size_t kListed = 8;
      std::string listed;
      for (std::size_t u = 0; u < std::min(unknown.size(), kListed); ++u) {
        const uint32_t rgb = unknown[u].first;
        const size_t first = unknown[u].second.first;
        listed +=
            Format("%sRGB %d %d %d (%lld pixel%s, first at column %d, row %d)", u == 0 ? "" : "; ",
                   static_cast<int>(rgb >> 16), static_cast<int>((rgb >> 8) & 255),
                   static_cast<int>(rgb & 255), static_cast<long long>(unknown[u].second.second),
                   unknown[u].second.second == 1 ? "" : "s", static_cast<int>(first % read.width),
                   static_cast<int>(first / read.width));
      }
      if (unknown.size() > kListed) {
        listed += Format("; and %d more", static_cast<int>(unknown.size() - kListed));
      }
      return Status::InvalidArgument(
          file, Format("%d colour%s not in %s: %s. Colours must match the table exactly; none "
                       "is matched to a nearby one (an anti-aliased or resampled plate needs "
                       "its colours restored)",
                       static_cast<int>(unknown.size()), unknown.size() == 1 ? "" : "s",
                       colour_file.c_str(), listed.c_str()));
    }
    read.labels.push_back(std::move(labels));
  }
  *stack = std::move(read);
  return Status::Ok();
}

}  // namespace pba
