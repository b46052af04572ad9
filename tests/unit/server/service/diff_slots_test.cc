// DiffSlots: at most two shape comparisons at once (issue 18); a third
// waits its turn, gives up when its caller goes, and is refused as busy
// when no slot frees in time.
#include "service/diff_slots.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

namespace pba {
namespace {

using std::chrono::milliseconds;

TEST(DiffSlotsTest, AThirdWaitsUntilOneIsReleased) {
  DiffSlots slots(2);
  ASSERT_TRUE(slots.Acquire(nullptr, milliseconds(0)).ok());
  ASSERT_TRUE(slots.Acquire(nullptr, milliseconds(0)).ok());
  std::atomic<bool> got{false};
  Status third;
  std::thread waiter([&] {
    third = slots.Acquire(nullptr, milliseconds(20000));
    got.store(true);
  });
  std::this_thread::sleep_for(milliseconds(200));
  EXPECT_FALSE(got.load()) << "a third comparison ran beside two";
  slots.Release();
  waiter.join();
  EXPECT_TRUE(third.ok()) << third.ToString();
}

TEST(DiffSlotsTest, NoSlotInTimeIsBusyNamingTheSlots) {
  DiffSlots slots(2);
  ASSERT_TRUE(slots.Acquire(nullptr, milliseconds(0)).ok());
  ASSERT_TRUE(slots.Acquire(nullptr, milliseconds(0)).ok());
  const auto start = std::chrono::steady_clock::now();
  const Status busy = slots.Acquire(nullptr, milliseconds(150));
  EXPECT_GE(std::chrono::steady_clock::now() - start, milliseconds(150));
  EXPECT_EQ(busy.code(), Status::Code::kResourceExhausted) << busy.ToString();
  EXPECT_EQ(busy.field(), "diff_slots");
  EXPECT_NE(busy.message().find("busy"), std::string::npos) << busy.ToString();
}

// The caller going (or the server stopping) ends the wait within its 50 ms
// poll, long before the patience runs out; the slot is not taken.
TEST(DiffSlotsTest, AWaitEndsWhenItsCallerGoes) {
  DiffSlots slots(1);
  ASSERT_TRUE(slots.Acquire(nullptr, milliseconds(0)).ok());
  std::atomic<bool> gone{false};
  Status waited;
  const auto start = std::chrono::steady_clock::now();
  std::thread waiter(
      [&] { waited = slots.Acquire([&] { return gone.load(); }, milliseconds(30000)); });
  std::this_thread::sleep_for(milliseconds(100));
  gone.store(true);
  waiter.join();
  EXPECT_LT(std::chrono::steady_clock::now() - start, milliseconds(5000));
  EXPECT_EQ(waited.code(), Status::Code::kCancelled) << waited.ToString();
  slots.Release();
  EXPECT_TRUE(slots.Acquire(nullptr, milliseconds(0)).ok());
  EXPECT_EQ(slots.Acquire(nullptr, milliseconds(0)).code(), Status::Code::kResourceExhausted)
      << "the cancelled wait took a slot";
}

}  // namespace
}  // namespace pba
