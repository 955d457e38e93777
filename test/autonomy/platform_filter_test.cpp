// The platform filter against analytic motion (a straight drift, a turn at constant speed, a
// heave), the gate, and the descent's timing against a known heave.
#include "autonomy/platform_filter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "autonomy/moving_landing.hpp"

namespace alight::autonomy {
namespace {

constexpr int64_t kPfT0 = 1'700'000'000'000'000;
constexpr double kPfDt = 1.0 / 30;    // the camera's rate
constexpr double kPfInterval = 0.25;  // vision's interval between its two frames

// Truth: a circle of radius r at speed v (centre at the origin), yaw turning at omega, heave A
// sin(2 pi f t).
struct PlatformPath {
  double r = 0.6, v = 0.8, omega = 0.1, A = 0.0, f = 0.3, psi0 = 0.3;
  bool straight = false;
  Vector2d p(double t) const {
    if (straight) return Vector2d(v * t, 0.2);
    const double a = v * t / r;
    return r * Vector2d(std::cos(a), std::sin(a));
  }
  Vector2d vel(double t) const {
    if (straight) return Vector2d(v, 0);
    const double a = v * t / r;
    return v * Vector2d(-std::sin(a), std::cos(a));
  }
  double z(double t) const { return 0.15 + A * std::sin(2 * M_PI * f * t); }
  double yaw(double t) const { return psi0 + omega * t; }
};

// Vision's measurement at t: the mean velocity over [t - interval, t], with noise.
PlatformMeasurement measure_path(const PlatformPath& m, double t, std::mt19937_64& rng,
                                 double sp = 0.01, double sv = 0.05) {
  std::normal_distribution<double> n(0, 1);
  PlatformMeasurement z;
  z.utime = kPfT0 + int64_t(t * 1e6);
  z.ref_utime = kPfT0 + int64_t((t - kPfInterval) * 1e6);
  const Vector2d dp = (m.p(t) - m.p(t - kPfInterval)) / kPfInterval;
  z.p_W << m.p(t) + sp * Vector2d(n(rng), n(rng)), m.z(t);
  z.v_W << dp + sv * Vector2d(n(rng), n(rng)),
      (m.z(t) - m.z(t - kPfInterval)) / kPfInterval + 0.01 * n(rng);
  z.cov_p_W = sp * sp * Matrix3d::Identity();
  z.cov_v_W = sv * sv * Matrix3d::Identity();
  z.yaw_rad = m.yaw(t) + 0.01 * n(rng);
  z.yaw_rate_rps = m.omega + 0.05 * n(rng);
  z.var_yaw = 1e-4;
  z.var_yaw_rate = 0.05 * 0.05;
  return z;
}

TEST(PlatformFilterTest, TracksAStraightDriftToItsVelocity) {
  PlatformPath m;
  m.straight = true;
  PlatformFilter f{PlatformFilterParams{}};
  std::mt19937_64 rng(1);
  double t = kPfInterval;
  for (; t < 4; t += kPfDt) EXPECT_TRUE(f.update(measure_path(m, t, rng)));
  // Predicted 0.1 s past the last measurement (vision's latency).
  const auto p = f.predict(kPfT0 + int64_t((t - kPfDt + 0.1) * 1e6));
  EXPECT_NEAR(p.v_W.x(), m.v, 0.05);
  EXPECT_NEAR(p.v_W.y(), 0.0, 0.05);
  EXPECT_LT((p.p_W - m.p(t - kPfDt + 0.1)).norm(), 0.015);
  EXPECT_NEAR(p.yaw_rate_rps, m.omega, 0.03);
  // The axes' direction, mod a quarter turn.
  EXPECT_NEAR(std::remainder(p.yaw_rad - m.yaw(t - kPfDt + 0.1), M_PI / 2), 0.0, 0.02);
  EXPECT_EQ(f.n_rejected(), 0);
}

TEST(PlatformFilterTest, FollowsATurnWithinTheLagOfItsModel) {
  // 0.8 m/s round a 0.6 m circle: 1.07 m/s^2 of centripetal acceleration, the model's white
  // noise. Over the second lap the position error stays within a few centimetres.
  PlatformPath m;
  PlatformFilter f{PlatformFilterParams{}};
  std::mt19937_64 rng(2);
  double worst = 0;
  for (double t = kPfInterval; t < 10; t += kPfDt) {
    f.update(measure_path(m, t, rng));
    if (t > 5) worst = std::max(worst, (f.predict(kPfT0 + int64_t(t * 1e6)).p_W - m.p(t)).norm());
  }
  EXPECT_LT(worst, 0.05);
}

TEST(PlatformFilterTest, RefusesAFarMeasurementAndStartsOverFromTheLastOfManyInARow) {
  PlatformPath m;
  m.straight = true;
  PlatformFilterParams params;
  PlatformFilter f{params};
  std::mt19937_64 rng(3);
  double t = kPfInterval;
  for (; t < 2; t += kPfDt) f.update(measure_path(m, t, rng));
  auto far = measure_path(m, t, rng);
  far.p_W.x() += 1.0;
  EXPECT_FALSE(f.update(far));
  EXPECT_EQ(f.n_rejected(), 1);
  // Out of order: refused.
  auto old = measure_path(m, t - 1, rng);
  EXPECT_FALSE(f.update(old));
  for (int k = 1; k < params.max_consecutive_rejections; ++k) {
    t += kPfDt;
    far = measure_path(m, t, rng);
    far.p_W.x() += 1.0;
    f.update(far);
  }
  // The last of them started the filter over from itself.
  EXPECT_TRUE(f.initialised());
  EXPECT_NEAR(f.predict(far.utime).p_W.x(), far.p_W.x(), 1e-9);
}

TEST(PlatformFilterTest, FitsAKnownHeave) {
  PlatformPath m;
  m.straight = true;
  m.A = 0.05, m.f = 0.35;
  PlatformFilter f{PlatformFilterParams{}};
  std::mt19937_64 rng(4);
  double t = kPfInterval;
  for (; t < 8; t += kPfDt) f.update(measure_path(m, t, rng));
  const HeaveModel& h = f.heave();
  ASSERT_GT(h.w_rps, 0);
  EXPECT_NEAR(h.w_rps / (2 * M_PI), m.f, 0.02);
  // Vision's velocities are means over 0.25 s: the amplitude shrinks by sinc(f T) ~ 0.98.
  EXPECT_NEAR(h.amplitude_m(), m.A, 0.006);
  // The predicted vertical speed one second ahead.
  const int64_t ahead = kPfT0 + int64_t((t + 1.0) * 1e6);
  const double vz_true = 2 * M_PI * m.f * m.A * std::cos(2 * M_PI * m.f * (t + 1.0));
  EXPECT_NEAR(h.vz(ahead), vz_true, 0.03);
}

TEST(HeaveReleaseTest, TheLastDropStartsSoThatContactFollowsACrest) {
  // Heave z = A sin(w t): crests at w t = pi/2 + 2 pi k. The release must put the contact
  // (fall_s after it) in the quarter period after a crest, and one comes within a period.
  HeaveModel h;
  const double A = 0.05, f = 0.3, w = 2 * M_PI * f;
  h.w_rps = w;
  h.t0_utime = kPfT0;
  h.a = 0, h.b = A * w;  // vz = A w cos(w t)
  MovingLandingParams params;
  const double fall_s = 0.4;
  std::optional<double> released;
  for (double t = 0; t < 1.0 / f && !released; t += 0.01) {
    const auto r = heave_release(h, kPfT0 + int64_t(t * 1e6), fall_s, t, params);
    ASSERT_NE(r, Release::kNoHeave);
    if (r != Release::kWait) released = t;
  }
  ASSERT_TRUE(released);
  const double phase = std::fmod(w * (*released + fall_s), 2 * M_PI);
  EXPECT_GE(phase, M_PI / 2 - 0.05);
  EXPECT_LE(phase, M_PI + 0.05);
  // The deck's height at contact is in its upper half, its velocity not upwards.
  const double t_c = *released + fall_s;
  EXPECT_GE(A * std::sin(w * t_c), -1e-3);
  EXPECT_LE(A * w * std::cos(w * t_c), 1e-3);
  // A still deck: at once; a deck whose crest never comes in time: after heave_max_wait_s.
  EXPECT_EQ(heave_release(HeaveModel{}, kPfT0, fall_s, 0, params), Release::kNoHeave);
  const int64_t rising = kPfT0;  // w t = 0: rising through the mean, contact still rising
  EXPECT_EQ(heave_release(h, rising, 0.0, params.heave_max_wait_s, params), Release::kWaitedEnough);
}

TEST(MovingApproachTest, MatchesThePlatformThenDescendsAndFailsSafeWhenTooFast) {
  PlatformPath m;
  m.straight = true;
  m.v = 0.5;
  PlatformFilter f{PlatformFilterParams{}};
  std::mt19937_64 rng(5);
  double t = kPfInterval;
  for (; t < 2; t += kPfDt) f.update(measure_path(m, t, rng));
  MovingLandingParams params;
  MovingApproach s;
  PoseSample pose;
  pose.p_W_B << m.p(t).x() + 0.3, m.p(t).y(), 1.2;
  const int64_t now = kPfT0 + int64_t(t * 1e6);
  auto st = step_moving_approach(s, f, pose, now, 0.01, 0.0, 0.1, 0.25, 1.0, params);
  EXPECT_EQ(st.next, MovingStep::Next::kContinue);
  // Over the predicted centre, the platform's velocity fed forward, no descent while unmatched.
  EXPECT_NEAR(st.sp_p_W.x(), m.p(t).x(), 0.03);
  EXPECT_NEAR(st.sp_v_W.x(), m.v, 0.05);
  EXPECT_EQ(st.sp_v_W.z(), 0.0);
  const double z0 = st.sp_p_W.z();
  // Matched (on the platform's centre at its velocity) for match_settle_s: descending.
  pose.p_W_B.head<2>() = st.sp_p_W.head<2>();
  pose.v_W_B << st.sp_v_W.head<2>(), 0;
  for (int k = 0; k <= 60; ++k) {
    pose.p_W_B.head<2>() = f.predict(now + k * 10000).p_W;
    st = step_moving_approach(s, f, pose, now + k * 10000, 0.01, 0.0, 0.1, 0.25, 1.0, params);
  }
  EXPECT_LT(st.sp_p_W.z(), z0);
  EXPECT_LT(st.sp_v_W.z(), 0.0);
  // The same platform beyond max_speed_mps for too_fast_s: the failsafe.
  params.max_speed_mps = 0.4;
  MovingApproach s2;
  st = step_moving_approach(s2, f, pose, now, 0.01, 0.0, 0.1, 0.25, 1.0, params);
  EXPECT_EQ(st.next, MovingStep::Next::kContinue);
  st = step_moving_approach(s2, f, pose, now + int64_t(params.too_fast_s * 1e6), 0.01, 0.0, 0.1,
                            0.25, 1.0, params);
  EXPECT_EQ(st.next, MovingStep::Next::kTooFast);
  // Not measured for lost_timeout_s: lost.
  MovingApproach s3;
  st = step_moving_approach(s3, f, pose, now + int64_t((params.lost_timeout_s + 0.1) * 1e6), 0.01,
                            0.0, 0.1, 0.25, 1.0, MovingLandingParams{});
  EXPECT_EQ(st.next, MovingStep::Next::kTargetLost);
}

TEST(MovingApproachTest, AlignsTheHeadingWithThePlatformsAxesTheNearestWay) {
  EXPECT_NEAR(aligned_yaw(0.2, 0.0), 0.2, 1e-12);
  EXPECT_NEAR(aligned_yaw(0.2, 1.5), 0.2 + M_PI / 2, 1e-12);
  EXPECT_NEAR(aligned_yaw(-1.4, 0.1), -1.4 + M_PI / 2, 1e-12);
}

}  // namespace
}  // namespace alight::autonomy
