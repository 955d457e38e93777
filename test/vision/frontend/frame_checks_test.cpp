// A frame's checks before its features (vision/frontend/frame_checks.hpp): exposure steps,
// smaller exposure changes, the driver's repeats.
#include "vision/frontend/frame_checks.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace alight::vision {
namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;
constexpr int64_t kPeriod = 33'333;  // 30 Hz

TEST(FrameChecksTest, LevelIsTheMeanGreyLevelOfTheSample) {
  EXPECT_DOUBLE_EQ(frame_level(cv::Mat(480, 640, CV_8UC1, cv::Scalar(77))), 77.0);
  cv::Mat half(480, 640, CV_8UC1, cv::Scalar(0));
  half.rowRange(240, 480).setTo(200);
  EXPECT_DOUBLE_EQ(frame_level(half), 100.0);
  EXPECT_EQ(frame_level(cv::Mat()), 0.0);
}

TEST(FrameChecksTest, SteadyBrightnessChangesNothing) {
  ExposureGuard g;
  for (int i = 0; i < 30; ++i) {
    // The scene's own wander, within the dead band.
    const ExposureCheck c = g.check(100.0 * (1 + 0.2 * std::sin(0.3 * i)), kT0 + i * kPeriod);
    EXPECT_FALSE(c.step) << i;
    EXPECT_EQ(c.threshold_scale, 1.0) << i;
  }
}

// The simulator's step: +-2 EV, brought back linearly over 6 frames.
TEST(FrameChecksTest, AStepIsRefusedUntilTheExposureComesBackAndScaledOnTheWay) {
  for (const double ev : {2.0, -2.0}) {
    SCOPED_TRACE(ev);
    ExposureGuard g;
    int64_t t = kT0;
    for (int i = 0; i < 10; ++i, t += kPeriod) ASSERT_FALSE(g.check(100.0, t).step);
    std::vector<ExposureCheck> checks;
    for (int k = 0; k <= 6; ++k, t += kPeriod)
      checks.push_back(g.check(100.0 * std::exp2(ev * (1.0 - k / 6.0)), t));
    // 2, 1.67, 1.33 EV: steps; 1 EV and less: taken.
    EXPECT_TRUE(checks[0].step && checks[1].step && checks[2].step);
    for (int k = 3; k <= 6; ++k) EXPECT_FALSE(checks[k].step) << k;
    // At 1 EV and 0.67 EV the detector's threshold follows the brightness.
    EXPECT_NEAR(checks[3].threshold_scale, std::exp2(ev / 2), 1e-9);
    EXPECT_NEAR(std::log2(checks[4].threshold_scale), checks[4].ev, 1e-12);
    EXPECT_GT(std::abs(checks[4].ev), ExposureGuard::kDeadBandEv);
    EXPECT_EQ(checks[6].threshold_scale, 1.0);
  }
}

TEST(FrameChecksTest, AStepThatClipsIsAStepThoughItsLevelRoseLess) {
  cv::Mat view(480, 640, CV_8UC1);
  cv::randu(view, 20, 240);  // a bright view: up to 240
  cv::Mat up;
  view.convertTo(up, CV_8U, 4.0);  // +2 EV: most of it clipped at 255
  EXPECT_LT(std::log2(frame_level(up) / frame_level(view)), ExposureGuard::kStepEv);
  EXPECT_GT(clipped_share(up), 0.5);
  EXPECT_EQ(clipped_share(view), 0.0);
  ExposureGuard g;
  for (int i = 0; i < 5; ++i)
    ASSERT_FALSE(g.check(frame_level(view), kT0 + i * kPeriod, clipped_share(view)).step);
  EXPECT_TRUE(g.check(frame_level(up), kT0 + 5 * kPeriod, clipped_share(up)).step);
}

TEST(FrameChecksTest, ALastingChangeIsTheScenesOwn) {
  ExposureGuard g;
  int64_t t = kT0;
  for (int i = 0; i < 5; ++i, t += kPeriod) g.check(60.0, t);
  int refused = 0;
  for (int i = 0; i < 30; ++i, t += kPeriod) refused += g.check(200.0, t).step;
  // Refused for kMaxStepS, then taken as the new level for good.
  EXPECT_EQ(refused, static_cast<int>(ExposureGuard::kMaxStepS / (kPeriod * 1e-6)) + 1);
  EXPECT_NEAR(g.settled_level(), 200.0, 1e-6);
  EXPECT_FALSE(g.check(200.0, t).step);
  g.reset();
  EXPECT_EQ(g.settled_level(), 0.0);
}

TEST(FrameChecksTest, ABlackFrameIsAStepNotADivisionByZero) {
  ExposureGuard g;
  g.check(100.0, kT0);
  const ExposureCheck c = g.check(0.0, kT0 + kPeriod);
  EXPECT_TRUE(c.step);
  EXPECT_TRUE(std::isfinite(c.ev));
}

TEST(FrameChecksTest, TheReferenceIsScaledOnlyBeyondTheDeadBand) {
  EXPECT_EQ(gain_between(100.0, 120.0), 1.0);
  EXPECT_EQ(gain_between(100.0, 80.0), 1.0);
  EXPECT_DOUBLE_EQ(gain_between(100.0, 180.0), 1.8);
  EXPECT_DOUBLE_EQ(gain_between(100.0, 50.0), 0.5);
  EXPECT_EQ(gain_between(0.0, 50.0), 1.0);  // no level known
}

TEST(FrameChecksTest, EqualPixelsEqualHashesAnyChangeAnother) {
  cv::Mat a(480, 641, CV_8UC1);  // a row length that is not a multiple of 8
  cv::randu(a, 0, 256);
  const cv::Mat b = a.clone();
  EXPECT_EQ(pixel_hash(a), pixel_hash(b));
  cv::Mat c = a.clone();
  c.at<uint8_t>(479, 640) ^= 1;  // the last pixel, in the tail
  EXPECT_NE(pixel_hash(a), pixel_hash(c));
  cv::Mat d = a.clone();
  d.at<uint8_t>(0, 0) ^= 1;
  EXPECT_NE(pixel_hash(a), pixel_hash(d));
  // A view into a larger image hashes its own pixels only.
  cv::Mat big(500, 700, CV_8UC1, cv::Scalar(9));
  a.copyTo(big(cv::Rect(3, 5, 641, 480)));
  EXPECT_EQ(pixel_hash(big(cv::Rect(3, 5, 641, 480))), pixel_hash(a));
}

}  // namespace
}  // namespace alight::vision
