#include "atlas/colour_table.h"

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "core/atomic_write.h"
#include "core/format.h"

namespace pba {
namespace {

std::vector<ColourEntry> BuiltinEntries() {
  // Byte-wise alphabetical, so the id is the position (see AtlasLabel).
  static const struct {
    const char* name;
    int r, g, b;
  } kRows[] = {
      {"Corpus callosum", 130, 75, 130},
      {"Corpus geniculatum laterale", 90, 81, 76},
      {"Corpus geniculatum mediale", 86, 42, 54},
      {"Corpus mamillare", 100, 100, 200},
      {"Cortical areas", 0, 49, 134},
      {"Cuneus", 126, 0, 255},
      {"Fornix", 17, 73, 219},
      {"Globus pallidus lateralis", 0, 161, 91},
      {"Globus pallidus medialis", 0, 200, 91},
      {"Hippocampal gyrus", 182, 171, 154},
      {"Hippocampus", 179, 147, 179},
      {"Hypothalamus: LAT", 149, 24, 149},
      {"Hypothalamus: POL", 198, 185, 160},
      {"Hypothalamus: SO", 69, 61, 59},
      {"Hypothalamus: VM", 80, 249, 80},
      {"Inferior frontal gyrus", 0, 255, 126},
      {"Inferior occipital gyrus", 63, 63, 63},
      {"Inferior temporal gyrus", 214, 189, 148},
      {"Insula", 239, 206, 90},
      {"Lingual gyrus", 249, 119, 0},
      {"Medial frontal gyrus", 226, 175, 0},
      {"Middle frontal gyrus", 105, 77, 89},
      {"Middle occipital gyrus", 184, 38, 131},
      {"Middle temporal gyrus", 17, 12, 242},
      {"Nucleus accumbens septi", 80, 131, 80},
      {"Nucleus caudatus", 255, 239, 0},
      {"Nucleus ruber (bottom)", 186, 58, 77},
      {"Nucleus ruber (top)", 154, 89, 107},
      {"Nucleus subthalamicus", 0, 103, 174},
      {"Putamen", 0, 135, 91},
      {"Substantia nigra", 0, 0, 255},
      {"Thalamus: anterior", 214, 51, 86},
      {"Thalamus: centromedianum", 151, 93, 131},
      {"Thalamus: dorsomedial", 198, 73, 117},
      {"Thalamus: lateral dorsal", 131, 31, 63},
      {"Thalamus: lateral posterior", 207, 43, 100},
      {"Thalamus: others", 223, 112, 151},
      {"Thalamus: pulvinar", 189, 93, 154},
      {"Thalamus: ventral anterior", 228, 24, 253},
      {"Thalamus: ventral lateral", 161, 63, 126},
      {"Thalamus: ventral posterolateral", 195, 207, 49},
      {"Thalamus: ventral posteromedial", 172, 38, 86},
      {"Ventricles", 200, 0, 0},
      {"White matter", 219, 193, 161},
  };
  std::vector<ColourEntry> entries;
  uint16_t label = 1;
  for (const auto& row : kRows) {
    entries.push_back({label++, row.name, static_cast<uint8_t>(row.r), static_cast<uint8_t>(row.g),
                       static_cast<uint8_t>(row.b)});
  }
  return entries;
}

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) {
    s.remove_suffix(1);
  }
  return s;
}

bool ParseInt(std::string_view s, int min, int max, int* value) {
  if (s.empty()) return false;
  const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), *value);
  return error == std::errc() && end == s.data() + s.size() && *value >= min && *value <= max;
}

std::string RgbText(int r, int g, int b) { return Format("%d %d %d", r, g, b); }

}  // namespace

bool SplitDelimited(std::string_view line, char delimiter, std::vector<std::string>* fields) {
  fields->clear();
  std::string field;
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        field += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        field += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == delimiter) {
      fields->push_back(std::string(Trim(field)));
      field.clear();
    } else {
      field += c;
    }
  }
  fields->push_back(std::string(Trim(field)));
  return !quoted;
}

const ColourTable& ColourTable::Builtin() {
  static const ColourTable table = [] {
    ColourTable t;
    const Status status = FromEntries(BuiltinEntries(), &t);
    if (!status.ok()) std::abort();  // the built-in rows are a constant
    return t;
  }();
  return table;
}

Status ColourTable::FromEntries(std::vector<ColourEntry> entries, ColourTable* table) {
  std::map<uint16_t, const ColourEntry*> by_label;
  std::map<std::string, const ColourEntry*> by_name;
  std::map<uint32_t, const ColourEntry*> by_rgb;
  for (const ColourEntry& e : entries) {
    const std::string where = Format("entry '%s' (label %d)", e.name.c_str(), e.label);
    if (e.label == 0) {
      return Status::InvalidArgument("label", where + ": label 0 is reserved for background");
    }
    if (e.name.empty()) return Status::InvalidArgument("name", where + ": empty name");
    if (e.r == 0 && e.g == 0 && e.b == 0) {
      return Status::InvalidArgument("rgb", where + ": RGB 0 0 0 is reserved for background");
    }
    if (!by_label.emplace(e.label, &e).second) {
      return Status::InvalidArgument("label", where + ": duplicate label");
    }
    if (!by_name.emplace(e.name, &e).second) {
      return Status::InvalidArgument("name", where + ": duplicate name");
    }
    const uint32_t rgb = (uint32_t{e.r} << 16) | (uint32_t{e.g} << 8) | e.b;
    const auto [it, inserted] = by_rgb.emplace(rgb, &e);
    if (!inserted) {
      return Status::InvalidArgument("rgb", where + ": duplicate colour " + RgbText(e.r, e.g, e.b) +
                                                " (also '" + it->second->name + "')");
    }
  }
  std::sort(entries.begin(), entries.end(),
            [](const ColourEntry& a, const ColourEntry& b) { return a.label < b.label; });
  table->entries_ = std::move(entries);
  return Status::Ok();
}

const ColourEntry* ColourTable::FindByLabel(uint16_t label) const {
  const auto it = std::lower_bound(entries_.begin(), entries_.end(), label,
                                   [](const ColourEntry& e, uint16_t l) { return e.label < l; });
  return it != entries_.end() && it->label == label ? &*it : nullptr;
}

bool InStructureGroup(std::string_view name, std::string_view group) {
  return name.size() > group.size() + 1 && name.substr(0, group.size()) == group &&
         name[group.size()] == ':';
}

Status EntriesNamed(const ColourTable& table, const std::string& name, const std::string& field,
                    std::vector<const ColourEntry*>* entries) {
  entries->clear();
  if (const ColourEntry* entry = table.FindByName(name)) {
    entries->push_back(entry);
    return Status::Ok();
  }
  for (const ColourEntry& e : table.entries()) {
    if (InStructureGroup(e.name, name)) entries->push_back(&e);
  }
  if (entries->empty()) {
    return Status::InvalidArgument(
        field, "no structure \"" + name + "\" in the colour table (nor any \"" + name + ": ...\")");
  }
  return Status::Ok();
}

const ColourEntry* ColourTable::FindByName(std::string_view name) const {
  for (const ColourEntry& e : entries_) {
    if (e.name == name) return &e;
  }
  return nullptr;
}

const ColourEntry* ColourTable::FindByRgb(uint8_t r, uint8_t g, uint8_t b) const {
  for (const ColourEntry& e : entries_) {
    if (e.r == r && e.g == g && e.b == b) return &e;
  }
  return nullptr;
}

std::string FormatColourTableCsv(const ColourTable& table) {
  std::string text = std::string("# ") + kSyntheticAtlasNotice + "\nlabel,name,r,g,b\n";
  for (const ColourEntry& e : table.entries()) {
    text += Format("%d,%s,%d,%d,%d\n", e.label, CsvQuoted(e.name).c_str(), e.r, e.g, e.b);
  }
  return text;
}

Status ParseColourTableCsv(std::string_view text, const std::string& source, ColourTable* table) {
  std::vector<ColourEntry> entries;
  std::map<uint16_t, int> label_line;
  std::map<std::string, int> name_line;
  std::map<uint32_t, int> rgb_line;
  bool header_seen = false;
  int line_number = 0;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = Trim(text.substr(start, end - start));
    start = end + 1;
    ++line_number;
    if (line.empty() || line.front() == '#') continue;
    const auto error = [&](const std::string& what) {
      return Status::InvalidArgument(source, Format("line %d: ", line_number) + what);
    };
    std::vector<std::string> f;
    if (!SplitDelimited(line, ',', &f)) return error("an unterminated quote");
    if (!header_seen) {
      if (f.size() != 5 || f[0] != "label" || f[1] != "name" || f[2] != "r" || f[3] != "g" ||
          f[4] != "b") {
        return error("expected the header 'label,name,r,g,b', got '" + std::string(line) + "'");
      }
      header_seen = true;
      continue;
    }
    if (f.size() != 5) {
      return error(Format("expected 5 comma-separated fields (label,name,r,g,b), got %d",
                          static_cast<int>(f.size())));
    }
    int label = 0;
    if (!ParseInt(f[0], 1, 65535, &label)) {
      return error("label '" + std::string(f[0]) + "' is not an integer in 1..65535");
    }
    if (f[1].empty()) return error("empty name");
    int rgb[3];
    static const char* kChannel[] = {"r", "g", "b"};
    for (int c = 0; c < 3; ++c) {
      if (!ParseInt(f[2 + c], 0, 255, &rgb[c])) {
        return error(std::string(kChannel[c]) + " '" + std::string(f[2 + c]) +
                     "' is not an integer in 0..255");
      }
    }
    if (rgb[0] == 0 && rgb[1] == 0 && rgb[2] == 0) {
      return error("RGB 0 0 0 is reserved for background");
    }
    const std::string name(f[1]);
    const uint32_t key = (uint32_t(rgb[0]) << 16) | (uint32_t(rgb[1]) << 8) | uint32_t(rgb[2]);
    if (const auto [it, ok] = label_line.emplace(label, line_number); !ok) {
      return error(Format("duplicate label %d (first on line %d)", label, it->second));
    }
    if (const auto [it, ok] = name_line.emplace(name, line_number); !ok) {
      return error("duplicate name '" + name + Format("' (first on line %d)", it->second));
    }
    if (const auto [it, ok] = rgb_line.emplace(key, line_number); !ok) {
      return error("duplicate colour " + RgbText(rgb[0], rgb[1], rgb[2]) +
                   Format(" (first on line %d)", it->second));
    }
    entries.push_back({static_cast<uint16_t>(label), name, static_cast<uint8_t>(rgb[0]),
                       static_cast<uint8_t>(rgb[1]), static_cast<uint8_t>(rgb[2])});
  }
  if (!header_seen) return Status::InvalidArgument(source, "no header line 'label,name,r,g,b'");
  return ColourTable::FromEntries(std::move(entries), table);
}

Status WriteColourTableCsv(const ColourTable& table, const std::filesystem::path& path) {
  return AtomicWriteText(path, FormatColourTableCsv(table));
}

Status ReadColourTableCsv(const std::filesystem::path& path, ColourTable* table) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Io("cannot open " + path.string());
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return Status::Io("reading " + path.string() + " failed");
  return ParseColourTableCsv(text.str(), path.filename().string(), table);
}

}  // namespace pba
