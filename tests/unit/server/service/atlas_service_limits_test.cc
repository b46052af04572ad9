// The atlas service's bounds (issue 18): the per-user upload quota and
// DiscardUpload, which frees a share of it; shape comparisons of shapes a
// metre across, coarsened to the voxel budget, at most two at once, and a
// shutdown that does not wait for them.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "common/bounded_run.h"
#include "unit/server/service/atlas_service_fixture.h"

namespace pba::service_test {
namespace {

using std::chrono::seconds;

constexpr int64_t kQuota = 64 * 1024;

// A quota of 64 KiB a user (pba-server's default is 4 GiB).
class AtlasQuotaTest : public AtlasServiceTest {
 protected:
  void SetUp() override {
    options_.upload_quota_bytes = kQuota;
    AtlasServiceTest::SetUp();
  }

  grpc::Status Discard(const std::string& user, const std::string& id) {
    v1::DiscardUploadRequest request;
    request.set_upload_id(id);
    v1::DiscardUploadResponse response;
    return Call(user, &v1::AtlasService::Stub::DiscardUpload, request, &response);
  }

  grpc::Status GetUpload(const std::string& user, const std::string& id) {
    v1::GetUploadRequest request;
    request.set_upload_id(id);
    v1::Upload upload;
    return Call(user, &v1::AtlasService::Stub::GetUpload, request, &upload);
  }
};

TEST_F(AtlasQuotaTest, ABeginPastTheQuotaIsResourceExhaustedUntilTheUploadIsDiscarded) {
  const std::string content(40 * 1024, 'x');
  v1::Upload first;
  ASSERT_RPC(Begin("bob", content, &first));
  // Unwritten, it still holds its announced share: a second would pass the
  // quota.
  v1::Upload second;
  EXPECT_CODE(Begin("bob", content, &second), grpc::StatusCode::RESOURCE_EXHAUSTED, "upload_quota");
  EXPECT_CODE(Begin("bob", content, &second), grpc::StatusCode::RESOURCE_EXHAUSTED,
              std::to_string(kQuota));
  EXPECT_CODE(Begin("bob", content, &second), grpc::StatusCode::RESOURCE_EXHAUSTED,
              "DiscardUpload");
  // The quota is each user's: carol's share is her own.
  v1::Upload carols;
  ASSERT_RPC(Begin("carol", content, &carols));

  // Someone else's upload is left alone, and answered as one already gone
  // is (not an error), so that ids cannot be probed.
  ASSERT_RPC(Discard("carol", first.id()));
  ASSERT_RPC(GetUpload("bob", first.id()));
  EXPECT_CODE(Begin("bob", content, &second), grpc::StatusCode::RESOURCE_EXHAUSTED, "upload_quota");
  ASSERT_RPC(Discard("bob", std::string(32, 'a')));
  EXPECT_CODE(Discard("bob", "../pba.db"), grpc::StatusCode::INVALID_ARGUMENT, "upload_id");
  EXPECT_CODE(Discard("bob", ""), grpc::StatusCode::INVALID_ARGUMENT, "upload_id");

  // Bob discards his own: its files go and its share is free again.
  ASSERT_RPC(Discard("bob", first.id()));
  EXPECT_CODE(GetUpload("bob", first.id()), grpc::StatusCode::NOT_FOUND, "");
  EXPECT_FALSE(fs::exists(options_.data_dir / "uploads" / first.id()));
  EXPECT_FALSE(fs::exists(options_.data_dir / "uploads" / (first.id() + ".meta")));
  ASSERT_RPC(Begin("bob", content, &second));
  // A second discard of the same upload is not an error either.
  ASSERT_RPC(Discard("bob", first.id()));
}

// A complete upload counts until it is used: the create consumes it.
TEST_F(AtlasQuotaTest, AnUploadUsedByACreateFreesItsShare) {
  const std::string content = Contours(40 * 1024, 3);
  ASSERT_RPC(Create("bob", "heart", content));
  v1::Upload again;
  ASSERT_RPC(Begin("bob", content, &again));
}

// A binary STL of the box [lo, hi]^3 [mm] shifted by `dx` in x at its low
// face: 12 triangles wound outward, 684 bytes.
std::string BoxStl(float lo, float hi, float dx = 0) {
  std::string stl(80, ' ');
  const auto put = [&](const void* bytes, size_t n) {
    stl.append(static_cast<const char*>(bytes), n);
  };
  const uint32_t count = 12;
  put(&count, sizeof count);
  const auto corner = [&](int bits, int axis) {
    const float low = axis == 0 ? lo + dx : lo;
    return bits >> axis & 1 ? hi : low;
  };
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      const int u = 1 << ((axis + 1) % 3), v = 1 << ((axis + 2) % 3), w = side << axis;
      // Around the face from the outside, counter-clockwise: u, then v
      // (right-handed for the high side, reversed for the low one).
      int quad[4] = {w, w | u, w | u | v, w | v};
      if (side == 0) std::swap(quad[1], quad[3]);
      float normal[3] = {0, 0, 0};
      normal[axis] = side == 0 ? -1.0f : 1.0f;
      for (const auto& triangle : {std::vector<int>{0, 1, 2}, std::vector<int>{0, 2, 3}}) {
        put(normal, sizeof normal);
        for (int i : triangle) {
          const float p[3] = {corner(quad[i], 0), corner(quad[i], 1), corner(quad[i], 2)};
          put(p, sizeof p);
        }
        const uint16_t attribute = 0;
        put(&attribute, sizeof attribute);
      }
    }
  }
  return stl;
}

// "box" at revision 1 a cube of 990 mm, at revision 2 one 10 mm shorter in
// x: at 1 mm voxels their comparison would hold 10^9 voxels. While a test
// runs, the process may map at most 2 GiB more than it had (the soft
// RLIMIT_AS): a comparison past the budget fails the test with bad_alloc
// instead of taking tens of GB of the machine's memory.
class AtlasDiffLimitsTest : public AtlasServiceTest {
 protected:
  void SetUp() override {
    ASSERT_EQ(::getrlimit(RLIMIT_AS, &saved_limit_), 0);
    rlimit bounded = saved_limit_;
    bounded.rlim_cur = static_cast<rlim_t>(test::MappedBytesForTest() + (int64_t{2} << 30));
    if (saved_limit_.rlim_cur == RLIM_INFINITY || bounded.rlim_cur < saved_limit_.rlim_cur) {
      ASSERT_EQ(::setrlimit(RLIMIT_AS, &bounded), 0);
    }
    AtlasServiceTest::SetUp();
    if (HasFatalFailure()) return;
    v1::CreateStructureRequest create;
    create.set_project("atlas");
    create.set_name("box");
    create.set_format(v1::STL);
    create.set_upload_id(Upload("bob", BoxStl(-495, 495)));
    v1::Revision revision;
    ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::CreateStructure, create, &revision));
    v1::Lock lock;
    ASSERT_RPC(Acquire("bob", &lock, "box"));
    v1::CommitStructureRequest commit;
    commit.set_project("atlas");
    commit.set_structure("box");
    commit.set_lock_id(lock.lock_id());
    commit.set_base_revision(1);
    commit.set_format(v1::STL);
    commit.set_upload_id(Upload("bob", BoxStl(-495, 495, 10)));
    commit.set_message("10 mm off one face");
    ASSERT_RPC(Call("bob", &v1::AtlasService::Stub::CommitStructure, commit, &revision));
    ASSERT_EQ(revision.number(), 2);
  }

  // carol (a viewer) compares revisions 1 and 2, waiting up to `patience`.
  grpc::Status Diff(v1::RevisionDiff* diff, seconds patience = seconds(120)) {
    grpc::ClientContext context;
    Authorize(&context, "carol");
    context.set_deadline(std::chrono::system_clock::now() + patience);
    v1::DiffRevisionsRequest request;
    request.set_project("atlas");
    request.set_structure("box");
    request.set_from_revision(1);
    request.set_to_revision(2);
    return stub_->DiffRevisions(&context, request, diff);
  }

  void TearDown() override {
    AtlasServiceTest::TearDown();
    ::setrlimit(RLIMIT_AS, &saved_limit_);
  }

  rlimit saved_limit_{};
};

// Three at once: two run, the third waits its turn rather than being
// refused, and each is coarsened to the budget (6 mm voxels) with its
// volumes about right.
TEST_F(AtlasDiffLimitsTest, ThreeComparisonsOfAMetreAllAnswerOnCoarserVoxels) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::pair<grpc::Status, v1::RevisionDiff>> results(3);
  std::vector<std::thread> callers;
  for (auto& result : results) {
    callers.emplace_back([&] { result.first = Diff(&result.second); });
  }
  for (std::thread& caller : callers) caller.join();
  std::printf("three comparisons of 990 mm boxes answered in %.2f s\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  for (const auto& [status, diff] : results) {
    ASSERT_TRUE(status.ok()) << status.error_code() << " " << status.error_message();
    EXPECT_TRUE(diff.geometry_changed());
    EXPECT_EQ(diff.shape().voxel_mm(), 6.0);
    EXPECT_NEAR(diff.shape().from_volume_mm3(), 990.0 * 990 * 990, 0.03 * 990.0 * 990 * 990);
    EXPECT_NEAR(diff.shape().to_volume_mm3(), 980.0 * 990 * 990, 0.03 * 980.0 * 990 * 990);
    EXPECT_GT(diff.shape().dice(), 0.98);
  }
}

// Four comparisons in flight when the server stops: the two waiting for a
// slot give up at once (UNAVAILABLE), the two running finish their bounded
// voxelisation, and the shutdown is over within seconds (before the budget,
// four of these kept a server from stopping for more than 90 s).
TEST_F(AtlasDiffLimitsTest, AShutdownWithComparisonsInFlightEndsWithinSeconds) {
  std::vector<grpc::Status> results(4);
  std::vector<std::thread> callers;
  for (grpc::Status& result : results) {
    callers.emplace_back([&] {
      v1::RevisionDiff diff;
      result = Diff(&diff);
    });
  }
  // Long enough for the calls to arrive, far shorter than a comparison.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const auto start = std::chrono::steady_clock::now();
  server_->Shutdown();
  const double shutdown_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (std::thread& caller : callers) caller.join();
  std::printf("shutdown with four comparisons in flight took %.2f s\n", shutdown_s);
  EXPECT_LT(shutdown_s, 15.0);
  for (const grpc::Status& status : results) {
    EXPECT_TRUE(status.ok() || status.error_code() == grpc::StatusCode::UNAVAILABLE ||
                status.error_code() == grpc::StatusCode::CANCELLED)
        << status.error_code() << " " << status.error_message();
    std::printf("  %d %s\n", static_cast<int>(status.error_code()), status.error_message().c_str());
  }
}

}  // namespace
}  // namespace pba::service_test
