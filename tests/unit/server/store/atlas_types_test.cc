// The field checks of the atlas store and its page tokens.
#include "store/atlas_types.h"

#include <gtest/gtest.h>

#include "store/page_token.h"

namespace pba {
namespace {

void ExpectRefused(const Status& status, const std::string& field, const std::string& fragment) {
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument) << status.ToString();
  EXPECT_EQ(status.field(), field) << status.ToString();
  EXPECT_NE(status.message().find(fragment), std::string::npos)
      << "'" << fragment << "' not in: " << status.message();
}

TEST(AtlasNames, AcceptTheDocumentedAlphabet) {
  for (const std::string& name :
       std::vector<std::string>{"a", "Hippocampus (left)", "CA1_2-3.v2", "white matter", "0",
                                std::string(kMaxNameLength, 'x')}) {
    EXPECT_TRUE(CheckName("structure", name).ok()) << name;
  }
}

TEST(AtlasNames, RefuseOtherCharactersNamingFieldAndCharacter) {
  ExpectRefused(CheckName("project", "a/b"), "project", "'/' at position 2");
  ExpectRefused(CheckName("project", "a\\b"), "project", "'\\'");
  ExpectRefused(CheckName("tag", "it's"), "tag", "'''");
  ExpectRefused(CheckName("tag", "say \"hi\""), "tag", "'\"'");
  ExpectRefused(CheckName("user", "x;y"), "user", "';'");
  ExpectRefused(CheckName("user", std::string("a\0b", 3)), "user", "\\x00");
  ExpectRefused(CheckName("user", "tab\there"), "user", "\\x09");
  ExpectRefused(CheckName("user", "\x1b[31m"), "user", "\\x1b");
  ExpectRefused(CheckName("user", "caf\xc3\xa9"), "user", "\\xc3");
  ExpectRefused(CheckName("structure", "'; DROP TABLE structures; --"), "structure", "'''");
}

TEST(AtlasNames, RefuseEmptyLongPaddedAndDotNames) {
  ExpectRefused(CheckName("structure", ""), "structure", "empty");
  ExpectRefused(CheckName("structure", std::string(kMaxNameLength + 1, 'x')), "structure", "129");
  ExpectRefused(CheckName("structure", " x"), "structure", "space");
  ExpectRefused(CheckName("structure", "x "), "structure", "space");
  ExpectRefused(CheckName("structure", "."), "structure", "..");
  ExpectRefused(CheckName("structure", ".."), "structure", "..");
}

TEST(AtlasNames, GroupPathsAreNamesJoinedBySlashes) {
  EXPECT_TRUE(CheckGroupPath("group_path", "").ok());
  EXPECT_TRUE(CheckGroupPath("group_path", "cerebrum/cortex/frontal lobe").ok());
  ExpectRefused(CheckGroupPath("group_path", "/cerebrum"), "group_path", "'/'");
  ExpectRefused(CheckGroupPath("group_path", "cerebrum/"), "group_path", "'/'");
  ExpectRefused(CheckGroupPath("group_path", "a//b"), "group_path", "'/'");
  ExpectRefused(CheckGroupPath("group_path", "a/b;c"), "group_path", "';'");
}

TEST(AtlasFields, ColoursAreBytes) {
  EXPECT_TRUE(CheckColour("colour", {0, 128, 255}).ok());
  ExpectRefused(CheckColour("colour", {0, 256, 0}), "colour.g", "256");
  ExpectRefused(CheckColour("colour", {-1, 0, 0}), "colour.r", "-1");
}

TEST(AtlasFields, MaterialIsAJsonObject) {
  for (const char* json :
       {"{}", R"({"model": "neo_hookean", "mu_pa": 1.2e3, "k": [1, -2.5, 0], "x": null})",
        R"( {"a": {"b": [true, false, "\u00e9\n"]}} )"}) {
    EXPECT_TRUE(CheckMaterialJson("material_json", json).ok()) << json;
  }
  for (const char* json :
       {"", "[]", "42", "{", R"({"a": })", R"({"a": 1,})", R"({a: 1})", R"({"a": 01})",
        R"({"a": "x)", R"({"a": 1} trailing)", R"({"a": tru})", R"({"a": "\q"})"}) {
    const Status status = CheckMaterialJson("material_json", json);
    EXPECT_EQ(status.code(), Status::Code::kInvalidArgument) << json;
    EXPECT_EQ(status.field(), "material_json") << json;
  }
  ExpectRefused(CheckMaterialJson("material_json", std::string(200, '[')), "material_json",
                "top level");
  ExpectRefused(CheckMaterialJson("material_json", "{\"a\":" + std::string(100, '[')),
                "material_json", "deeper");
}

TEST(AtlasFields, MessagesRefuseControlCharacters) {
  EXPECT_TRUE(CheckMessage("message", "smoothed the\n\tboundary").ok());
  ExpectRefused(CheckMessage("message", "bell\a"), "message", "\\x07");
  ExpectRefused(CheckMessage("message", std::string(kMaxMessageBytes + 1, 'm')), "message",
                "longer");
}

TEST(AtlasEnums, RoundTrip) {
  for (Role role : {Role::kViewer, Role::kEditor, Role::kAdmin}) {
    Role parsed = Role::kViewer;
    ASSERT_TRUE(ParseRole(RoleName(role), &parsed));
    EXPECT_EQ(parsed, role);
  }
  Role role;
  EXPECT_FALSE(ParseRole("owner", &role));
  for (StructureFormat format :
       {StructureFormat::kContours, StructureFormat::kNifti, StructureFormat::kStl,
        StructureFormat::kObj, StructureFormat::kVtk}) {
    StructureFormat parsed = StructureFormat::kContours;
    ASSERT_TRUE(ParseStructureFormat(StructureFormatName(format), &parsed));
    EXPECT_EQ(parsed, format);
  }
  StructureFormat format;
  EXPECT_FALSE(ParseStructureFormat("ply", &format));
}

TEST(PageTokens, RoundTripAndRefuseTokensOfOtherListings) {
  const std::string token = EncodePageToken("history", 7, 42);
  int64_t key = 0;
  ASSERT_TRUE(DecodePageToken(token, "history", 7, &key).ok());
  EXPECT_EQ(key, 42);
  EXPECT_EQ(DecodePageToken(token, "history", 8, &key).code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(DecodePageToken(token, "audit", 7, &key).code(), Status::Code::kInvalidArgument);
  for (const std::string& bad : std::vector<std::string>{
           "zz", "abc", "", "6869", EncodePageToken("history", 7, 42) + "00"}) {
    const Status status = DecodePageToken(bad, "history", 7, &key);
    EXPECT_EQ(status.code(), Status::Code::kInvalidArgument) << bad;
    EXPECT_EQ(status.field(), "page_token");
  }
  int size = 0;
  ASSERT_TRUE(NormalisePageSize(0, &size).ok());
  EXPECT_EQ(size, kDefaultPageSize);
  ASSERT_TRUE(NormalisePageSize(5000, &size).ok());
  EXPECT_EQ(size, kMaxPageSize);
  ASSERT_TRUE(NormalisePageSize(7, &size).ok());
  EXPECT_EQ(size, 7);
  EXPECT_EQ(NormalisePageSize(-1, &size).code(), Status::Code::kInvalidArgument);
}

}  // namespace
}  // namespace pba
