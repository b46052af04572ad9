#include "store/blob_store.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>

#include "core/sha256.h"
#include "unit/server/temp_dir.h"

namespace pba {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// SHA-256("abc"), FIPS 180-2 appendix B.1.
constexpr char kAbcHash[] = "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad";

class BlobStoreTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(BlobStore::Open(root(), &store_).ok()); }
  fs::path root() const { return dir_.path() / "blobs"; }

  std::string Put(const std::string& bytes) {
    std::string hash;
    const Status status = store_->Put(bytes, &hash);
    EXPECT_TRUE(status.ok()) << status.ToString();
    return hash;
  }

  // Every regular file under the root, as paths relative to it.
  std::vector<std::string> Files() const {
    std::vector<std::string> files;
    for (const auto& entry : fs::recursive_directory_iterator(root())) {
      if (entry.is_regular_file()) files.push_back(fs::relative(entry.path(), root()).string());
    }
    std::sort(files.begin(), files.end());
    return files;
  }

  static void Overwrite(const fs::path& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << bytes;
  }

  TempDir dir_;
  std::unique_ptr<BlobStore> store_;
};

TEST_F(BlobStoreTest, NamesBlobsByTheirSha256UnderTwoCharacterDirectories) {
  EXPECT_EQ(Put("abc"), kAbcHash);
  EXPECT_EQ(Files(), std::vector<std::string>{std::string("ba/") + (kAbcHash + 2)});
  std::string bytes;
  ASSERT_TRUE(store_->Get(kAbcHash, &bytes).ok());
  EXPECT_EQ(bytes, "abc");
  bool has = false;
  ASSERT_TRUE(store_->Has(kAbcHash, &has).ok());
  EXPECT_TRUE(has);
}

TEST_F(BlobStoreTest, KeepsBinaryContentExactly) {
  std::string binary(4096, '\0');
  for (size_t i = 0; i < binary.size(); ++i) binary[i] = static_cast<char>(i * 7);
  const std::string hash = Put(binary);
  EXPECT_EQ(hash, Sha256Hex(binary));
  std::string bytes;
  ASSERT_TRUE(store_->Get(hash, &bytes).ok());
  EXPECT_EQ(bytes, binary);
}

TEST_F(BlobStoreTest, PutIsIdempotentAndLeavesNoTemporaryFiles) {
  const std::string first = Put("same content");
  const fs::file_time_type written = fs::last_write_time(store_->PathOf(first));
  const std::string second = Put("same content");
  EXPECT_EQ(first, second);
  EXPECT_EQ(fs::last_write_time(store_->PathOf(first)), written) << "an intact blob was rewritten";
  EXPECT_EQ(Files().size(), 1u);
}

TEST_F(BlobStoreTest, PutRepairsADamagedCopy) {
  const std::string hash = Put("geometry");
  Overwrite(store_->PathOf(hash), "geometrX");
  EXPECT_EQ(Put("geometry"), hash);
  std::string bytes;
  ASSERT_TRUE(store_->Get(hash, &bytes).ok());
  EXPECT_EQ(bytes, "geometry");
}

TEST_F(BlobStoreTest, GetRefusesCorruptedAndTruncatedBlobsNamingTheHash) {
  const std::string hash = Put("contours of the left hippocampus");
  Overwrite(store_->PathOf(hash), "contours of the left hippocampuS");
  std::string bytes = "stale";
  Status status = store_->Get(hash, &bytes);
  EXPECT_EQ(status.code(), Status::Code::kIo) << status.ToString();
  EXPECT_NE(status.message().find(hash), std::string::npos) << status.message();
  EXPECT_TRUE(bytes.empty()) << "damaged content was handed out";

  Overwrite(store_->PathOf(hash), "contours of");
  status = store_->Get(hash, &bytes);
  EXPECT_EQ(status.code(), Status::Code::kIo) << status.ToString();
  EXPECT_NE(status.message().find(hash), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("11 bytes"), std::string::npos) << status.message();
}

TEST_F(BlobStoreTest, MissingAndMalformedHashes) {
  std::string bytes;
  Status status = store_->Get(kAbcHash, &bytes);
  EXPECT_EQ(status.code(), Status::Code::kNotFound);
  EXPECT_NE(status.message().find(kAbcHash), std::string::npos);
  bool has = true;
  ASSERT_TRUE(store_->Has(kAbcHash, &has).ok());
  EXPECT_FALSE(has);

  const std::string upper = "BA7816BF8F01CFEA414140DE5DAE2223B00361A396177A9CB410FF61F20015AD";
  for (const std::string& bad : {std::string("ba78"), upper, std::string("../../../etc/passwd"),
                                 std::string(kAbcHash) + "0", std::string()}) {
    EXPECT_EQ(store_->Get(bad, &bytes).code(), Status::Code::kInvalidArgument) << bad;
    EXPECT_EQ(store_->Has(bad, &has).code(), Status::Code::kInvalidArgument) << bad;
  }
}

TEST_F(BlobStoreTest, SweepRemovesUnreferencedBlobsAndStrayTemporaryFiles) {
  const std::string kept = Put("referenced");
  const std::string orphan = Put("orphan");
  // What a crash between write and rename leaves (AtomicWriteText's naming,
  // and the one an earlier version of the store used).
  const fs::path stray = store_->PathOf(kept).parent_path() / ".deadbeef.partial-Ab3xYz";
  Overwrite(stray, "half a blob");
  const fs::path old_stray = store_->PathOf(kept).parent_path() / ".cafe.tmp-12345";
  Overwrite(old_stray, "older");
  // A file that is neither a blob nor ours is left for a person to look at.
  Overwrite(root() / "README", "notes");

  BlobSweepReport report;
  ASSERT_TRUE(store_->Sweep({kept}, &report).ok());
  EXPECT_EQ(report.removed_blobs, 1);
  EXPECT_EQ(report.removed_temp_files, 2);
  EXPECT_EQ(report.removed_bytes, 6);
  EXPECT_EQ(report.kept_blobs, 1);
  EXPECT_FALSE(fs::exists(store_->PathOf(orphan)));
  EXPECT_FALSE(fs::exists(stray));
  EXPECT_FALSE(fs::exists(old_stray));
  EXPECT_TRUE(fs::exists(root() / "README"));
  std::string bytes;
  ASSERT_TRUE(store_->Get(kept, &bytes).ok());
  EXPECT_EQ(bytes, "referenced");

  // Nothing left to remove.
  ASSERT_TRUE(store_->Sweep({kept}, &report).ok());
  EXPECT_EQ(report.removed_blobs + report.removed_temp_files, 0);
  EXPECT_EQ(report.kept_blobs, 1);
}

TEST_F(BlobStoreTest, PutFileMovesTheCheckedFileIntoItsName) {
  const fs::path source = dir_.path() / "upload";
  Overwrite(source, "abc");
  std::unique_ptr<MappedFile> file;
  ASSERT_TRUE(MappedFile::Open(source, &file).ok());
  EXPECT_EQ(file->bytes(), "abc");
  std::string hash;
  ASSERT_TRUE(store_->PutFile(*file, &hash).ok());
  EXPECT_EQ(hash, kAbcHash);
  EXPECT_FALSE(fs::exists(source));
  EXPECT_EQ(Files(), std::vector<std::string>{std::string("ba/") + (kAbcHash + 2)});
  std::string bytes;
  ASSERT_TRUE(store_->Get(kAbcHash, &bytes).ok());
  EXPECT_EQ(bytes, "abc");

  // Stored already: the file stays where it is, the blob as it was.
  Overwrite(source, "abc");
  ASSERT_TRUE(MappedFile::Open(source, &file).ok());
  ASSERT_TRUE(store_->PutFile(*file, &hash).ok());
  EXPECT_TRUE(fs::exists(source));
  EXPECT_EQ(Files().size(), 1u);
}

TEST_F(BlobStoreTest, PutFileCopiesWhenThePathNoLongerNamesTheHashedFile) {
  const fs::path source = dir_.path() / "upload";
  Overwrite(source, "abc");
  std::unique_ptr<MappedFile> file;
  ASSERT_TRUE(MappedFile::Open(source, &file).ok());
  // Another file takes the name after the mapping: it must not become the blob.
  fs::remove(source);
  Overwrite(source, "not abc");
  std::string hash;
  ASSERT_TRUE(store_->PutFile(*file, &hash).ok());
  EXPECT_EQ(hash, kAbcHash);
  std::string bytes;
  ASSERT_TRUE(store_->Get(kAbcHash, &bytes).ok());
  EXPECT_EQ(bytes, "abc");
  std::ifstream in(source);
  std::string left;
  std::getline(in, left);
  EXPECT_EQ(left, "not abc");
}

TEST(MappedFileTest, HashesEmptyAndMissingFiles) {
  TempDir dir;
  std::ofstream(dir.path() / "empty").close();
  std::string hash;
  ASSERT_TRUE(Sha256HexOfFile(dir.path() / "empty", &hash).ok());
  EXPECT_EQ(hash, "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(Sha256HexOfFile(dir.path() / "missing", &hash).code(), Status::Code::kIo);
}

}  // namespace
}  // namespace pba
