// The pass before yaml-cpp loads an untrusted text: aliases refused with
// their line and name, and the size, node and depth caps; everything else
// (plain YAML, JSON, malformed text) is left to yaml-cpp.
#include "core/yaml_guard.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/yaml_bombs.h"

namespace pba {
namespace {

using yaml_bombs::BillionLaughs;

TEST(YamlGuardTest, AnAliasIsRefusedWithItsLineAndName) {
  const YamlProblem problem =
      FindYamlProblem("name: block\nbase: &base {youngs_modulus_pa: 3000}\nother: *base\n");
  EXPECT_EQ(problem.line, 3);
  EXPECT_NE(problem.message.find("YAML aliases (*base) are not accepted"), std::string::npos)
      << problem.message;

  const Status status = CheckYamlText("a: &x 1\nb: [2, *x]\n", "scene");
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.field(), "scene");
  EXPECT_EQ(status.message().rfind("line 2: YAML aliases (*x)", 0), 0u) << status.message();

  // A merge key is an alias too.
  EXPECT_NE(FindYamlProblem("a: &m {x: 1}\nb:\n  <<: *m\n").message.find("(*m)"),
            std::string::npos);
}

TEST(YamlGuardTest, AnAliasInALaterDocumentIsNamedByItsOwnDocumentsAnchor) {
  // yaml-cpp numbers anchors afresh in each document.
  const YamlProblem problem = FindYamlProblem("a: &first 1\n---\nb: &second 2\nc: *second\n");
  EXPECT_EQ(problem.line, 4);
  EXPECT_NE(problem.message.find("(*second)"), std::string::npos) << problem.message;
}

TEST(YamlGuardTest, BillionLaughsIsRefusedAtOnce) {
  const std::string text = BillionLaughs();
  ASSERT_LT(text.size(), 1000u);
  const auto start = std::chrono::steady_clock::now();
  const YamlProblem problem = FindYamlProblem(text);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(problem.line, 2);
  EXPECT_NE(problem.message.find("(*l0)"), std::string::npos) << problem.message;
  // The expansion would take minutes and gigabytes; refusing it reads a
  // line and a half.
  EXPECT_LT(seconds, 0.5);
}

TEST(YamlGuardTest, NestingDeeperThanTheLimitIsRefused) {
  const std::string deep = std::string(65, '[') + "1" + std::string(65, ']');
  const YamlProblem problem = FindYamlProblem(deep);  // the default: 64 levels
  EXPECT_NE(problem.message.find("nested deeper than 64 levels"), std::string::npos)
      << problem.message;
  EXPECT_EQ(problem.line, 1);
  EXPECT_TRUE(FindYamlProblem(std::string(64, '[') + "1" + std::string(64, ']')).message.empty());

  YamlLimits limits;
  limits.max_depth = 2;
  EXPECT_TRUE(FindYamlProblem("a: {b: 1}\n", limits).message.empty());
  const YamlProblem maps = FindYamlProblem("a:\n  b:\n    c: 1\n", limits);
  EXPECT_NE(maps.message.find("nested deeper than 2 levels"), std::string::npos) << maps.message;
  EXPECT_EQ(maps.line, 3);
}

TEST(YamlGuardTest, NodeAndByteCapsAreRefused) {
  YamlLimits limits;
  limits.max_nodes = 10;
  // A sequence and its ten values: eleven nodes.
  EXPECT_TRUE(FindYamlProblem("[1, 2, 3, 4, 5, 6, 7, 8, 9]", limits).message.empty());
  const YamlProblem nodes = FindYamlProblem("[1, 2, 3, 4, 5, 6, 7, 8, 9, 10]", limits);
  EXPECT_NE(nodes.message.find("more than 10 YAML values"), std::string::npos) << nodes.message;

  limits = YamlLimits();
  limits.max_bytes = 16;
  EXPECT_TRUE(FindYamlProblem("{a: 1, b: 2345}", limits).message.empty());  // 15 bytes
  const YamlProblem bytes = FindYamlProblem("{a: 1, b: 23456789}", limits);
  EXPECT_NE(bytes.message.find("19 bytes; at most 16"), std::string::npos) << bytes.message;
  EXPECT_EQ(bytes.line, 0);
  const Status status = CheckYamlText("{a: 1, b: 23456789}", "f", limits);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.message().rfind("the text is 19 bytes", 0), 0u) << status.message();
}

TEST(YamlGuardTest, PlainYamlJsonAndMalformedTextPass) {
  EXPECT_TRUE(
      FindYamlProblem("name: block\nmesh: {element_size_mm: 2.5}\nlist: [1, 2]\n").message.empty());
  EXPECT_TRUE(FindYamlProblem(R"({"plates": [{"z_mm": 1, "polygons": [[[0, 0], [1, 0]]]}]})")
                  .message.empty());
  // An anchor nobody refers to is harmless.
  EXPECT_TRUE(FindYamlProblem("a: &unused 1\nb: 2\n").message.empty());
  EXPECT_TRUE(FindYamlProblem("").message.empty());
  // Malformed text is yaml-cpp's to report, with its own line.
  EXPECT_TRUE(FindYamlProblem("name: [unclosed\nmesh: {}\n").message.empty());
  EXPECT_TRUE(FindYamlProblem("a: *undefined\n").message.empty());
  EXPECT_TRUE(CheckYamlText("key: value\n", "f").ok());
}

TEST(YamlGuardTest, FilesAreReadNoFurtherThanTheCapAndChecked) {
  const std::filesystem::path dir = ::testing::TempDir();
  const std::filesystem::path file = dir / "yaml_guard_test.yaml";
  std::ofstream(file) << "a: &x 1\nb: *x\n";
  std::string text = "unchanged";
  const Status alias = ReadYamlFileText(file, "index.json", &text);
  EXPECT_EQ(alias.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(alias.ToString(), "index.json: line 2: " + FindYamlProblem("a: &x 1\nb: *x\n").message);
  EXPECT_EQ(text, "unchanged");

  std::ofstream(file) << std::string(200000, '#');
  YamlLimits limits;
  limits.max_bytes = 100000;
  const Status big = ReadYamlFileText(file, "index.json", &text, limits);
  EXPECT_EQ(big.code(), Status::Code::kInvalidArgument);
  EXPECT_NE(big.message().find("more than 100000 bytes"), std::string::npos) << big.ToString();

  std::ofstream(file) << "key: [1, 2]\n";
  ASSERT_TRUE(ReadYamlFileText(file, "index.json", &text).ok());
  EXPECT_EQ(text, "key: [1, 2]\n");
  std::filesystem::remove(file);
  EXPECT_EQ(ReadYamlFileText(file, "index.json", &text).code(), Status::Code::kIo);
}

}  // namespace
}  // namespace pba
