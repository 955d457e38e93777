// StampGuard: per-source plausibility of message stamps (issue 14).
#include "common/stamp_guard.hpp"

#include <gtest/gtest.h>

namespace alight {
namespace {

constexpr int64_t kWall = 1'700'000'000'000'000;  // a wall clock [us]
constexpr int64_t kSec = 1'000'000;

TEST(StampGuardTest, AcceptsASteadyStream) {
  StampGuard g;
  for (int i = 0; i < 100; ++i)
    EXPECT_EQ(g.check("POSE", kWall + i * 10'000, i * 10'000, kWall + i * 10'000),
              StampVerdict::kAccepted);
  EXPECT_EQ(g.newest_utime(), kWall + 99 * 10'000);
}

TEST(StampGuardTest, RefusesNonPositive) {
  StampGuard g;
  EXPECT_EQ(g.check("SP", 0, 0, kWall), StampVerdict::kNonPositive);
  EXPECT_EQ(g.check("SP", -5, 0, kWall), StampVerdict::kNonPositive);
  EXPECT_EQ(g.newest_utime(), 0);
}

// Regression (issue 14): one IMU message stamped an hour ahead kept autonomy in FAILSAFE for
// good, and poisoned the outer loop and vision (every later pose refused).
TEST(StampGuardTest, OneStampAnHourAheadIsRefusedAndDoesNotPoisonTheSource) {
  StampGuard g;
  ASSERT_TRUE(stamp_ok(g.check("IMU", kWall, 0, kWall)));
  ASSERT_TRUE(stamp_ok(g.check("POSE", kWall + 1000, 1000, kWall + 1000)));
  EXPECT_EQ(g.check("IMU", kWall + 3600 * kSec, 5000, kWall + 5000), StampVerdict::kAhead);
  EXPECT_EQ(g.newest_utime(), kWall + 1000);
  EXPECT_EQ(g.check("IMU", kWall + 10'000, 10'000, kWall + 10'000), StampVerdict::kAccepted);
  EXPECT_EQ(g.check("POSE", kWall + 11'000, 11'000, kWall + 11'000), StampVerdict::kAccepted);
}

TEST(StampGuardTest, FirstStampOfANewSourceJudgedAgainstTheOthers) {
  StampGuard g;
  ASSERT_TRUE(stamp_ok(g.check("POSE", kWall, 0, kWall)));
  EXPECT_EQ(g.check("IMU", kWall + 3600 * kSec, 0, kWall), StampVerdict::kAhead);
  EXPECT_EQ(g.check("IMU", kWall + 100, 0, kWall), StampVerdict::kAccepted);
}

TEST(StampGuardTest, FirstStampOfAllJudgedAgainstTheWallClock) {
  StampGuard g;
  EXPECT_EQ(g.check("IMU", kWall + 3600 * kSec, 0, kWall), StampVerdict::kAhead);
  // A log replayed into a fresh node: old stamps are fine.
  EXPECT_EQ(g.check("IMU", kWall - 86400 * kSec, 0, kWall), StampVerdict::kAccepted);
}

// Regression (issue 14): a log replayed onto the live port replaced new poses with old ones.
TEST(StampGuardTest, OldMessagesInterleavedWithALiveStreamAreRefused) {
  StampGuard g;
  int64_t t = 0;
  for (int i = 0; i < 300; ++i, t += 10'000) {
    EXPECT_EQ(g.check("POSE", kWall + t, t, kWall + t), StampVerdict::kAccepted);
    EXPECT_EQ(g.check("POSE", kWall - 600 * kSec + t, t + 1, kWall + t), StampVerdict::kBackwards);
  }
}

TEST(StampGuardTest, ASourceThatRestartsLowerIsTakenBackAfterTheResetTime) {
  StampGuardParams p;
  p.reset_after_s = 1.0;
  StampGuard g(p);
  ASSERT_TRUE(stamp_ok(g.check("CAMERA", kWall + 50 * kSec, 0, kWall)));
  // The device reopens and its stamps restart lower.
  EXPECT_EQ(g.check("CAMERA", kWall, 500'000, kWall), StampVerdict::kBackwards);
  EXPECT_EQ(g.check("CAMERA", kWall + 1, 1'100'000, kWall), StampVerdict::kRestarted);
  EXPECT_EQ(g.check("CAMERA", kWall + 33'000, 1'133'000, kWall), StampVerdict::kAccepted);
  EXPECT_EQ(g.newest_utime(), kWall + 33'000);
}

TEST(StampGuardTest, AllowsASimulatorFasterThanRealTime) {
  StampGuard g;  // max_rate 20
  int64_t steady = 0;
  for (int i = 0; i < 1000; ++i, steady += 1000)  // 10x real time: 10 ms of stamps per 1 ms
    EXPECT_EQ(g.check("POSE", kWall + i * 10'000, steady, kWall), StampVerdict::kAccepted);
}

TEST(StampGuardTest, AGapIsFineWhenTheSteadyClockAgrees) {
  StampGuard g;
  ASSERT_TRUE(stamp_ok(g.check("POSE", kWall, 0, kWall)));
  EXPECT_EQ(g.check("POSE", kWall + 5 * kSec, 5 * kSec, kWall + 5 * kSec), StampVerdict::kAccepted);
  EXPECT_EQ(g.check("POSE", kWall + 500 * kSec, 5 * kSec + 1000, kWall), StampVerdict::kAhead);
}

}  // namespace
}  // namespace alight
