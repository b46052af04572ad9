#include "store/upload_store.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <atomic>
#include <fstream>
#include <iterator>
#include <vector>

#include "core/sha256.h"
#include "unit/server/temp_dir.h"

namespace pba {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

constexpr int64_t kSecond = 1000 * 1000;
constexpr int64_t kStart = 1767225600LL * kSecond;

std::string Hash(const std::string& bytes) {
  const std::string hash = Sha256Hex(bytes);
  return hash;
}

#define ASSERT_OK(expr)                              \
  do {                                               \
    const ::pba::Status status_ = (expr);            \
    ASSERT_TRUE(status_.ok()) << status_.ToString(); \
  } while (false)

class UploadStoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_OK(UploadStore::Open(dir_.path(), &uploads_, [this] { return now_.load(); }));
  }

  TempDir dir_;
  std::atomic<int64_t> now_{kStart};
  std::unique_ptr<UploadStore> uploads_;
};

TEST_F(UploadStoreTest, ChunksArriveInOrderAndTheContentIsVerified) {
  const std::string content = "0123456789abcdef";
  UploadInfo info;
  ASSERT_OK(uploads_->Begin("bob", 16, Hash(content), &info));
  EXPECT_TRUE(UploadStore::IsWellFormedId(info.id));
  EXPECT_EQ(info.expire_us, kStart + UploadStore::kLifetimeMicros);
  ASSERT_OK(uploads_->Write("bob", info.id, 0, content.substr(0, 10), &info));
  EXPECT_EQ(info.received_bytes, 10);

  // Out of order: kOutOfRange on the field "offset", naming the received size.
  Status status = uploads_->Write("bob", info.id, 4, "xx", &info);
  EXPECT_EQ(status.code(), Status::Code::kOutOfRange);
  EXPECT_EQ(status.field(), "offset");
  EXPECT_NE(status.message().find("10 bytes have arrived"), std::string::npos) << status.ToString();
  // Past the announced size.
  status = uploads_->Write("bob", info.id, 10, "0123456789", &info);
  EXPECT_EQ(status.field(), "data");
  // Incomplete uploads cannot be taken.
  std::string taken;
  EXPECT_EQ(uploads_->Take("bob", info.id, &taken).code(), Status::Code::kFailedPrecondition);

  ASSERT_OK(uploads_->Write("bob", info.id, 10, content.substr(10), &info));
  // Another user does not see it.
  EXPECT_EQ(uploads_->Get("carol", info.id, &info).code(), Status::Code::kNotFound);
  EXPECT_EQ(uploads_->Take("carol", info.id, &taken).code(), Status::Code::kNotFound);
  ASSERT_OK(uploads_->Get("bob", info.id, &info));
  EXPECT_EQ(info.received_bytes, 16);
  ASSERT_OK(uploads_->Take("bob", info.id, &taken));
  EXPECT_EQ(taken, content);
  // Taking does not remove; Remove does, and a second Remove is fine.
  ASSERT_OK(uploads_->Get("bob", info.id, &info));
  ASSERT_OK(uploads_->Remove("bob", info.id));
  ASSERT_OK(uploads_->Remove("bob", info.id));
  EXPECT_EQ(uploads_->Get("bob", info.id, &info).code(), Status::Code::kNotFound);
  EXPECT_FALSE(fs::exists(dir_.path() / info.id));
}

TEST_F(UploadStoreTest, AWrongHashDiscardsTheUpload) {
  UploadInfo info;
  ASSERT_OK(uploads_->Begin("bob", 3, Hash("abc"), &info));
  ASSERT_OK(uploads_->Write("bob", info.id, 0, "abd", &info));
  std::string taken;
  const Status status = uploads_->Take("bob", info.id, &taken);
  EXPECT_EQ(status.code(), Status::Code::kInvalidArgument);
  EXPECT_EQ(status.field(), "sha256");
  EXPECT_TRUE(taken.empty());
  EXPECT_EQ(uploads_->Get("bob", info.id, &info).code(), Status::Code::kNotFound);
}

TEST_F(UploadStoreTest, BadRequestsAndHostileIdsAreRefused) {
  UploadInfo info;
  EXPECT_EQ(uploads_->Begin("bob", 0, Hash(""), &info).field(), "size_bytes");
  EXPECT_EQ(uploads_->Begin("bob", UploadStore::kMaxUploadBytes + 1, Hash(""), &info).field(),
            "size_bytes");
  EXPECT_EQ(uploads_->Begin("bob", 3, "ABC", &info).field(), "sha256");
  ASSERT_OK(uploads_->Begin("bob", 3, Hash("abc"), &info));
  EXPECT_EQ(
      uploads_->Write("bob", info.id, 0, std::string(UploadStore::kMaxChunkBytes + 1, 'x'), &info)
          .field(),
      "data");
  for (const std::string& id :
       std::vector<std::string>{"../pba.db", "/etc/passwd", info.id + "/..", info.id + ".meta",
                                std::string(32, 'G'), std::string()}) {
    EXPECT_NE(uploads_->Get("bob", id, &info).code(), Status::Code::kOk) << id;
    EXPECT_NE(uploads_->Write("bob", id, 0, "a", &info).code(), Status::Code::kOk) << id;
  }
}

TEST_F(UploadStoreTest, ExpiredUploadsAreRemovedWhenTouchedOrSwept) {
  UploadInfo first, second;
  ASSERT_OK(uploads_->Begin("bob", 3, Hash("abc"), &first));
  ASSERT_OK(uploads_->Begin("bob", 3, Hash("abc"), &second));
  // Strays: a data file without its metadata, a temporary file.
  std::ofstream(dir_.path() / std::string(32, 'a')) << "stray";
  std::ofstream(dir_.path() / ".x.meta.tmp-1") << "stray";
  int removed = 0;
  ASSERT_OK(uploads_->Sweep(&removed));
  EXPECT_EQ(removed, 2);

  now_ = kStart + UploadStore::kLifetimeMicros;
  UploadInfo info;
  EXPECT_EQ(uploads_->Get("bob", first.id, &info).code(), Status::Code::kNotFound);
  EXPECT_FALSE(fs::exists(dir_.path() / first.id));
  ASSERT_OK(uploads_->Sweep(&removed));
  EXPECT_EQ(removed, 2);  // the second upload's two files
  EXPECT_TRUE(fs::is_empty(dir_.path()));
}

}  // namespace
}  // namespace pba

namespace pba {
namespace {

// A user's open uploads may announce at most the quota together: past it
// Begin is refused (field "upload_quota", RESOURCE_EXHAUSTED at the
// service) naming the quota, before any file is made; removing (DiscardUpload)
// or expiry frees the share; other users have their own; a reopened store
// (a server restart) still counts what is open.
TEST_F(UploadStoreTest, QuotaBoundsTheBytesAUserHasAnnounced) {
  constexpr int64_t kGiB = int64_t{1} << 30;
  uploads_->set_quota_bytes(4 * kGiB);
  const std::string hash = Hash("x");
  std::vector<UploadInfo> open(4);
  for (UploadInfo& info : open) ASSERT_OK(uploads_->Begin("bob", kGiB, hash, &info));
  const auto files = [&] {
    return std::distance(fs::directory_iterator(dir_.path()), fs::directory_iterator());
  };
  const auto before = files();
  UploadInfo refused;
  Status status = uploads_->Begin("bob", 1, hash, &refused);
  EXPECT_EQ(status.code(), Status::Code::kResourceExhausted);
  EXPECT_EQ(status.field(), "upload_quota");
  EXPECT_NE(status.message().find("upload quota of 4294967296 bytes"), std::string::npos)
      << status.ToString();
  EXPECT_EQ(files(), before);
  // Someone else is not held back by bob.
  UploadInfo carols;
  ASSERT_OK(uploads_->Begin("carol", kGiB, hash, &carols));

  // A discarded upload frees its share.
  ASSERT_OK(uploads_->Remove("bob", open[0].id));
  ASSERT_OK(uploads_->Begin("bob", kGiB, hash, &open[0]));
  EXPECT_EQ(uploads_->Begin("bob", 1, hash, &refused).field(), "upload_quota");

  // A restart forgets nothing.
  uploads_.reset();
  ASSERT_OK(UploadStore::Open(dir_.path(), &uploads_, [this] { return now_.load(); }));
  uploads_->set_quota_bytes(4 * kGiB);
  EXPECT_EQ(uploads_->Begin("bob", 1, hash, &refused).field(), "upload_quota");

  // Expired uploads count no more (and are removed).
  now_ += UploadStore::kLifetimeMicros;
  for (int i = 0; i < 4; ++i) ASSERT_OK(uploads_->Begin("bob", kGiB, hash, &refused));
  EXPECT_FALSE(fs::exists(dir_.path() / open[1].id));
}

// Without a byte quota, the number of open uploads is still bounded (each
// is two files).
TEST_F(UploadStoreTest, OpenUploadsAreCountedWithoutAQuota) {
  const std::string hash = Hash("x");
  UploadInfo info;
  for (int i = 0; i < UploadStore::kMaxOpenUploads; ++i) {
    ASSERT_OK(uploads_->Begin("bob", 1, hash, &info));
  }
  const Status status = uploads_->Begin("bob", 1, hash, &info);
  EXPECT_EQ(status.field(), "upload_quota");
  EXPECT_NE(status.message().find("1000 open uploads"), std::string::npos) << status.ToString();
}

}  // namespace
}  // namespace pba
