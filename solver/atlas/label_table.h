// Label tables as atlases ship them: the names of a label volume's values,
// read into a ColourTable. A label's identity is its value and its name;
// colours are for display, so a table may give the same colour to several
// labels, black to some, or none at all: PBA keeps each colour the first
// label gives it and picks a distinct display colour for the others, and
// says how many (the notes).
//
// Formats (ReadLabelTable tells them apart by extension and content):
//   PBA CSV             label,name,r,g,b (colour_table.h)
//   MRIcron / AAL .txt  "value name [code]" per line, colours from the
//                       256-entry .lut of the same stem beside it (planar
//                       R, G, B bytes), if there is one
//   FSL atlas XML       <atlas><header><type>..</type></header><data>
//                       <label index="i">name</label>..; a label atlas's
//                       values are its indices, a probabilistic atlas's
//                       summary (maxprob) image holds index + 1
//   3D Slicer           colour table .ctbl / .txt: "value name r g b a";
//                       .csv / .tsv with the header LabelValue,Name,
//                       Color_R,Color_G,Color_B[,Color_A]
//   ITK-SNAP            label description: "value r g b a vis msh "name""
// Value 0 is background in every format: a table's entry for it
// ("Unclassified", "Background") is left out.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "atlas/colour_table.h"
#include "pba/status.h"

namespace pba {

enum class LabelTableFormat { kPbaCsv, kMricron, kFslXml, kSlicer, kSlicerCsv, kItkSnap };

// "PBA CSV", "MRIcron", ...: for messages and notes.
const char* LabelTableFormatName(LabelTableFormat format);

// What a table read gave besides its entries.
struct LabelTableRead {
  LabelTableFormat format = LabelTableFormat::kPbaCsv;
  // The files read (the table, and an MRIcron .lut beside it), for the
  // mesh cache's key.
  std::vector<std::filesystem::path> files;
  // For people: the format, background entries left out, colours chosen.
  std::vector<std::string> notes;
};

// The largest table file read [bytes]; a larger one is refused unread.
inline constexpr std::uintmax_t kMaxLabelTableBytes = 16u << 20;

// The files a table at `path` is read from: itself, and for a .txt the
// .lut of the same stem beside it, if there is one (an MRIcron table's
// colours). The mesh cache keys on their contents.
std::vector<std::filesystem::path> LabelTableFiles(const std::filesystem::path& path);

// Reads the table at `path` in whichever of the formats above it is. An
// unknown format, a malformed line (named by its number), a value outside
// 1..65535, a value or name given twice, an empty name: kInvalidArgument
// naming the file, nothing read.
Status ReadLabelTable(const std::filesystem::path& path, ColourTable* table, LabelTableRead* read);

// The same on text in memory; `lut` is an MRIcron .lut's bytes (may be
// empty), `extension` the file's (".txt", ".xml", ...), `source` names the
// text in messages.
Status ParseLabelTable(std::string_view text, std::string_view extension, std::string_view lut,
                       const std::string& source, ColourTable* table, LabelTableRead* read);

// Gives `entry` a display colour that is neither black nor any colour of
// `table`'s entries (the colours ReadLabelTable chooses): for a structure
// the label algebra adds (label_algebra.h).
void ChooseDisplayColour(const ColourTable& table, ColourEntry* entry);

// Without a table, a label volume's values would be read as the synthetic
// atlas's names, silently wrong for any other atlas: kInvalidArgument on
// `field` unless `volume` is the synthetic atlas's own (its description is
// kSyntheticAtlasNotice, as MakeSyntheticAtlas and the files PBA writes
// from it say).
class LabelVolume;
Status LabelVolumeNeedsATable(const LabelVolume& volume, const std::string& field);

}  // namespace pba
