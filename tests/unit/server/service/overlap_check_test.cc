// The commit rule against locked neighbours (overlap_check.h) through the
// real service: a commit that grows into a structure someone else holds
// locked is refused naming it, the holder and the overlap; the same
// geometry goes through once the lock is released, or when the committer
// holds the neighbour.
#include "unit/server/service/atlas_service_fixture.h"

namespace pba::service_test {
namespace {

TEST_F(AtlasServiceTest, ACommitIntoANeighbourSomeoneElseHoldsIsRefused) {
  ASSERT_RPC(Create("bob", "left", Square(0, 10)));
  ASSERT_RPC(Create("bob", "right", Square(20, 30)));
  v1::Lock admins;
  ASSERT_RPC(Acquire("admin", &admins, "right"));
  v1::Lock bobs;
  ASSERT_RPC(Acquire("bob", &bobs, "left"));
  const grpc::Status refused = Commit("bob", bobs.lock_id(), 1, Square(0, 25), nullptr, "left");
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << refused.error_message();
  EXPECT_NE(refused.error_message().find("overlaps 'right', which admin holds locked"),
            std::string::npos)
      << refused.error_message();
  EXPECT_NE(refused.error_message().find("mm^3"), std::string::npos) << refused.error_message();
  EXPECT_EQ(Get("left").head(), 1);
  // Up to the neighbour's edge is fine (a commit keeps its lock).
  v1::Revision revision;
  ASSERT_RPC(Commit("bob", bobs.lock_id(), 1, Square(0, 19.5), &revision, "left"));
  EXPECT_EQ(revision.number(), 2);
  // Once the lock is given back the overlap is the committer's to resolve.
  ASSERT_RPC(Release("admin", admins.lock_id()));
  ASSERT_RPC(Commit("bob", bobs.lock_id(), 2, Square(0, 25), &revision, "left"));
  EXPECT_EQ(revision.number(), 3);
}

TEST_F(AtlasServiceTest, ANeighbourTheCommitterHoldsDoesNotBlockTheCommit) {
  ASSERT_RPC(Create("bob", "left", Square(0, 10)));
  ASSERT_RPC(Create("bob", "right", Square(20, 30)));
  v1::Lock right, left;
  ASSERT_RPC(Acquire("bob", &right, "right"));
  ASSERT_RPC(Acquire("bob", &left, "left"));
  ASSERT_RPC(Commit("bob", left.lock_id(), 1, Square(0, 25), nullptr, "left"));
}

}  // namespace
}  // namespace pba::service_test
