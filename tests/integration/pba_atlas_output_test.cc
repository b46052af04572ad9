// pba-atlas -o PATH: what is at PATH is replaced only when pba-atlas wrote
// it and --force says so; a file, a link or a directory holding anything
// else is refused (exit 5, invalid input) and left as it was.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "common/subprocess.h"

namespace pba::testing {
namespace {
namespace fs = std::filesystem;

constexpr int kExitInvalid = 5;  // core/exit_codes.h, docs/cli.md

RunResult Plates(const fs::path& out, bool force = false) {
  std::vector<std::string> args = {PBA_ATLAS_BIN, "plates", "-o", out.string(), "--voxel-mm", "2"};
  if (force) args.push_back("--force");
  return RunProcess(args);
}

TEST(PbaAtlasOutputTest, AnEarlierResultIsReplacedOnlyWithForce) {
  TempDir dir;
  const fs::path out = dir.path() / "plates";
  const RunResult first = Plates(out);
  ASSERT_EQ(first.exit_code, 0) << first.out << first.err;
  ASSERT_TRUE(fs::exists(out / "plates" / "plates.json"));

  const RunResult again = Plates(out);
  EXPECT_EQ(again.exit_code, kExitInvalid) << again.out << again.err;
  EXPECT_NE(again.err.find("--force"), std::string::npos) << again.err;
  const RunResult forced = Plates(out, true);
  EXPECT_EQ(forced.exit_code, 0) << forced.out << forced.err;
  EXPECT_TRUE(fs::exists(out / "plates" / "plates.json"));

  // An empty directory is fine without --force.
  const fs::path empty = dir.path() / "empty";
  fs::create_directories(empty);
  EXPECT_EQ(Plates(empty).exit_code, 0);
}

TEST(PbaAtlasOutputTest, WhatPbaAtlasDidNotWriteIsNeverReplaced) {
  TempDir dir;
  // A regular file.
  const fs::path file = dir.path() / "thesis.docx";
  std::ofstream(file) << "three years of work";
  for (const char* command : {"plates", "build"}) {
    SCOPED_TRACE(command);
    for (bool force : {false, true}) {
      std::vector<std::string> args = {PBA_ATLAS_BIN, command, "-o", file.string()};
      if (force) args.push_back("--force");
      const RunResult run = RunProcess(args);
      EXPECT_EQ(run.exit_code, kExitInvalid) << run.out << run.err;
      EXPECT_NE(run.err.find("is a file"), std::string::npos) << run.err;
      EXPECT_EQ(ReadFile(file), "three years of work");
    }
  }

  // A folder with the user's things, even one beside an earlier result.
  const fs::path folder = dir.path() / "results";
  ASSERT_EQ(Plates(folder).exit_code, 0);
  std::ofstream(folder / "notes.txt") << "mine";
  std::ofstream(folder / "plates" / "draft.txt") << "mine too";
  for (const char* command : {"plates", "build"}) {
    SCOPED_TRACE(command);
    const RunResult run = RunProcess({PBA_ATLAS_BIN, command, "-o", folder.string(), "--force"});
    EXPECT_EQ(run.exit_code, kExitInvalid) << run.out << run.err;
    EXPECT_NE(run.err.find("did not write"), std::string::npos) << run.err;
    EXPECT_EQ(ReadFile(folder / "notes.txt"), "mine");
    EXPECT_EQ(ReadFile(folder / "plates" / "draft.txt"), "mine too");
    EXPECT_TRUE(fs::exists(folder / "labels.nii.gz"));
  }
  fs::remove(folder / "notes.txt");
  const RunResult nested = Plates(folder, true);
  EXPECT_EQ(nested.exit_code, kExitInvalid) << nested.err;
  EXPECT_EQ(ReadFile(folder / "plates" / "draft.txt"), "mine too");

  // A link, to a folder or anywhere.
  const fs::path link = dir.path() / "link";
  fs::create_directory_symlink(dir.path() / "elsewhere", link);
  const RunResult linked = Plates(link, true);
  EXPECT_EQ(linked.exit_code, kExitInvalid) << linked.err;
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_FALSE(fs::exists(dir.path() / "elsewhere"));
}

}  // namespace
}  // namespace pba::testing
