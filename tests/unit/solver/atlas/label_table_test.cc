// Label tables as atlases ship them (atlas/label_table.h): the MRIcron
// tables of Debian's mricron-data read as they are (AAL, JHU white matter,
// AICHA, with their .lut colours, black and repeated ones replaced), every
// other format from a sample written as its tool writes it, and bad tables
// refused naming the file, the line and what is wrong.
#include "atlas/label_table.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>

#include "atlas/label_volume_io.h"
#include "common/subprocess.h"
#include "core/format.h"

namespace pba {
namespace {

namespace fs = std::filesystem;

const fs::path kTemplates = "/usr/share/mricron/templates";

uint32_t Packed(const ColourEntry& e) { return (uint32_t(e.r) << 16) | (uint32_t(e.g) << 8) | e.b; }

// Every colour distinct and none black: what a ColourTable holds.
void ExpectDistinctColours(const ColourTable& table) {
  std::set<uint32_t> colours;
  for (const ColourEntry& e : table.entries()) {
    EXPECT_NE(Packed(e), 0u) << e.name;
    EXPECT_TRUE(colours.insert(Packed(e)).second) << e.name;
  }
}

bool HasNote(const LabelTableRead& read, const std::string& part) {
  for (const std::string& note : read.notes) {
    if (note.find(part) != std::string::npos) return true;
  }
  return false;
}

TEST(LabelTable, AalAsMricronShipsIt) {
  ColourTable table;
  LabelTableRead read;
  const Status status = ReadLabelTable(kTemplates / "aal.nii.txt", &table, &read);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(read.format, LabelTableFormat::kMricron);
  ASSERT_EQ(table.size(), 116);
  EXPECT_EQ(table.FindByLabel(1)->name, "Precentral_L");
  EXPECT_EQ(table.FindByLabel(116)->name, "Vermis_10");
  ASSERT_EQ(read.files.size(), 2u);  // the .txt and its .lut
  EXPECT_EQ(read.files[1].filename(), "aal.nii.lut");
  EXPECT_TRUE(HasNote(read, "colours from its .lut")) << read.notes.front();
  // AAL's .lut gives 43 colours to 116 labels, 16 of them black.
  EXPECT_TRUE(HasNote(read, "16 black")) << read.notes.back();
  EXPECT_TRUE(HasNote(read, "repeating another's colour")) << read.notes.back();
  ExpectDistinctColours(table);
  // The first label with a colour keeps it: the .lut's entry 1.
  std::ifstream lut(kTemplates / "aal.nii.lut", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(lut)), std::istreambuf_iterator<char>());
  ASSERT_EQ(bytes.size(), 768u);
  const ColourEntry* first = table.FindByLabel(1);
  EXPECT_EQ(first->r, static_cast<unsigned char>(bytes[1]));
  EXPECT_EQ(first->g, static_cast<unsigned char>(bytes[257]));
  EXPECT_EQ(first->b, static_cast<unsigned char>(bytes[513]));

  // Every label of the volume has its name.
  LabelVolume volume;
  ASSERT_TRUE(ReadLabelVolume(kTemplates / "aal.nii.gz", "input", &volume).ok());
  std::set<uint16_t> labels(volume.labels().begin(), volume.labels().end());
  labels.erase(0);
  EXPECT_EQ(labels.size(), 116u);
  for (uint16_t label : labels) EXPECT_NE(table.FindByLabel(label), nullptr) << label;
}

TEST(LabelTable, JhuAndAichaAsMricronShipsThem) {
  ColourTable jhu, aicha;
  LabelTableRead jhu_read, aicha_read;
  ASSERT_TRUE(
      ReadLabelTable(kTemplates / "JHU-WhiteMatter-labels-1mm.nii.txt", &jhu, &jhu_read).ok());
  EXPECT_EQ(jhu.size(), 48);  // value 0, "Unclassified", is background
  EXPECT_TRUE(HasNote(jhu_read, "value 0 ('Unclassified') is background"));
  EXPECT_EQ(jhu.FindByLabel(1)->name, "Middle_cerebellar_peduncle");
  ExpectDistinctColours(jhu);
  ASSERT_TRUE(ReadLabelTable(kTemplates / "AICHAmc.nii.txt", &aicha, &aicha_read).ok());
  EXPECT_EQ(aicha.size(), 192);
  // "1 G_Frontal_Sup-1 2": the last integer is AICHA's own code, not the name.
  EXPECT_EQ(aicha.FindByLabel(1)->name, "G_Frontal_Sup-1");
  ExpectDistinctColours(aicha);
}

// Parses `text` as a file with `extension`.
Status Parse(const std::string& text, const std::string& extension, ColourTable* table,
             LabelTableRead* read) {
  return ParseLabelTable(text, extension, "", "sample" + extension, table, read);
}

TEST(LabelTable, SlicerColourTable) {
  const std::string text =
      "# Color table file GenericAnatomyColors.ctbl\n"
      "# 3 values\n"
      "0 Background 0 0 0 0\n"
      "1 tissue 128 174 128 255\n"
      "2 bone 241 214 145 255\n"
      "3 skin 128 174 128 255\n";
  ColourTable table;
  LabelTableRead read;
  const Status status = Parse(text, ".ctbl", &table, &read);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(read.format, LabelTableFormat::kSlicer);
  ASSERT_EQ(table.size(), 3);
  EXPECT_EQ(table.FindByLabel(2)->name, "bone");
  EXPECT_EQ(table.FindByLabel(2)->r, 241);
  EXPECT_EQ(table.FindByLabel(1)->g, 174);  // the first keeps the colour
  EXPECT_NE(Packed(*table.FindByLabel(3)), Packed(*table.FindByLabel(1)));
  EXPECT_TRUE(HasNote(read, "1 repeating another's colour"));
  // The same in a .txt.
  ASSERT_TRUE(Parse(text, ".txt", &table, &read).ok());
  EXPECT_EQ(read.format, LabelTableFormat::kSlicer);
}

TEST(LabelTable, SlicerCsvAndTsv) {
  const std::string csv =
      "LabelValue,Name,Color_R,Color_G,Color_B,Color_A\n"
      "1,\"Inferior Frontal Gyrus, pars triangularis\",200,10,10,255\n"
      "2,Putamen,10,200,10,255\n";
  ColourTable table;
  LabelTableRead read;
  Status status = Parse(csv, ".csv", &table, &read);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(read.format, LabelTableFormat::kSlicerCsv);
  EXPECT_EQ(table.FindByLabel(1)->name, "Inferior Frontal Gyrus, pars triangularis");
  std::string tsv = csv;
  for (char& c : tsv) c = c == ',' ? '\t' : c;
  // The quoted name keeps its (now tab) separator inside the quotes.
  status = Parse(tsv, ".tsv", &table, &read);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(table.FindByLabel(2)->name, "Putamen");
  EXPECT_EQ(table.FindByLabel(2)->g, 200);
}

TEST(LabelTable, ItkSnapLabelDescription) {
  const std::string text =
      "################################################\n"
      "# ITK-SnAP Label Description File\n"
      "# File format: \n"
      "# IDX   -R-  -G-  -B-  -A--  VIS MSH  LABEL\n"
      "################################################\n"
      "    0     0    0    0        0  0  0    \"Clear Label\"\n"
      "    1   255    0    0        1  1  1    \"Left hippocampus\"\n"
      "    2     0  255    0        1  1  1    \"Right hippocampus\"\n";
  ColourTable table;
  LabelTableRead read;
  const Status status = Parse(text, ".txt", &table, &read);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(read.format, LabelTableFormat::kItkSnap);
  ASSERT_EQ(table.size(), 2);
  EXPECT_EQ(table.FindByLabel(1)->name, "Left hippocampus");
  EXPECT_EQ(table.FindByLabel(1)->r, 255);
  EXPECT_TRUE(HasNote(read, "'Clear Label'"));
}

TEST(LabelTable, FslAtlasXml) {
  const std::string label_atlas =
      "<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?>\n<atlas version=\"1.0\">\n"
      "  <header><name>JHU ICBM-DTI-81 White-Matter Labels</name><type>Label</type></header>\n"
      "  <data>\n"
      "    <label index=\"0\" x=\"0\" y=\"0\" z=\"0\">Unclassified</label>\n"
      "    <label index=\"1\" x=\"98\" y=\"117\" z=\"75\">Middle cerebellar peduncle</label>\n"
      "  </data>\n</atlas>\n";
  ColourTable table;
  LabelTableRead read;
  Status status = Parse(label_atlas, ".xml", &table, &read);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(read.format, LabelTableFormat::kFslXml);
  ASSERT_EQ(table.size(), 1);
  EXPECT_EQ(table.FindByLabel(1)->name, "Middle cerebellar peduncle");
  EXPECT_TRUE(HasNote(read, "1 without a colour"));

  const std::string probabilistic =
      "<atlas><header><type>Probabalistic</type></header><data>\n"
      "<label index=\"0\" x=\"48\" y=\"94\" z=\"35\">Frontal Pole</label>\n"
      "<label index=\"1\" x=\"25\" y=\"70\" z=\"32\">Insular Cortex</label>\n"
      "<label index=\"4\" x=\"1\" y=\"1\" z=\"1\">Inferior Frontal Gyrus, pars "
      "triangularis</label>\n"
      "</data></atlas>\n";
  status = Parse(probabilistic, ".xml", &table, &read);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(table.FindByLabel(1)->name, "Frontal Pole");  // index + 1
  EXPECT_EQ(table.FindByLabel(5)->name, "Inferior Frontal Gyrus, pars triangularis");
  EXPECT_TRUE(HasNote(read, "index + 1"));
}

TEST(LabelTable, PbaCsvTakesRepeatedAndBlackColoursAndCommasRoundTrip) {
  const std::string text =
      "label, name, r, g, b\n"
      "1,\"Gyrus, left\",10,20,30\n"
      "2,Other,10,20,30\n"
      "3,Dark,0,0,0\n";
  ColourTable table;
  LabelTableRead read;
  const Status status = Parse(text, ".csv", &table, &read);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(read.format, LabelTableFormat::kPbaCsv);
  ExpectDistinctColours(table);
  EXPECT_TRUE(HasNote(read, "2 of the 3 structures got a display colour"));
  // Written and read back through the strict CSV (distinct colours now).
  ColourTable again;
  const Status back = ParseColourTableCsv(FormatColourTableCsv(table), "again.csv", &again);
  ASSERT_TRUE(back.ok()) << back.ToString();
  EXPECT_EQ(again.FindByLabel(1)->name, "Gyrus, left");
  EXPECT_EQ(Packed(*again.FindByLabel(3)), Packed(*table.FindByLabel(3)));
}

// A table as large as a label volume allows, with no colours: each gets
// its own (and the reading ends).
TEST(LabelTable, EveryValueOfALargeTableWithoutColoursGetsItsOwn) {
  std::string text;
  for (int value = 1; value <= 65535; ++value) text += Format("%d structure_%d\n", value, value);
  ColourTable table;
  LabelTableRead read;
  const Status status = Parse(text, ".txt", &table, &read);
  ASSERT_TRUE(status.ok()) << status.ToString();
  EXPECT_EQ(table.size(), 65535);
  ExpectDistinctColours(table);
}

struct Bad {
  const char* text;
  const char* extension;
  const char* message_part;
};

TEST(LabelTable, BadTablesAreRefusedSayingWhy) {
  const Bad cases[] = {
      {"hello world, this is not a table at all\n", ".txt", "not a label table PBA reads"},
      {"1 Left\n1 Right\n", ".txt", "line 2: value 1 is given twice ('Left' and 'Right')"},
      {"1 Same\n2 Same\n", ".txt", "line 2: the name 'Same' is given to values 1 and 2"},
      {"70000 Far\n", ".txt", "line 1: value 70000 is outside 1..65535"},
      {"label,name,r,g,b\n1,,1,2,3\n", ".csv", "line 2: value 1 has no name"},
      {"label,name,r,g,b\n1,A,1,2,300\n", ".csv", "line 2: a colour channel"},
      {"label,name,r,g,b\n1,\"A,1,2,3\n", ".csv", "line 2: an unterminated quote"},
      {"0 Background\n", ".txt", "names no structure"},
      {"<atlas><data>", ".xml", "not well-formed XML"},
      {"<atlas><header><type>Other</type></header><data/></atlas>", ".xml", "'other'"},
      {"<atlas><header><type>Probabilistic</type></header><data><label "
       "index=\"9223372036854775807\">Far</label></data></atlas>",
       ".xml", "outside 1..65535"},
      {"1 Ok 10 20 30 255\nx bad 1 2 3 4\n", ".ctbl", "line 2: expected 'value name r g b a'"},
  };
  for (const Bad& c : cases) {
    ColourTable table;
    LabelTableRead read;
    const Status status = Parse(c.text, c.extension, &table, &read);
    ASSERT_FALSE(status.ok()) << c.text;
    EXPECT_EQ(status.code(), Status::Code::kInvalidArgument) << status.ToString();
    EXPECT_EQ(status.field(), std::string("sample") + c.extension);
    EXPECT_NE(status.message().find(c.message_part), std::string::npos) << status.message();
    EXPECT_EQ(table.size(), 0) << "a refused table leaves nothing";
  }
}

TEST(LabelTable, FilesAreBoundedAndTheLutMustBeOne) {
  testing::TempDir dir;
  // A .lut beside the table that is not 768 bytes.
  std::ofstream(dir.path() / "atlas.txt") << "1 A\n";
  std::ofstream(dir.path() / "atlas.lut") << "short";
  ColourTable table;
  LabelTableRead read;
  Status status = ReadLabelTable(dir.path() / "atlas.txt", &table, &read);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument) << status.ToString();
  EXPECT_NE(status.message().find("not an MRIcron .lut's 768"), std::string::npos)
      << status.message();
  // A table over the bound is refused unread.
  {
    std::ofstream big(dir.path() / "big.txt");
    const std::string line(1023, 'x');
    for (std::uintmax_t i = 0; i <= kMaxLabelTableBytes / 1024; ++i) big << line << '\n';
  }
  status = ReadLabelTable(dir.path() / "big.txt", &table, &read);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument) << status.ToString();
  EXPECT_NE(status.message().find("more than a label table's"), std::string::npos)
      << status.message();
  status = ReadLabelTable(dir.path() / "missing.txt", &table, &read);
  EXPECT_EQ(status.code(), Status::Code::kIo) << status.ToString();
}

}  // namespace
}  // namespace pba
