// The step port's bookkeeping (step_queue.hpp): steps queued ahead go out in order when
// their time comes, the ones after a time can be taken back, and the net step count at any
// time is known, ahead within the queue and back within the history kept.
#include "node/motion/step_queue.hpp"

#include <gtest/gtest.h>

namespace stepnode::motion {
namespace {

TEST(StepQueue, StepsGoOutInOrderWhenDue) {
  StepQueue q;
  q.push(100, +1);
  q.push(200, +1);
  q.push(300, -1);
  EXPECT_FALSE(q.due(99));
  ASSERT_TRUE(q.due(200));
  EXPECT_EQ(q.pop().time, 100);
  EXPECT_EQ(q.pop().time, 200);
  EXPECT_FALSE(q.due(299));
  EXPECT_EQ(q.count(), 2);
  EXPECT_EQ(q.queued(), 1u);
}

TEST(StepQueue, CancelAfterTakesBackOnlyTheLaterSteps) {
  StepQueue q;
  for (Tick t = 10; t <= 100; t += 10) q.push(t, +1);
  EXPECT_EQ(q.cancel_after(50), 5u);  // 60..100
  EXPECT_EQ(q.queued(), 5u);
  EXPECT_EQ(q.cancel_after(50), 0u);  // a step at exactly 50 stays
  EXPECT_EQ(q.cancel_after(1000), 0u);
}

TEST(StepQueue, PositionAtAPastAndAFutureTime) {
  StepQueue q;
  for (Tick t = 10; t <= 50; t += 10) q.went_out(t, +1);  // five up, gone out
  q.push(60, -1);
  q.push(70, -1);                   // two down, queued
  EXPECT_EQ(q.position_at(5), 0);   // before the first step
  EXPECT_EQ(q.position_at(10), 1);  // a step counts from its tick on
  EXPECT_EQ(q.position_at(35), 3);
  EXPECT_EQ(q.position_at(50), 5);
  EXPECT_EQ(q.position_at(65), 4);  // ahead: the queued step at 60 will have gone out
  EXPECT_EQ(q.position_at(1000), 3);
}

TEST(StepQueue, PositionOlderThanTheHistoryIsNotKnown) {
  StepQueue q(4);  // keeps the last 4 steps that went out
  for (Tick t = 1; t <= 10; ++t) q.went_out(t * 10, +1);
  EXPECT_EQ(q.position_at(100), 10);
  EXPECT_EQ(q.position_at(75), 7);  // 80, 90, 100 undone: within the 4 kept
  EXPECT_EQ(q.position_at(70), 7);  // the oldest kept step is at 70
  // Before it, a forgotten step may lie anywhere between: not known.
  EXPECT_FALSE(q.position_at(69).has_value());
}

}  // namespace
}  // namespace stepnode::motion
