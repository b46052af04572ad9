// A result folder's SHA256SUMS (core/checksum_file.h): written in
// coreutils' format (sha256sum -c agrees), and a folder that is not as
// listed (a file cut short, lost, added, a symbolic link, a list that is
// malformed, names a path outside, or is too large) refused naming what
// is wrong; the cheap check sees what is missing, not what changed.
#include "core/checksum_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "core/sha256.h"

namespace pba {
namespace {
namespace fs = std::filesystem;

class ChecksumFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("pba-checksum-test-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "structures");
    Write("summary.json", "{}\n");
    Write("result.h5", "hello\n");
    Write("structures/Left caudate.nii.gz", "voxels");
  }
  void TearDown() override { fs::remove_all(dir_); }

  void Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
  }
  std::string List() {
    std::ifstream in(dir_ / kChecksumFileName, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  }
  // The message VerifyChecksumFile fails with ("" when it passes).
  std::string Refusal() {
    std::vector<ChecksummedFile> files;
    const Status status = VerifyChecksumFile(dir_, &files);
    if (!status.ok()) {
      EXPECT_EQ(status.code(), Status::Code::kIo);
    }
    return status.ok() ? "" : status.message();
  }

  fs::path dir_;
};

TEST_F(ChecksumFileTest, ListsEveryFileAsSha256sumDoes) {
  ASSERT_TRUE(WriteChecksumFile(dir_).ok());
  EXPECT_EQ(List(), Sha256Hex("hello\n") + "  result.h5\n" + Sha256Hex("voxels") +
                        "  structures/Left caudate.nii.gz\n" + Sha256Hex("{}\n") +
                        "  summary.json\n");
  // coreutils reads it as its own.
  const std::string check = "cd '" + dir_.string() + "' && sha256sum --quiet -c " +
                            kChecksumFileName + " >/dev/null 2>&1";
  EXPECT_EQ(std::system(check.c_str()), 0);

  std::vector<ChecksummedFile> files;
  ASSERT_TRUE(VerifyChecksumFile(dir_, &files).ok());
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(files[0].path, "result.h5");
  EXPECT_EQ(files[0].sha256, Sha256Hex("hello\n"));
  EXPECT_EQ(files[0].size, 6);
  EXPECT_EQ(files[1].path, "structures/Left caudate.nii.gz");
  EXPECT_EQ(files[2].path, "summary.json");

  // sha256sum's binary marker and upper-case digests read too.
  std::string upper = Sha256Hex("hello\n");
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  Write(kChecksumFileName, upper + " *result.h5\n" + Sha256Hex("voxels") +
                               "  structures/Left caudate.nii.gz\n" + Sha256Hex("{}\n") +
                               "  summary.json\n");
  EXPECT_EQ(Refusal(), "");
}

TEST_F(ChecksumFileTest, AFolderNotAsListedIsRefusedNamingTheFile) {
  ASSERT_TRUE(WriteChecksumFile(dir_).ok());
  const std::string list = List();

  Write("result.h5", "hell");  // cut short
  EXPECT_NE(Refusal().find("result.h5 is damaged: its SHA-256 is " + Sha256Hex("hell") +
                           ", SHA256SUMS says " + Sha256Hex("hello\n") + " (4 bytes now)"),
            std::string::npos)
      << Refusal();
  EXPECT_TRUE(ChecksumFileComplete(dir_).ok()) << "the cheap check computes no digest";
  Write("result.h5", "hello\n");
  EXPECT_EQ(Refusal(), "");

  fs::remove(dir_ / "structures" / "Left caudate.nii.gz");
  EXPECT_NE(Refusal().find("lacks structures/Left caudate.nii.gz, which SHA256SUMS names"),
            std::string::npos)
      << Refusal();
  EXPECT_NE(ChecksumFileComplete(dir_).message().find(
                "lacks structures/Left caudate.nii.gz, which SHA256SUMS names"),
            std::string::npos);
  Write("structures/Left caudate.nii.gz", "voxels");

  Write("stray.txt", "");
  EXPECT_NE(Refusal().find("holds stray.txt, which SHA256SUMS does not name"), std::string::npos)
      << Refusal();
  fs::remove(dir_ / "stray.txt");

  fs::create_symlink("/etc/passwd", dir_ / "link");
  EXPECT_NE(Refusal().find("holds link, which is not a regular file (a symbolic link)"),
            std::string::npos)
      << Refusal();
  EXPECT_FALSE(WriteChecksumFile(dir_).ok()) << "nothing is listed through a link";
  fs::remove(dir_ / "link");
  EXPECT_EQ(List(), list);

  fs::remove(dir_ / kChecksumFileName);
  EXPECT_NE(Refusal().find("has no SHA256SUMS"), std::string::npos) << Refusal();
  EXPECT_NE(ChecksumFileComplete(dir_).message().find("has no SHA256SUMS"), std::string::npos);
}

TEST_F(ChecksumFileTest, AMalformedOrHostileListIsRefusedNamingTheLine) {
  const std::string hello = Sha256Hex("hello\n");
  const std::string rest = Sha256Hex("voxels") + "  structures/Left caudate.nii.gz\n" +
                           Sha256Hex("{}\n") + "  summary.json\n";
  const std::pair<std::string, std::string> cases[] = {
      {rest + hello + "  result.h5", "does not end with a whole line"},
      {"not a digest  result.h5\n", "line 1 of"},
      {hello + "\tresult.h5\n", "is not \"<SHA-256 in hex>  <file>\""},
      {hello + "  ../result.h5\n", "outside the folder"},
      {hello + "  /etc/passwd\n", "outside the folder"},
      {hello + "  structures/./x\n", "outside the folder"},
      {hello + "  SHA256SUMS\n", "outside the folder or not a file's"},
      {hello + "  result.h5\n" + hello + "  result.h5\n", "line 2 of"},
  };
  for (const auto& [text, words] : cases) {
    Write(kChecksumFileName, text.back() == '\n' ? text + rest : text);
    const std::string refusal = Refusal();
    EXPECT_NE(refusal.find(words), std::string::npos) << text << " -> " << refusal;
  }
  // A list past its bound is not read at all.
  Write(kChecksumFileName, "");
  fs::resize_file(dir_ / kChecksumFileName, kMaxChecksumFileBytes + 1);
  EXPECT_NE(Refusal().find("is larger than 16 MiB"), std::string::npos) << Refusal();
}

}  // namespace
}  // namespace pba
