// pba_base: the one SHA-256 (known answers, pieces against one call, files
// with their size), the one atomic write (its mode, never replacing,
// directories replaced whole, its temporary names)
// and Format, which never cuts a message.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>

#include "core/atomic_write.h"
#include "core/format.h"
#include "core/number_format.h"
#include "core/sha256.h"

namespace pba {
namespace {

// FIPS 180-2's examples.
constexpr char kEmpty[] = "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855";
constexpr char kAbc[] = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad";

TEST(Sha256Test, KnownAnswers) {
  EXPECT_EQ(Sha256Hex(""), kEmpty);
  EXPECT_EQ(Sha256Hex("abc"), kAbc);
  EXPECT_EQ(HexOf(Sha256Of("abc", 3)), kAbc);
  EXPECT_TRUE(IsSha256Hex(kAbc));
  EXPECT_FALSE(IsSha256Hex(std::string(kAbc).substr(1)));
  EXPECT_FALSE(IsSha256Hex("BA7816BF8F01CFEA414140DE5DAE2223B00361A396177A9CB410FF61F20015AD"));
  const unsigned char bytes[] = {0x00, 0x0f, 0xa0, 0xff};
  EXPECT_EQ(HexOf(bytes, sizeof bytes), "000fa0ff");
}

TEST(Sha256Test, PiecesGiveTheDigestOfTheWhole) {
  std::string text;
  for (int i = 0; i < 100000; ++i) text += static_cast<char>('a' + i % 26);
  Sha256 sha;
  for (size_t at = 0; at < text.size(); at += 777) {
    ASSERT_TRUE(sha.Update(text.data() + at, std::min<size_t>(777, text.size() - at)));
  }
  Sha256Digest digest{};
  ASSERT_TRUE(sha.Finish(&digest).ok());
  EXPECT_EQ(HexOf(digest), Sha256Hex(text));
  // A digest is taken once.
  EXPECT_FALSE(sha.Finish(&digest).ok());
}

TEST(Sha256Test, AFileHasTheDigestOfItsBytesAndItsSize) {
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("pba-sha-" + std::to_string(::getpid()));
  const std::string bytes(3 << 20 | 5, 'x');  // more than one read block
  std::ofstream(path, std::ios::binary) << bytes;
  std::string hex;
  int64_t size = 0;
  ASSERT_TRUE(FileSha256Hex(path, &hex, &size).ok());
  EXPECT_EQ(hex, Sha256Hex(bytes));
  EXPECT_EQ(size, static_cast<int64_t>(bytes.size()));
  std::filesystem::remove(path);
  const Status missing = FileSha256Hex(path, &hex);
  EXPECT_EQ(missing.code(), Status::Code::kIo);
  EXPECT_NE(missing.message().find(path.string()), std::string::npos) << missing.ToString();
}

TEST(AtomicWriteTest, ATextGetsItsModeAndLeavesNoTemporaryFile) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("pba-atomic-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  namespace fs = std::filesystem;
  ASSERT_TRUE(AtomicWriteText(dir / "private", "a").ok());
  EXPECT_EQ(fs::status(dir / "private").permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write);
  ASSERT_TRUE(AtomicWriteText(dir / "shared", "b", 0644).ok());
  EXPECT_EQ(fs::status(dir / "shared").permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read |
                fs::perms::others_read);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 2);
  // Into a directory that does not exist: refused, nothing written.
  const Status missing = AtomicWriteText(dir / "no" / "file", "c");
  EXPECT_EQ(missing.code(), Status::Code::kIo);
  fs::remove_all(dir);
}

// A new empty directory for one test.
std::filesystem::path FreshDir(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("pba-" + name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string ReadText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::ptrdiff_t Entries(const std::filesystem::path& dir) {
  return std::distance(std::filesystem::directory_iterator(dir),
                       std::filesystem::directory_iterator());
}

TEST(AtomicWriteTest, NeverReplaceRefusesWhatIsThereAndLeavesNoTemporaryFile) {
  namespace fs = std::filesystem;
  const fs::path dir = FreshDir("never-replace");
  std::ofstream(dir / "kept") << "old";
  AtomicWriteOptions options;
  options.never_replace = true;
  options.mode = 0640;
  const Status refused = AtomicWriteText(dir / "kept", "new", options);
  EXPECT_EQ(refused.code(), Status::Code::kAlreadyExists);
  EXPECT_NE(refused.message().find((dir / "kept").string()), std::string::npos)
      << refused.ToString();
  EXPECT_EQ(ReadText(dir / "kept"), "old");
  // A dangling symbolic link counts as something there.
  fs::create_symlink(dir / "nowhere", dir / "dangling");
  EXPECT_EQ(AtomicWriteText(dir / "dangling", "new", options).code(), Status::Code::kAlreadyExists);
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir / "dangling")));
  EXPECT_EQ(Entries(dir), 2);
  // A new name is written, with the mode asked for.
  ASSERT_TRUE(AtomicWriteText(dir / "fresh", "new", options).ok());
  EXPECT_EQ(ReadText(dir / "fresh"), "new");
  EXPECT_EQ(fs::status(dir / "fresh").permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  EXPECT_EQ(Entries(dir), 3);
  fs::remove_all(dir);
}

TEST(AtomicWriteTest, TheModeOptionAppliesToAWriteThroughTheDescriptor) {
  namespace fs = std::filesystem;
  const fs::path dir = FreshDir("atomic-mode");
  std::ofstream(dir / "file") << "old";
  AtomicWriteOptions options;
  options.mode = 0604;
  ASSERT_TRUE(
      AtomicWrite(
          dir / "file", ".txt",
          [](int fd, const std::string& temporary) { return WriteAll(fd, "new", 3, temporary); },
          options)
          .ok());
  EXPECT_EQ(ReadText(dir / "file"), "new");  // replaced: never_replace is off
  EXPECT_EQ(fs::status(dir / "file").permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write | fs::perms::others_read);
  EXPECT_EQ(Entries(dir), 1);
  fs::remove_all(dir);
}

TEST(AtomicWriteTest, MoveIntoPlaceReplacesOrRefusesAsAsked) {
  namespace fs = std::filesystem;
  const fs::path dir = FreshDir("move-into-place");
  std::ofstream(dir / "part") << "new";
  std::ofstream(dir / "target") << "old";
  const Status refused = MoveIntoPlace(dir / "part", dir / "target", /*never_replace=*/true);
  EXPECT_EQ(refused.code(), Status::Code::kAlreadyExists);
  EXPECT_NE(refused.message().find((dir / "target").string()), std::string::npos);
  EXPECT_EQ(ReadText(dir / "target"), "old");
  EXPECT_EQ(ReadText(dir / "part"), "new");
  ASSERT_TRUE(MoveIntoPlace(dir / "part", dir / "other", /*never_replace=*/true).ok());
  EXPECT_EQ(ReadText(dir / "other"), "new");
  EXPECT_FALSE(fs::exists(dir / "part"));
  ASSERT_TRUE(MoveIntoPlace(dir / "other", dir / "target", /*never_replace=*/false).ok());
  EXPECT_EQ(ReadText(dir / "target"), "new");
  EXPECT_EQ(Entries(dir), 1);
  const Status missing = MoveIntoPlace(dir / "part", dir / "target", /*never_replace=*/false);
  EXPECT_EQ(missing.code(), Status::Code::kIo);
  EXPECT_EQ(
      missing.message().rfind("cannot move " + (dir / "target").string() + " into place: ", 0), 0u)
      << missing.ToString();
  fs::remove_all(dir);
}

TEST(AtomicWriteTest, ADirectoryIsReplacedWholeOnlyWhenAskedAndKeptWhenTheFillFails) {
  namespace fs = std::filesystem;
  const fs::path parent = FreshDir("atomic-dir");
  const fs::path out = parent / "out";
  fs::create_directories(out);
  std::ofstream(out / "a") << "old";
  const auto write_b = [](const fs::path& staging) {
    return AtomicWriteText(staging / "b", "new");
  };
  // Not empty: refused without `replace`.
  EXPECT_EQ(AtomicWriteDirectory(out, write_b).code(), Status::Code::kIo);
  // A fill that fails leaves the old content, and nothing beside it.
  const Status failed = AtomicWriteDirectory(
      out,
      [&](const fs::path& staging) {
        EXPECT_TRUE(write_b(staging).ok());
        return Status::Io("the fill failed");
      },
      /*replace=*/true);
  EXPECT_EQ(failed.message(), "the fill failed");
  EXPECT_EQ(ReadText(out / "a"), "old");
  EXPECT_EQ(Entries(out), 1);
  EXPECT_EQ(Entries(parent), 1);
  // A move in that fails puts the old content back.
  EXPECT_EQ(MoveDirectoryIntoPlace(parent / "missing", out, /*replace=*/true).code(),
            Status::Code::kIo);
  EXPECT_EQ(ReadText(out / "a"), "old");
  EXPECT_EQ(Entries(parent), 1);
  // Replaced whole: the old entries are gone, no hidden directory is left.
  ASSERT_TRUE(AtomicWriteDirectory(out, write_b, /*replace=*/true).ok());
  EXPECT_FALSE(fs::exists(out / "a"));
  EXPECT_EQ(ReadText(out / "b"), "new");
  EXPECT_EQ(Entries(parent), 1);
  // A file where the directory goes is replaced too.
  fs::remove_all(out);
  std::ofstream(out) << "a file";
  ASSERT_TRUE(AtomicWriteDirectory(out, write_b, /*replace=*/true).ok());
  EXPECT_EQ(ReadText(out / "b"), "new");
  EXPECT_EQ(Entries(parent), 1);
  fs::remove_all(parent);
}

TEST(AtomicWriteTest, ItsTemporaryNamesAreKnownForSweeps) {
  EXPECT_TRUE(IsAtomicWriteTemporary(".abc.partial-Ab3xYz"));
  EXPECT_TRUE(IsAtomicWriteTemporary(".result.h5.partial-Ab3xYz.h5"));
  EXPECT_FALSE(IsAtomicWriteTemporary("abc.partial-Ab3xYz"));  // not hidden
  EXPECT_FALSE(IsAtomicWriteTemporary(".abc.partial-Ab3"));    // no random part
  EXPECT_FALSE(IsAtomicWriteTemporary(".partial-Ab3xYz"));     // no name
  EXPECT_FALSE(IsAtomicWriteTemporary("0a1b2c"));
}

TEST(FormatTest, ALongMessageIsNeverCut) {
  const std::string name(2000, 'n');
  const std::string message = Format("structure %s at %.1f mm", name.c_str(), 2.5);
  EXPECT_EQ(message, "structure " + name + " at 2.5 mm");
  EXPECT_EQ(Format("%d of %d", 3, 7), "3 of 7");
  EXPECT_EQ(Format("%s", std::string(511, 'a').c_str()).size(), 511u);
  EXPECT_EQ(Format("%s", std::string(512, 'a').c_str()).size(), 512u);
}

}  // namespace
}  // namespace pba

TEST(NumberFormatTest, RoundTripIsTheShortestTextThatReadsBack) {
  EXPECT_EQ(pba::RoundTripNumber(0.45), "0.45");
  EXPECT_EQ(pba::RoundTripNumber(0.4999999), "0.4999999");  // %g would say 0.5
  EXPECT_EQ(pba::RoundTripNumber(3000), "3000");
  EXPECT_EQ(pba::RoundTripNumber(-0.0), "-0");
  for (double value : {1.0 / 3.0, -0.1 - 0.2, 6.02214076e23, 5e-324, 1.7976931348623157e308,
                       0.1 + 0.7, 1e-5, 123456789.123456789}) {
    const std::string text = pba::RoundTripNumber(value);
    EXPECT_EQ(std::strtod(text.c_str(), nullptr), value) << text;
    EXPECT_LE(text.size(), 24u) << text;
  }
  EXPECT_EQ(pba::RoundTripNumber(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(pba::RoundTripNumber(-std::numeric_limits<double>::infinity()), "-inf");
  EXPECT_EQ(pba::RoundTripNumber(std::nan("")), "nan");
}

TEST(NumberFormatTest, AFieldWidthKeepsAsManyDigitsAsFit) {
  EXPECT_EQ(pba::RoundTripNumber(0.45, 20), "0.45");
  const double big = -1.2345678901234567e+200;
  const std::string text = pba::RoundTripNumber(big, 20);
  EXPECT_EQ(text, "-1.234567890123e+200");  // 13 significant digits in 20 characters
  EXPECT_NEAR(std::strtod(text.c_str(), nullptr) / big, 1, 1e-12);
  // Every width from 8 up holds some text of every double.
  for (int width = 8; width <= 24; ++width) {
    for (double value : {1.0 / 3.0, -2.0 / 3.0 * 1e-300, 6.02214076e23}) {
      EXPECT_LE(pba::RoundTripNumber(value, width).size(), static_cast<std::size_t>(width))
          << value << " in " << width;
    }
  }
}

TEST(NumberFormatTest, ShortIsSixDigitsForMessages) {
  EXPECT_EQ(pba::ShortNumber(0.4999999), "0.5");
  EXPECT_EQ(pba::ShortNumber(1e6), "1e+06");
  EXPECT_EQ(pba::ShortNumber(3000), "3000");
}
