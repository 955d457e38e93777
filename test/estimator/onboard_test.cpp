// estimator::Onboard's own part (the gyro's rotation between two frames, the frame queue) and
// the message conversions; the filter and the front end have their own tests.
#include "estimator/onboard.hpp"

#include <gtest/gtest.h>

#include <alight/state_estimate_t.hpp>

#include "estimator/convert.hpp"

namespace alight::estimator {
namespace {

CameraModel camera() {
  CameraModel c;
  c.width = 640;
  c.height = 480;
  c.fx = c.fy = 500;
  c.cx = 319.5;
  c.cy = 239.5;
  return c;
}

// At rest for the alignment, then a constant yaw rate.
Onboard aligned(double yaw_rate_radps, int64_t* t_end) {
  Onboard o(EstimatorParams{}, camera());
  int64_t t = 1'000'000;
  for (int k = 0; k < 400; ++k, t += 5000) {
    ImuSample imu;
    imu.utime = t;
    imu.accel_B = Vector3d(0, 0, 9.80665);
    imu.gyro_B = Vector3d(0, 0, k < 300 ? 0.0 : yaw_rate_radps);
    o.add_imu(imu);
  }
  *t_end = t - 5000;
  return o;
}

TEST(OnboardTest, BodyRotationIntegratesTheGyroOverExactlyTheInterval) {
  int64_t t_end = 0;
  const Onboard o = aligned(0.5, &t_end);
  ASSERT_TRUE(o.state().initialised);
  // The last 100 samples turn at 0.5 rad/s: over 0.2 s (40 samples) 0.1 rad about z.
  const auto R = o.body_rotation(t_end - 200'000, t_end, Vector3d::Zero());
  ASSERT_TRUE(R);
  EXPECT_TRUE(R->isApprox(Eigen::AngleAxisd(0.1, Vector3d::UnitZ()).toRotationMatrix(), 1e-9));
  // Half a sample's interval counts half.
  const auto half = o.body_rotation(t_end - 2500, t_end, Vector3d::Zero());
  ASSERT_TRUE(half);
  EXPECT_TRUE(
      half->isApprox(Eigen::AngleAxisd(0.5 * 0.0025, Vector3d::UnitZ()).toRotationMatrix(), 1e-12));
  // The bias is taken off.
  const auto unbiased = o.body_rotation(t_end - 200'000, t_end, Vector3d(0, 0, 0.5));
  ASSERT_TRUE(unbiased);
  EXPECT_TRUE(unbiased->isApprox(Matrix3d::Identity(), 1e-12));
  // Refused samples never enter the history (regression: a NaN during the alignment did).
  Onboard fresh(EstimatorParams{}, camera());
  ImuSample bad;
  bad.utime = 1000;
  bad.gyro_B = Vector3d(NAN, 0, 0);
  EXPECT_EQ(fresh.add_imu(bad), Outcome::kNonFinite);
  ImuSample good;
  good.utime = 2000;
  good.accel_B = Vector3d(0, 0, 9.80665);
  fresh.add_imu(good);
  good.utime = 7000;
  fresh.add_imu(good);
  const auto rest = fresh.body_rotation(2000, 7000, Vector3d::Zero());
  ASSERT_TRUE(rest);
  EXPECT_TRUE(rest->allFinite());
  EXPECT_FALSE(fresh.body_rotation(1000, 7000, Vector3d::Zero()));
  // Not covered by the samples: none.
  EXPECT_FALSE(o.body_rotation(t_end - 100'000, t_end + 1, Vector3d::Zero()));
  EXPECT_FALSE(o.body_rotation(0, t_end, Vector3d::Zero()));
  EXPECT_FALSE(o.body_rotation(t_end, t_end - 1, Vector3d::Zero()));
}

TEST(OnboardTest, AFrameAheadOfTheImuWaitsAndAFullQueueDropsTheOldest) {
  int64_t t_end = 0;
  Onboard o = aligned(0.0, &t_end);
  const cv::Mat gray(480, 640, CV_8UC1, cv::Scalar(128));
  FrameOutcome first = o.add_frame(gray, t_end - 10'000);
  EXPECT_EQ(first.processed, 1);
  for (int k = 1; k <= 8; ++k) EXPECT_TRUE(o.add_frame(gray, t_end + k * 33'000).queued);
  EXPECT_TRUE(o.add_frame(gray, t_end + 9 * 33'000).dropped);
  EXPECT_EQ(o.frames_dropped(), 1);
  // The IMU catches up: the queued frames go through as it reaches them; a frame behind the
  // IMU then goes through at once.
  ImuSample imu;
  imu.accel_B = Vector3d(0, 0, 9.80665);
  for (int64_t t = t_end + 5000; t <= t_end + 400'000; t += 5000) {
    imu.utime = t;
    o.add_imu(imu);
  }
  EXPECT_EQ(o.add_frame(gray, t_end + 10 * 33'000).processed, 1);
  EXPECT_EQ(o.frames_dropped(), 1);
  EXPECT_NE(o.last_frame().flow, FlowReason::kNoPrevious);
}

TEST(EstimatorConvertTest, MessagesCarryTheStateAndTheSensorsVerdicts) {
  range_t r{};
  r.utime = 5;
  r.status = range_t::STATUS_NO_ECHO;
  r.distance_m = 3.0;
  EXPECT_FALSE(from_msg(r).valid);
  EXPECT_EQ(from_msg(r).range_m, 0.0);
  r.status = range_t::STATUS_OK;
  EXPECT_TRUE(from_msg(r).valid);
  EXPECT_EQ(from_msg(r).range_m, 3.0);

  State s;
  s.utime = 42;
  s.p_W_B = Vector3d(1, 2, 3);
  s.v_W_B = Vector3d(0.1, 0.2, 0.3);
  s.gyro_bias_B = Vector3d(0, 0, 0.01);
  s.cov.setIdentity();
  s.cov(0, 1) = 0.5;
  s.health = Health::kDegraded;
  s.health_reasons = kNoFlow;
  const state_estimate_t m = to_msg(s, Vector3d(0, 0, 0.11), 7);
  EXPECT_EQ(m.utime, 42);
  EXPECT_EQ(m.seq, 7);
  EXPECT_EQ(m.pos[2], 3.0);
  EXPECT_NEAR(m.angular_velocity_B[2], 0.10, 1e-12);
  EXPECT_EQ(m.cov_pva[1], 0.5);
  EXPECT_EQ(m.health, state_estimate_t::HEALTH_DEGRADED);
  EXPECT_EQ(m.health_reasons, state_estimate_t::REASON_NO_FLOW);
  const pose_t p = to_pose_msg(s, Vector3d::Zero(), 7);
  EXPECT_EQ(p.status, pose_t::STATUS_COASTING);
  s.health = Health::kOk;
  EXPECT_EQ(to_pose_msg(s, Vector3d::Zero(), 7).status, pose_t::STATUS_OK);
}

}  // namespace
}  // namespace alight::estimator
