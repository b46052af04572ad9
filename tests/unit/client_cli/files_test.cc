// The client's checks of names a server sends before they become paths,
// and the rename that never replaces (client_cli/files.h).
#include "files.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace pba::cli {
namespace {
namespace fs = std::filesystem;

TEST(FilesTest, OnlyPlainFileNamesAreSafe) {
  const std::string good[] = {"summary.json",
                              "result.h5",
                              ".hidden",
                              "a b (c).json",
                              "...",
                              "Caudate nucleus.nii.gz",
                              std::string(kMaxFileNameBytes, 'x')};
  for (const std::string& name : good) {
    EXPECT_EQ(UnsafeFileNameReason(name), "") << name;
  }
  const std::pair<std::string, const char*> bad[] = {
      {"", "empty"},
      {".", "directory"},
      {"..", "directory"},
      {"../escaped.txt", "separator"},
      {"/etc/passwd", "separator"},
      {"a\\b", "separator"},
      {std::string("a\0b", 3), "NUL"},
      {"bell\x07", "control"},
      {"del\x7f", "control"},
      {"new\nline", "control"},
      {std::string(kMaxFileNameBytes + 1, 'x'), "256 bytes"},
  };
  for (const auto& [name, why] : bad) {
    const std::string reason = UnsafeFileNameReason(name);
    EXPECT_NE(reason.find(why), std::string::npos) << QuotedName(name) << ": " << reason;
  }
}

TEST(FilesTest, QuotedNamesShowControlCharactersEscaped) {
  EXPECT_EQ(QuotedName("a.json"), "\"a.json\"");
  EXPECT_EQ(QuotedName("esc\x1b[31m"), "\"esc\\x1b[31m\"");
  EXPECT_EQ(QuotedName("q\"\\"), "\"q\\x22\\x5c\"");
  EXPECT_EQ(FoldCase("Foo.JSON"), "foo.json");
}

TEST(FilesTest, RenameNoReplaceRefusesAnythingThere) {
  const fs::path dir = fs::temp_directory_path() / ("pba-files-test-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "a") << "a";
  std::ofstream(dir / "b") << "b";
  EXPECT_FALSE(RenameNoReplace(dir / "a", dir / "b"));
  EXPECT_EQ(errno, EEXIST);
  fs::create_symlink(dir / "nowhere", dir / "dangling");
  EXPECT_FALSE(RenameNoReplace(dir / "a", dir / "dangling"));
  EXPECT_EQ(errno, EEXIST);
  EXPECT_TRUE(RenameNoReplace(dir / "a", dir / "c"));
  EXPECT_FALSE(fs::exists(dir / "a"));
  std::ifstream in(dir / "b");
  std::stringstream b;
  b << in.rdbuf();
  EXPECT_EQ(b.str(), "b");
  fs::remove_all(dir);
}

TEST(FilesTest, AtomicWritesReplaceAPlantedLinkInsteadOfFollowingIt) {
  const fs::path dir =
      fs::temp_directory_path() / ("pba-files-test-link-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "victim") << "precious";
  fs::create_symlink(dir / "victim", dir / "out");
  ASSERT_TRUE(WriteFileAtomically(dir / "out", "new", 0640));
  std::ifstream victim(dir / "victim");
  std::stringstream text;
  text << victim.rdbuf();
  EXPECT_EQ(text.str(), "precious");
  EXPECT_FALSE(fs::is_symlink(dir / "out"));
  std::ifstream out(dir / "out");
  std::stringstream written;
  written << out.rdbuf();
  EXPECT_EQ(written.str(), "new");
  EXPECT_EQ(fs::status(dir / "out").permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  // Nothing else left beside it.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 2);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pba::cli
