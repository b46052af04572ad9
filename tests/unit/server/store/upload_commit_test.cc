// Creating and committing from an upload without copying it: the upload's
// file is mapped, checked and hashed, and renamed into the blob store
// (BlobStore::PutFile); a commit refused before that leaves no blob and the
// upload whole.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <sstream>

#include "store/upload_store.h"
#include "unit/server/store/atlas_store_fixture.h"

namespace pba::store_test {
namespace {

// Bytes that differ from window to window (MappedFile hashes 16 MiB at a time).
std::string Content(size_t size, char seed) {
  std::string bytes(size, '\0');
  for (size_t i = 0; i < size; ++i) bytes[i] = static_cast<char>(seed + (i * 131) % 251);
  return bytes;
}

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

class UploadCommitTest : public AtlasStoreTest {
 protected:
  void SetUp() override {
    AtlasStoreTest::SetUp();
    ASSERT_OK(UploadStore::Open(dir_.path() / "uploads", &uploads_));
  }

  // A complete upload of `content` by `user`; its id.
  std::string Upload(const std::string& user, const std::string& content) {
    UploadInfo info;
    EXPECT_TRUE(
        uploads_->Begin(user, static_cast<int64_t>(content.size()), Hash(content), &info).ok());
    for (size_t offset = 0; offset < content.size(); offset += UploadStore::kMaxChunkBytes) {
      const std::string_view chunk =
          std::string_view(content).substr(offset, UploadStore::kMaxChunkBytes);
      const Status status =
          uploads_->Write(user, info.id, static_cast<int64_t>(offset), chunk, &info);
      EXPECT_TRUE(status.ok()) << status.ToString();
    }
    return info.id;
  }

  fs::path BlobPath(const std::string& hash) {
    return dir_.path() / "blobs" / hash.substr(0, 2) / hash.substr(2);
  }

  std::unique_ptr<UploadStore> uploads_;
};

TEST_F(UploadCommitTest, ACommittedUploadIsRenamedIntoItsBlob) {
  const std::string content = Content((size_t{33} << 20) + 123, 'a');
  const std::string id = Upload("bob", content);
  const fs::path upload_file = dir_.path() / "uploads" / id;
  std::unique_ptr<MappedFile> mapped;
  ASSERT_OK(uploads_->Take("bob", id, &mapped));
  ASSERT_EQ(mapped->size(), content.size());

  const LockInfo lock = Lock("bob");
  CommitRequest request;
  request.structure = kHippocampus;
  request.lock_id = lock.lock_id;
  request.base_revision = 1;
  request.geometry = mapped->bytes();
  request.geometry_file = mapped.get();
  Revision revision;
  ASSERT_OK(store_->Commit("bob", request, &revision));
  EXPECT_EQ(revision.content_sha256, Hash(content));
  EXPECT_EQ(revision.size_bytes, static_cast<int64_t>(content.size()));

  // The upload's file became the blob: one name, the blob's, and whole.
  const fs::path blob = BlobPath(revision.content_sha256);
  EXPECT_FALSE(fs::exists(upload_file));
  struct stat st {};
  ASSERT_EQ(::stat(blob.c_str(), &st), 0);
  EXPECT_EQ(st.st_nlink, 1u);
  EXPECT_EQ(static_cast<size_t>(st.st_size), content.size());
  EXPECT_TRUE(ReadFile(blob) == content);
  std::string stored;
  ASSERT_OK(store_->GetRevision("carol", kHippocampus, 2, &revision, &stored));
  EXPECT_TRUE(stored == content);
  mapped.reset();

  // A resumed write cannot reach the blob: the upload's path names nothing.
  UploadInfo info;
  EXPECT_FALSE(uploads_->Write("bob", id, static_cast<int64_t>(content.size()), "x", &info).ok());
  EXPECT_FALSE(uploads_->Write("bob", id, 0, "x", &info).ok());
  EXPECT_FALSE(fs::exists(upload_file));
  EXPECT_EQ(Hash(ReadFile(blob)), revision.content_sha256);
  // What is left of the upload is removed.
  ASSERT_OK(uploads_->Remove("bob", id));
  EXPECT_TRUE(fs::is_empty(dir_.path() / "uploads"));

  // The same content again: the stored blob stays, the upload is left to remove.
  const std::string again = Upload("bob", content);
  ASSERT_OK(uploads_->Take("bob", again, &mapped));
  request.base_revision = 2;
  request.geometry = mapped->bytes();
  request.geometry_file = mapped.get();
  ASSERT_OK(store_->Commit("bob", request, &revision));
  EXPECT_EQ(revision.number, 3);
  EXPECT_TRUE(fs::exists(dir_.path() / "uploads" / again));
  EXPECT_EQ(::stat(blob.c_str(), &st), 0);
  EXPECT_EQ(st.st_nlink, 1u);
  mapped.reset();
  ASSERT_OK(uploads_->Remove("bob", again));
  EXPECT_TRUE(fs::is_empty(dir_.path() / "uploads"));

  // A new structure from an upload goes the same way.
  const std::string outline = Content(4096, 'k');
  const std::string created = Upload("bob", outline);
  ASSERT_OK(uploads_->Take("bob", created, &mapped));
  NewStructure create;
  create.structure = {"atlas", "fornix"};
  create.metadata = Metadata();
  create.geometry = mapped->bytes();
  create.geometry_file = mapped.get();
  ASSERT_OK(store_->CreateStructure("bob", create, &revision));
  EXPECT_FALSE(fs::exists(dir_.path() / "uploads" / created));
  EXPECT_TRUE(ReadFile(BlobPath(Hash(outline))) == outline);
}

TEST_F(UploadCommitTest, ACommitRefusedMidwayLeavesNoBlobAndTheUploadWhole) {
  const std::string content = Content((size_t{3} << 20) + 7, 'q');
  const std::string id = Upload("bob", content);
  std::unique_ptr<MappedFile> mapped;
  ASSERT_OK(uploads_->Take("bob", id, &mapped));
  const LockInfo lock = Lock("bob");
  CommitRequest request;
  request.structure = kHippocampus;
  request.lock_id = lock.lock_id;
  request.base_revision = 7;  // stale: refused after the upload was taken
  request.geometry = mapped->bytes();
  request.geometry_file = mapped.get();
  Revision revision;
  EXPECT_STATUS(store_->Commit("bob", request, &revision), Status::Code::kAborted, "head");
  request.base_revision = 1;
  request.lock_id = "not-the-lock";
  EXPECT_STATUS(store_->Commit("bob", request, &revision), Status::Code::kFailedPrecondition,
                "lock");
  mapped.reset();
  EXPECT_FALSE(fs::exists(BlobPath(Hash(content))));
  BlobSweepReport report;
  ASSERT_OK(store_->SweepBlobs(&report));
  EXPECT_EQ(report.removed_blobs, 0);
  EXPECT_EQ(report.removed_temp_files, 0);

  // The upload is whole and can be used again.
  UploadInfo info;
  ASSERT_OK(uploads_->Get("bob", id, &info));
  EXPECT_EQ(info.received_bytes, static_cast<int64_t>(content.size()));
  ASSERT_OK(uploads_->Take("bob", id, &mapped));
  request.lock_id = lock.lock_id;
  request.geometry = mapped->bytes();
  request.geometry_file = mapped.get();
  ASSERT_OK(store_->Commit("bob", request, &revision));
  EXPECT_TRUE(ReadFile(BlobPath(Hash(content))) == content);

  // Content that does not hash to the announced SHA-256 never gets that far:
  // the upload is discarded (upload_store.h), and no blob is written.
  UploadInfo bad;
  const std::string other = Content(1000, 'z');
  ASSERT_OK(uploads_->Begin("bob", 1000, Hash("something else"), &bad));
  ASSERT_OK(uploads_->Write("bob", bad.id, 0, other, &bad));
  EXPECT_STATUS(uploads_->Take("bob", bad.id, &mapped), Status::Code::kInvalidArgument, "sha256");
  EXPECT_STATUS(uploads_->Get("bob", bad.id, &bad), Status::Code::kNotFound, "does not exist");
  EXPECT_FALSE(fs::exists(BlobPath(Hash(other))));
}

}  // namespace
}  // namespace pba::store_test
