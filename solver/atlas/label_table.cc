#include "atlas/label_table.h"

#include <tinyxml2.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "atlas/label_volume.h"
#include "core/format.h"

namespace pba {
namespace {

// One entry as a file gives it, before it is checked.
struct RawEntry {
  long label = 0;
  std::string name;
  bool coloured = false;
  int r = 0, g = 0, b = 0;
  int line = 0;  // 0: no line (XML)
};

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) {
    s.remove_suffix(1);
  }
  return s;
}

std::string Lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

bool ParseLong(std::string_view s, long* value) {
  if (s.empty()) return false;
  const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), *value);
  return error == std::errc() && end == s.data() + s.size();
}

bool ParseChannel(std::string_view s, int* value) {
  long v = 0;
  if (!ParseLong(s, &v) || v < 0 || v > 255) return false;
  *value = static_cast<int>(v);
  return true;
}

std::vector<std::string_view> Tokens(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

// Calls `visit(line_number, line)` for every line that is neither blank nor
// a '#' comment; stops at the first error it returns.
template <typename Visit>
Status ForEachLine(std::string_view text, const Visit& visit) {
  int number = 0;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = Trim(text.substr(start, end - start));
    start = end + 1;
    ++number;
    if (line.empty() || line.front() == '#') continue;
    PBA_RETURN_IF_ERROR(visit(number, line));
  }
  return Status::Ok();
}

// The first line that is neither blank nor a comment.
std::string_view FirstLine(std::string_view text) {
  std::string_view first;
  ForEachLine(text, [&](int, std::string_view line) {
    if (first.empty()) first = line;
    return Status::Ok();
  }).ok();
  return first;
}

// ---- The formats.

Status ParsePbaCsv(std::string_view text, const std::string& source, std::vector<RawEntry>* out) {
  bool header = false;
  std::vector<std::string> f;
  return ForEachLine(text, [&](int number, std::string_view line) -> Status {
    const auto error = [&](const std::string& what) {
      return Status::InvalidArgument(source, Format("line %d: ", number) + what);
    };
    if (!SplitDelimited(line, ',', &f)) return error("an unterminated quote");
    if (!header) {
      if (f.size() != 5 || f[0] != "label" || f[1] != "name" || f[2] != "r" || f[3] != "g" ||
          f[4] != "b") {
        return error("expected the header 'label,name,r,g,b'");
      }
      header = true;
      return Status::Ok();
    }
    if (f.size() != 5) {
      return error(Format("expected 5 fields (label,name,r,g,b), got %d", int(f.size())));
    }
    RawEntry e;
    e.line = number;
    if (!ParseLong(f[0], &e.label)) return error("label '" + f[0] + "' is not an integer");
    e.name = f[1];
    e.coloured = true;
    if (!ParseChannel(f[2], &e.r) || !ParseChannel(f[3], &e.g) || !ParseChannel(f[4], &e.b)) {
      return error("a colour channel is not an integer in 0..255");
    }
    out->push_back(std::move(e));
    return Status::Ok();
  });
}

// "value name [code]"; the colours from the .lut's planar bytes.
Status ParseMricron(std::string_view text, std::string_view lut, const std::string& source,
                    std::vector<RawEntry>* out) {
  return ForEachLine(text, [&](int number, std::string_view line) -> Status {
    const std::vector<std::string_view> t = Tokens(line);
    RawEntry e;
    e.line = number;
    if (t.size() < 2 || !ParseLong(t[0], &e.label)) {
      return Status::InvalidArgument(
          source, Format("line %d: expected 'value name [code]', got '%s'", number,
                         std::string(line).c_str()));
    }
    // A last integer after the name is the atlas's own code (AAL's 2001 ...).
    long code = 0;
    const std::size_t name_end =
        t.size() >= 3 && ParseLong(t.back(), &code) ? t.size() - 1 : t.size();
    for (std::size_t i = 1; i < name_end; ++i) {
      if (i > 1) e.name += ' ';
      e.name += t[i];
    }
    if (lut.size() == 768 && e.label >= 0 && e.label < 256) {
      e.coloured = true;
      e.r = static_cast<unsigned char>(lut[e.label]);
      e.g = static_cast<unsigned char>(lut[256 + e.label]);
      e.b = static_cast<unsigned char>(lut[512 + e.label]);
    }
    out->push_back(std::move(e));
    return Status::Ok();
  });
}

// "value name r g b a" (Slicer's colour table).
Status ParseSlicer(std::string_view text, const std::string& source, std::vector<RawEntry>* out) {
  return ForEachLine(text, [&](int number, std::string_view line) -> Status {
    const std::vector<std::string_view> t = Tokens(line);
    RawEntry e;
    e.line = number;
    if (t.size() < 5 || !ParseLong(t[0], &e.label) || !ParseChannel(t[2], &e.r) ||
        !ParseChannel(t[3], &e.g) || !ParseChannel(t[4], &e.b)) {
      return Status::InvalidArgument(
          source, Format("line %d: expected 'value name r g b a', got '%s'", number,
                         std::string(line).c_str()));
    }
    e.name = std::string(t[1]);
    e.coloured = true;
    out->push_back(std::move(e));
    return Status::Ok();
  });
}

// Slicer's .csv / .tsv: a header naming the columns.
Status ParseSlicerCsv(std::string_view text, char delimiter, const std::string& source,
                      std::vector<RawEntry>* out) {
  int value = -1, name = -1, red = -1, green = -1, blue = -1;
  bool header = false;
  std::vector<std::string> f;
  return ForEachLine(text, [&](int number, std::string_view line) -> Status {
    const auto error = [&](const std::string& what) {
      return Status::InvalidArgument(source, Format("line %d: ", number) + what);
    };
    if (!SplitDelimited(line, delimiter, &f)) return error("an unterminated quote");
    if (!header) {
      for (int i = 0; i < static_cast<int>(f.size()); ++i) {
        const std::string column = Lower(f[i]);
        if (column == "labelvalue") value = i;
        if (column == "name") name = i;
        if (column == "color_r") red = i;
        if (column == "color_g") green = i;
        if (column == "color_b") blue = i;
      }
      if (value < 0 || name < 0) return error("the header names no LabelValue and Name columns");
      header = true;
      return Status::Ok();
    }
    const int needed = std::max({value, name, red, green, blue});
    if (static_cast<int>(f.size()) <= needed) {
      return error(Format("expected at least %d fields, got %d", needed + 1, int(f.size())));
    }
    RawEntry e;
    e.line = number;
    if (!ParseLong(f[value], &e.label)) return error("value '" + f[value] + "' is not an integer");
    e.name = f[name];
    if (red >= 0 && green >= 0 && blue >= 0) {
      if (!ParseChannel(f[red], &e.r) || !ParseChannel(f[green], &e.g) ||
          !ParseChannel(f[blue], &e.b)) {
        return error("a colour channel is not an integer in 0..255");
      }
      e.coloured = true;
    }
    out->push_back(std::move(e));
    return Status::Ok();
  });
}

// ITK-SNAP: value r g b a visible mesh "name".
Status ParseItkSnap(std::string_view text, const std::string& source, std::vector<RawEntry>* out) {
  return ForEachLine(text, [&](int number, std::string_view line) -> Status {
    const auto error = [&]() {
      return Status::InvalidArgument(
          source, Format("line %d: expected 'value r g b a visible mesh \"name\"', got '%s'",
                         number, std::string(line).c_str()));
    };
    const std::size_t open = line.find('"'), close = line.rfind('"');
    if (open == std::string_view::npos || close <= open) return error();
    const std::vector<std::string_view> t = Tokens(line.substr(0, open));
    RawEntry e;
    e.line = number;
    if (t.size() < 4 || !ParseLong(t[0], &e.label) || !ParseChannel(t[1], &e.r) ||
        !ParseChannel(t[2], &e.g) || !ParseChannel(t[3], &e.b)) {
      return error();
    }
    e.name = std::string(Trim(line.substr(open + 1, close - open - 1)));
    e.coloured = true;
    out->push_back(std::move(e));
    return Status::Ok();
  });
}

Status ParseFslXml(std::string_view text, const std::string& source, std::vector<RawEntry>* out,
                   std::vector<std::string>* notes) {
  tinyxml2::XMLDocument document;
  if (document.Parse(text.data(), text.size()) != tinyxml2::XML_SUCCESS) {
    return Status::InvalidArgument(source, std::string("not well-formed XML: ") +
                                               (document.ErrorStr() ? document.ErrorStr() : ""));
  }
  const tinyxml2::XMLElement* atlas = document.FirstChildElement("atlas");
  const tinyxml2::XMLElement* data = atlas ? atlas->FirstChildElement("data") : nullptr;
  if (data == nullptr) {
    return Status::InvalidArgument(source, "not an FSL atlas description (<atlas><data>)");
  }
  const tinyxml2::XMLElement* header = atlas->FirstChildElement("header");
  const tinyxml2::XMLElement* type_element = header ? header->FirstChildElement("type") : nullptr;
  const std::string type =
      Lower(type_element && type_element->GetText() ? type_element->GetText() : "");
  // FSL's summary image of a probabilistic atlas numbers its structures
  // from 1, its XML from 0; a label atlas's image holds the indices.
  const bool probabilistic = type.rfind("probab", 0) == 0;
  if (type != "label" && !probabilistic) {
    return Status::InvalidArgument(
        source, "the atlas's <type> is '" + type + "', neither Label nor Probabilistic");
  }
  if (probabilistic) {
    notes->push_back(
        "FSL probabilistic atlas: its labels are read as the summary (maxprob) image numbers them, "
        "index + 1");
  }
  int n = 0;
  for (const tinyxml2::XMLElement* label = data->FirstChildElement("label"); label != nullptr;
       label = label->NextSiblingElement("label")) {
    ++n;
    int64_t index = 0;
    if (label->QueryInt64Attribute("index", &index) != tinyxml2::XML_SUCCESS) {
      return Status::InvalidArgument(source, Format("<label> %d has no integer index", n));
    }
    // Bounded before the + 1; Finish names a value outside 1..65535.
    index = std::clamp<int64_t>(index, -1, 65536);
    RawEntry e;
    e.label = static_cast<long>(index + (probabilistic ? 1 : 0));
    e.name = label->GetText() ? std::string(Trim(label->GetText())) : "";
    out->push_back(std::move(e));
  }
  return Status::Ok();
}

// ---- Telling them apart.

bool AllChannels(const std::vector<std::string_view>& t, std::size_t first) {
  int ignored = 0;
  for (std::size_t i = first; i < first + 3 && i < t.size(); ++i) {
    if (!ParseChannel(t[i], &ignored)) return false;
  }
  return t.size() >= first + 3;
}

Status Detect(std::string_view text, std::string_view extension, const std::string& source,
              LabelTableFormat* format) {
  const std::string ext = Lower(extension);
  if (ext == ".xml") return *format = LabelTableFormat::kFslXml, Status::Ok();
  if (ext == ".ctbl") return *format = LabelTableFormat::kSlicer, Status::Ok();
  const std::string_view first = FirstLine(text);
  const std::string lower = Lower(first);
  long ignored = 0;
  if (lower.rfind("labelvalue", 0) == 0) {
    *format = LabelTableFormat::kSlicerCsv;
  } else if (std::vector<std::string> f;
             SplitDelimited(lower, ',', &f) &&
             f == std::vector<std::string>{"label", "name", "r", "g", "b"}) {
    *format = LabelTableFormat::kPbaCsv;
  } else if (text.find("ITK-SnAP") != std::string_view::npos ||
             (first.find('"') != std::string_view::npos && AllChannels(Tokens(first), 1))) {
    *format = LabelTableFormat::kItkSnap;
  } else if (const auto t = Tokens(first);
             t.size() >= 2 && ParseLong(t[0], &ignored) && t.size() <= 3) {
    *format = LabelTableFormat::kMricron;
  } else if (t.size() == 6 && ParseLong(t[0], &ignored) && AllChannels(t, 2)) {
    *format = LabelTableFormat::kSlicer;
  } else {
    return Status::InvalidArgument(
        source,
        "not a label table PBA reads (its first line is '" + std::string(first.substr(0, 80)) +
            "'): PBA CSV (label,name,r,g,b), MRIcron/AAL .txt (value name [code], with its .lut), "
            "FSL atlas .xml, 3D Slicer .ctbl/.txt (value name r g b a) or .csv/.tsv "
            "(LabelValue,Name,Color_R,...), ITK-SNAP label descriptions");
  }
  return Status::Ok();
}

// Distinct display colours: hues a golden angle apart, three levels of
// saturation and value, none black and none `taken`.
uint32_t NextColour(int* counter, const std::set<uint32_t>& taken) {
  // Past the hues' few thousand distinct 8-bit colours, every colour in
  // turn: a table of up to 65,535 structures always gets its colours.
  constexpr int kHues = 20000;
  while (*counter >= kHues) {
    const uint32_t packed = static_cast<uint32_t>((*counter)++ - kHues + 1);
    if (taken.count(packed) == 0) return packed;
  }
  while (true) {
    const int k = (*counter)++;
    if (k >= kHues) return NextColour(counter, taken);
    const double hue = std::fmod(k * 137.50776405, 360.0) / 60.0;
    const double s = 0.55 + 0.15 * (k % 3), v = 0.95 - 0.15 * ((k / 3) % 3);
    const double c = v * s, x = c * (1 - std::abs(std::fmod(hue, 2.0) - 1)), m = v - c;
    double rgb[3] = {0, 0, 0};
    const int sector = static_cast<int>(hue) % 6;
    const int order[6][3] = {{0, 1, 2}, {1, 0, 2}, {2, 0, 1}, {2, 1, 0}, {1, 2, 0}, {0, 2, 1}};
    rgb[order[sector][0]] = c;
    rgb[order[sector][1]] = x;
    uint32_t packed = 0;
    for (int i = 0; i < 3; ++i) {
      packed = (packed << 8) | static_cast<uint32_t>(std::lround(255 * (rgb[i] + m)));
    }
    if (packed != 0 && taken.count(packed) == 0) return packed;
  }
}

// Checks the entries and builds the table, colouring those without a
// colour of their own.
Status Finish(std::vector<RawEntry> raw, const std::string& source, ColourTable* table,
              LabelTableRead* read) {
  std::vector<RawEntry> kept;
  std::map<long, const RawEntry*> by_label;
  std::map<std::string, const RawEntry*> by_name;
  const auto where = [](const RawEntry& e) {
    return e.line > 0 ? Format("line %d: ", e.line) : std::string();
  };
  for (RawEntry& e : raw) {
    if (e.label == 0) {
      read->notes.push_back("value 0 ('" + e.name + "') is background and not a structure");
      continue;
    }
    if (e.label < 1 || e.label > 65535) {
      return Status::InvalidArgument(source,
                                     where(e) + Format("value %ld is outside 1..65535", e.label));
    }
    if (e.name.empty()) {
      return Status::InvalidArgument(source, where(e) + Format("value %ld has no name", e.label));
    }
    kept.push_back(std::move(e));
  }
  if (kept.empty()) return Status::InvalidArgument(source, "the table names no structure");
  for (const RawEntry& e : kept) {
    if (const auto [it, ok] = by_label.emplace(e.label, &e); !ok) {
      return Status::InvalidArgument(
          source, where(e) + Format("value %ld is given twice ('%s' and '%s')", e.label,
                                    it->second->name.c_str(), e.name.c_str()));
    }
    if (const auto [it, ok] = by_name.emplace(e.name, &e); !ok) {
      return Status::InvalidArgument(
          source, where(e) + Format("the name '%s' is given to values %ld and %ld", e.name.c_str(),
                                    it->second->label, e.label));
    }
  }
  // The first label with a colour keeps it; black, repeated and missing
  // colours are chosen.
  std::set<uint32_t> taken;
  std::vector<bool> keeps(kept.size(), false);
  for (std::size_t i = 0; i < kept.size(); ++i) {
    const RawEntry& e = kept[i];
    const uint32_t packed = (uint32_t(e.r) << 16) | (uint32_t(e.g) << 8) | uint32_t(e.b);
    keeps[i] = e.coloured && packed != 0 && taken.insert(packed).second;
  }
  int counter = 0, chosen = 0, black = 0, repeated = 0, missing = 0;
  std::vector<ColourEntry> entries;
  for (std::size_t i = 0; i < kept.size(); ++i) {
    const RawEntry& e = kept[i];
    ColourEntry out{static_cast<uint16_t>(e.label), e.name, 0, 0, 0};
    uint32_t packed = (uint32_t(e.r) << 16) | (uint32_t(e.g) << 8) | uint32_t(e.b);
    if (!keeps[i]) {
      ++chosen;
      (!e.coloured ? missing : packed == 0 ? black : repeated) += 1;
      packed = NextColour(&counter, taken);
      taken.insert(packed);
    }
    out.r = static_cast<uint8_t>(packed >> 16);
    out.g = static_cast<uint8_t>(packed >> 8);
    out.b = static_cast<uint8_t>(packed);
    entries.push_back(std::move(out));
  }
  if (chosen > 0) {
    std::vector<std::string> why;
    if (missing > 0) why.push_back(Format("%d without a colour", missing));
    if (black > 0) why.push_back(Format("%d black", black));
    if (repeated > 0) why.push_back(Format("%d repeating another's colour", repeated));
    std::string reasons;
    for (std::size_t i = 0; i < why.size(); ++i) reasons += (i > 0 ? ", " : "") + why[i];
    read->notes.push_back(
        Format("%d of the %d structures got a display colour of PBA's choosing (%s in the table): "
               "colours are for display, a structure is its value and name",
               chosen, static_cast<int>(entries.size()), reasons.c_str()));
  }
  return ColourTable::FromEntries(std::move(entries), table);
}

Status ReadBounded(const std::filesystem::path& path, std::uintmax_t limit, std::string* text) {
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(path, error);
  if (error) return Status::Io("cannot read " + path.string() + ": " + error.message());
  if (size > limit) {
    return Status::InvalidArgument(path.filename().string(),
                                   Format("%ju bytes, more than a label table's %ju", size, limit));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Io("cannot open " + path.string());
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) return Status::Io("reading " + path.string() + " failed");
  *text = buffer.str();
  return Status::Ok();
}

}  // namespace

const char* LabelTableFormatName(LabelTableFormat format) {
  switch (format) {
    case LabelTableFormat::kPbaCsv:
      return "PBA CSV";
    case LabelTableFormat::kMricron:
      return "MRIcron";
    case LabelTableFormat::kFslXml:
      return "FSL atlas XML";
    case LabelTableFormat::kSlicer:
      return "3D Slicer colour table";
    case LabelTableFormat::kSlicerCsv:
      return "3D Slicer CSV";
    case LabelTableFormat::kItkSnap:
      return "ITK-SNAP label description";
  }
  return "?";
}

Status ParseLabelTable(std::string_view text, std::string_view extension, std::string_view lut,
                       const std::string& source, ColourTable* table, LabelTableRead* read) {
  LabelTableRead result;
  PBA_RETURN_IF_ERROR(Detect(text, extension, source, &result.format));
  std::vector<RawEntry> raw;
  switch (result.format) {
    case LabelTableFormat::kPbaCsv:
      PBA_RETURN_IF_ERROR(ParsePbaCsv(text, source, &raw));
      break;
    case LabelTableFormat::kMricron:
      PBA_RETURN_IF_ERROR(ParseMricron(text, lut, source, &raw));
      break;
    case LabelTableFormat::kFslXml:
      PBA_RETURN_IF_ERROR(ParseFslXml(text, source, &raw, &result.notes));
      break;
    case LabelTableFormat::kSlicer:
      PBA_RETURN_IF_ERROR(ParseSlicer(text, source, &raw));
      break;
    case LabelTableFormat::kSlicerCsv:
      PBA_RETURN_IF_ERROR(
          ParseSlicerCsv(text, Lower(extension) == ".tsv" ? '\t' : ',', source, &raw));
      break;
    case LabelTableFormat::kItkSnap:
      PBA_RETURN_IF_ERROR(ParseItkSnap(text, source, &raw));
      break;
  }
  result.notes.insert(
      result.notes.begin(),
      source + Format(": %s", LabelTableFormatName(result.format)) +
          (result.format == LabelTableFormat::kMricron
               ? (lut.size() == 768 ? ", colours from its .lut" : ", no .lut beside it")
               : ""));
  ColourTable built;
  PBA_RETURN_IF_ERROR(Finish(std::move(raw), source, &built, &result));
  *table = std::move(built);
  read->format = result.format;
  read->notes = std::move(result.notes);
  return Status::Ok();
}

void ChooseDisplayColour(const ColourTable& table, ColourEntry* entry) {
  std::set<uint32_t> taken;
  for (const ColourEntry& e : table.entries()) {
    taken.insert((uint32_t(e.r) << 16) | (uint32_t(e.g) << 8) | uint32_t(e.b));
  }
  int counter = 0;
  const uint32_t packed = NextColour(&counter, taken);
  entry->r = static_cast<uint8_t>(packed >> 16);
  entry->g = static_cast<uint8_t>(packed >> 8);
  entry->b = static_cast<uint8_t>(packed);
}

Status LabelVolumeNeedsATable(const LabelVolume& volume, const std::string& field) {
  if (volume.description() == kSyntheticAtlasNotice) return Status::Ok();
  return Status::InvalidArgument(
      field,
      "a label volume needs its label table (--colour-table; PBA CSV, MRIcron, FSL, Slicer or "
      "ITK-SNAP): without one its values would take the synthetic atlas's names, wrong for any "
      "other atlas; only the synthetic atlas's own volume goes without");
}

std::vector<std::filesystem::path> LabelTableFiles(const std::filesystem::path& path) {
  std::vector<std::filesystem::path> files = {path};
  // An MRIcron table's colours: the .lut of the same stem ("aal.nii.txt",
  // "aal.nii.lut").
  std::filesystem::path lut = path;
  lut.replace_extension(".lut");
  std::error_code error;
  if (Lower(path.extension().string()) == ".txt" && lut != path &&
      std::filesystem::is_regular_file(lut, error)) {
    files.push_back(lut);
  }
  return files;
}

Status ReadLabelTable(const std::filesystem::path& path, ColourTable* table, LabelTableRead* read) {
  std::string text, lut;
  PBA_RETURN_IF_ERROR(ReadBounded(path, kMaxLabelTableBytes, &text));
  const std::vector<std::filesystem::path> files = LabelTableFiles(path);
  if (files.size() > 1) {
    std::error_code error;
    const std::uintmax_t size = std::filesystem::file_size(files[1], error);
    if (error || size != 768) {
      return Status::InvalidArgument(
          files[1].filename().string(),
          error ? "cannot be read: " + error.message()
                : Format("%ju bytes, not an MRIcron .lut's 768 (256 red, green, blue)", size));
    }
    PBA_RETURN_IF_ERROR(ReadBounded(files[1], 768, &lut));
  }
  PBA_RETURN_IF_ERROR(
      ParseLabelTable(text, path.extension().string(), lut, path.filename().string(), table, read));
  read->files = {path};
  if (read->format == LabelTableFormat::kMricron && !lut.empty()) read->files.push_back(files[1]);
  return Status::Ok();
}

}  // namespace pba
