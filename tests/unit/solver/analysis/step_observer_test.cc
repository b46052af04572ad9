// The observers every integrator shares (analysis/step_observer.h):
// progress on its schedule and a cancelled job stopping the run, history
// rows every n steps or every interval of time (within a thousandth of a
// step, and at the last), the list stopping at the first refusal.
#include "analysis/step_observer.h"

#include <gtest/gtest.h>

#include <atomic>
#include <string>
#include <vector>

namespace pba {
namespace {

TEST(StepObserverTest, ProgressReportsOnItsScheduleAndStopsACancelledRun) {
  std::atomic<bool> cancel{false};
  std::vector<std::string> messages;
  SolveOptions options;
  options.cancel = &cancel;
  options.progress = [&](const ProgressEvent& event) { messages.push_back(event.message); };
  std::vector<PhaseTime> times;
  PhaseClock clock(options, &times);
  clock.Begin("integrate", 0, 1, "stepping");
  int described = 0;
  ProgressObserver progress(&clock, 10, "the test loop", [&](const StepState& s) {
    ++described;
    return "step " + std::to_string(s.step);
  });
  for (int64_t step = 1; step <= 35; ++step) {
    ASSERT_TRUE(progress.AfterStep({step, 0.0, step / 100.0}).ok());
  }
  EXPECT_EQ(described, 3);  // steps 10, 20, 30
  cancel = true;
  EXPECT_TRUE(progress.AfterStep({36, 0.0, 0.36}).ok());  // not on the schedule
  const Status stopped = progress.AfterStep({40, 0.0, 0.4});
  EXPECT_EQ(stopped.code(), Status::Code::kCancelled);
  EXPECT_EQ(stopped.message(), "cancelled during the test loop");
}

TEST(StepObserverTest, HistoryRowsEveryNStepsOrEveryIntervalOfTime) {
  std::vector<std::vector<double>> rows;
  HistoryObserver every_three(&rows, 3, 0, [](const StepState& s) {
    return std::vector<double>{static_cast<double>(s.step)};
  });
  for (int64_t step = 0; step <= 7; ++step) ASSERT_TRUE(every_three.AfterStep({step}).ok());
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0][0], 0);
  EXPECT_EQ(rows[2][0], 6);

  // Time: a row at t = 0, then at each multiple of 0.1 s; steps of 0.03 s
  // land near 0.1 within rounding (0.09 + 0.03 = 0.12 first passes it).
  rows.clear();
  HistoryObserver timed(&rows, 0, 0.1,
                        [](const StepState& s) { return std::vector<double>{s.time_s}; });
  timed.SetStep(0.03);
  double t = 0;
  for (int64_t step = 0; step < 12; ++step, t += 0.03) {
    ASSERT_TRUE(timed.AfterStep({step, t, t / 0.33, false}).ok());
  }
  ASSERT_EQ(rows.size(), 4u);  // 0, 0.12, 0.21, 0.30
  EXPECT_NEAR(rows[1][0], 0.12, 1e-12);
  EXPECT_NEAR(rows[3][0], 0.30, 1e-12);
  // Within a thousandth of a step of the next multiple counts as on it.
  rows.clear();
  HistoryObserver near(&rows, 0, 0.1,
                       [](const StepState& s) { return std::vector<double>{s.time_s}; });
  near.SetStep(0.05);
  ASSERT_TRUE(near.AfterStep({0, 0.0}).ok());
  EXPECT_FALSE(near.Due({1, 0.1 - 1e-4}));
  EXPECT_TRUE(near.Due({1, 0.1 - 1e-5}));
  EXPECT_TRUE(near.Due({1, 0.05, 0.5, true}));  // the last step always writes
}

// Refuses from its n-th step on.
class Refuser final : public StepObserver {
 public:
  explicit Refuser(int64_t from) : from_(from) {}
  Status AfterStep(const StepState& state) override {
    return state.step >= from_ ? Status::Numerical("refused") : Status::Ok();
  }

 private:
  int64_t from_;
};

TEST(StepObserverTest, TheListStopsAtTheFirstRefusal) {
  std::vector<std::vector<double>> rows;
  HistoryObserver history(&rows, 1, 0, [](const StepState& s) {
    return std::vector<double>{static_cast<double>(s.step)};
  });
  Refuser refuser(2);
  StepObservers list;
  list.Add(&refuser);
  list.Add(&history);
  EXPECT_TRUE(list.AfterStep({1}).ok());
  const Status status = list.AfterStep({2});
  EXPECT_EQ(status.code(), Status::Code::kNumerical);
  // The history after the refuser was not told of step 2.
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0][0], 1);
}

}  // namespace
}  // namespace pba
