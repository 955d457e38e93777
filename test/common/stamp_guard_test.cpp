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

// A companion without a real-time clock boots at some old date: its inputs' stamps are far
// ahead of its wall clock. After a second of steady stamps they are the time base, instead of
// every first stamp being refused as "ahead" for ever.
TEST(StampGuardTest, AWallClockFarBehindTheInputsTakesTheirTimeBase) {
  StampGuard g;
  const int64_t boot_wall = 86400 * kSec;  // 1970-01-02: no RTC, no NTP yet
  int64_t steady = 0;
  StampVerdict v = StampVerdict::kAhead;
  int n = 0;
  for (; n < 200 && v == StampVerdict::kAhead; ++n, steady += 10'000)
    v = g.check("MOCAP_POSE", kWall + steady, steady, boot_wall + steady);
  EXPECT_EQ(v, StampVerdict::kAdopted);
  EXPECT_TRUE(g.inputs_time_base());
  EXPECT_GE(steady, kSec);  // not before a second of steady stamps
  EXPECT_LE(steady, kSec + 20'000);
  // From then on the source is accepted and the others are judged against it.
  EXPECT_EQ(g.check("MOCAP_POSE", kWall + steady, steady, boot_wall + steady),
            StampVerdict::kAccepted);
  EXPECT_EQ(g.check("IMU", kWall + steady + 1000, steady + 1000, boot_wall + steady),
            StampVerdict::kAccepted);
  EXPECT_EQ(g.check("IMU", kWall + steady + 3600 * kSec, steady + 2000, boot_wall + steady),
            StampVerdict::kAhead);
}

// One forged stamp far ahead, or a source whose stamps jump about, never becomes the time base;
// a source near the wall clock is accepted meanwhile and is then the reference.
TEST(StampGuardTest, AnUnsteadyOrSingleFarAheadStampIsNotAdopted) {
  StampGuard g;
  int64_t steady = 0;
  for (int i = 0; i < 300; ++i, steady += 10'000) {
    const int64_t jump = (i % 2) ? 0 : 50 * kSec * (i + 1);  // not in step with the steady clock
    EXPECT_EQ(g.check("FORGED", kWall + 3600 * kSec + jump, steady, kWall + steady),
              StampVerdict::kAhead);
  }
  EXPECT_FALSE(g.inputs_time_base());
  EXPECT_EQ(g.check("IMU", kWall + steady, steady, kWall + steady), StampVerdict::kAccepted);
  EXPECT_EQ(g.check("FORGED", kWall + 3600 * kSec, steady + 10'000, kWall + steady),
            StampVerdict::kAhead);
}

}  // namespace
}  // namespace alight
