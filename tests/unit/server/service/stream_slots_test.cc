// StreamSlots: a user holds at most per_user() long-lived streams open; one
// user at the limit does not keep another from opening theirs, and a slot
// comes back when its ticket goes.
#include "service/stream_slots.h"

#include <gtest/gtest.h>

#include <vector>

namespace pba {
namespace {

TEST(StreamSlotsTest, AUserAtTheLimitIsRefusedAndOthersAreNot) {
  StreamSlots slots(3);
  std::vector<StreamSlots::Ticket> alice;
  for (int k = 0; k < 3; ++k) {
    alice.push_back(slots.TryAcquire("alice"));
    ASSERT_TRUE(alice.back().held()) << k;
  }
  EXPECT_FALSE(slots.TryAcquire("alice").held());
  EXPECT_EQ(slots.open("alice"), 3);
  const StreamSlots::Ticket bob = slots.TryAcquire("bob");
  EXPECT_TRUE(bob.held());
  EXPECT_EQ(slots.open("bob"), 1);
}

TEST(StreamSlotsTest, ASlotComesBackWhenItsTicketGoesAndOnlyOnce) {
  StreamSlots slots(1);
  {
    StreamSlots::Ticket first = slots.TryAcquire("alice");
    ASSERT_TRUE(first.held());
    // Moved, the slot is still held once: by the new owner only.
    StreamSlots::Ticket moved = std::move(first);
    EXPECT_FALSE(first.held());  // NOLINT(bugprone-use-after-move): the point of the test
    EXPECT_TRUE(moved.held());
    EXPECT_FALSE(slots.TryAcquire("alice").held());
  }
  EXPECT_EQ(slots.open("alice"), 0);
  StreamSlots::Ticket again = slots.TryAcquire("alice");
  EXPECT_TRUE(again.held());
  again = StreamSlots::Ticket();
  EXPECT_EQ(slots.open("alice"), 0);
  EXPECT_TRUE(slots.TryAcquire("alice").held());
}

}  // namespace
}  // namespace pba
