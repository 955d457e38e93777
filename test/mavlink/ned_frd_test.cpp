// ENU/FLU <-> NED/FRD: known answers and round trips.

#include "mavlink/ned_frd.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace alight::mavlink {
namespace {

constexpr double kTol = 1e-12;

Quaterniond random_quat(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  return Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
}

Quaterniond yaw_quat(double yaw_rad) {
  return Quaterniond(Eigen::AngleAxisd(yaw_rad, Vector3d::UnitZ()));
}

// Same rotation (q and -q are one attitude).
void expect_same_rotation(const Quaterniond& a, const Quaterniond& b, double tol = 1e-9) {
  EXPECT_NEAR(std::abs(a.dot(b)), 1.0, tol)
      << a.coeffs().transpose() << " vs " << b.coeffs().transpose();
}

TEST(MavlinkNedFrd, PositionsKnownAnswers) {
  // 1 m east, 2 m north, 3 m up -> 2 m north, 1 m east, 3 m up (z down: -3).
  EXPECT_TRUE(ned_from_enu({1, 2, 3}).isApprox(Vector3d(2, 1, -3), kTol));
  EXPECT_TRUE(enu_from_ned({2, 1, -3}).isApprox(Vector3d(1, 2, 3), kTol));
}

TEST(MavlinkNedFrd, BodyRatesKnownAnswers) {
  // Roll rate about FLU x (forward) is roll rate about FRD x; pitch (FLU y left, nose down) is
  // minus FRD pitch (y right, nose up); yaw left (FLU z up) is minus FRD yaw (z down, yaw right).
  EXPECT_TRUE(frd_from_flu({0.1, 0, 0}).isApprox(Vector3d(0.1, 0, 0), kTol));
  EXPECT_TRUE(frd_from_flu({0, 0.2, 0}).isApprox(Vector3d(0, -0.2, 0), kTol));
  EXPECT_TRUE(frd_from_flu({0, 0, 0.3}).isApprox(Vector3d(0, 0, -0.3), kTol));
  EXPECT_TRUE(flu_from_frd({0.1, -0.2, -0.3}).isApprox(Vector3d(0.1, 0.2, 0.3), kTol));
}

TEST(MavlinkNedFrd, YawKnownAnswers) {
  // Nose north: yaw 90 deg in ENU is yaw 0 in NED; nose east: 0 in ENU is 90 deg in NED.
  EXPECT_NEAR(yaw_ned_from_enu(M_PI_2), 0.0, kTol);
  EXPECT_NEAR(yaw_ned_from_enu(0.0), M_PI_2, kTol);
  EXPECT_NEAR(yaw_ned_from_enu(M_PI), -M_PI_2, kTol);  // nose west
  EXPECT_NEAR(yaw_ned_from_enu(-M_PI_2), M_PI, kTol);  // nose south
  EXPECT_NEAR(yaw_enu_from_ned(0.0), M_PI_2, kTol);
}

TEST(MavlinkNedFrd, AttitudeKnownAnswers) {
  // Level, nose north (ENU yaw 90 deg) is the identity in NED/FRD.
  expect_same_rotation(q_ned_frd_from_enu_flu(yaw_quat(M_PI_2)), Quaterniond::Identity());
  // Level, nose east (ENU identity) is yaw 90 deg about NED z (down).
  expect_same_rotation(q_ned_frd_from_enu_flu(Quaterniond::Identity()), yaw_quat(M_PI_2));
  // Nose north, rolled 30 deg right wing down: +30 deg about x in FLU (y left goes up) and in
  // FRD (y right goes down).
  const Quaterniond roll_flu(Eigen::AngleAxisd(M_PI / 6, Vector3d::UnitX()));
  const Quaterniond roll_frd(Eigen::AngleAxisd(M_PI / 6, Vector3d::UnitX()));
  expect_same_rotation(q_ned_frd_from_enu_flu(yaw_quat(M_PI_2) * roll_flu), roll_frd);
  // Nose north, pitched 10 deg up: FLU pitch -10 deg about y (left), FRD +10 deg about y (right).
  const Quaterniond pitch_flu(Eigen::AngleAxisd(-M_PI / 18, Vector3d::UnitY()));
  const Quaterniond pitch_frd(Eigen::AngleAxisd(M_PI / 18, Vector3d::UnitY()));
  expect_same_rotation(q_ned_frd_from_enu_flu(yaw_quat(M_PI_2) * pitch_flu), pitch_frd);
}

TEST(MavlinkNedFrd, AttitudeMapsBodyAxesConsistently) {
  // For any attitude: the FRD body's x axis in NED is the FLU body's x axis in ENU, converted.
  std::mt19937_64 rng(3);
  for (int i = 0; i < 200; ++i) {
    const Quaterniond q = random_quat(rng);
    const Quaterniond q_ned = q_ned_frd_from_enu_flu(q);
    for (const Vector3d& v_FLU : {Vector3d(1, 0, 0), Vector3d(0, 1, 0), Vector3d(0.3, -0.2, 0.9)}) {
      const Vector3d in_enu = q * v_FLU;
      const Vector3d in_ned = q_ned * frd_from_flu(v_FLU);
      EXPECT_TRUE(in_ned.isApprox(ned_from_enu(in_enu), 1e-9));
    }
  }
}

TEST(MavlinkNedFrd, RoundTrips) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-100, 100), a(-M_PI, M_PI);
  for (int i = 0; i < 1000; ++i) {
    const Vector3d v(u(rng), u(rng), u(rng));
    EXPECT_TRUE(enu_from_ned(ned_from_enu(v)).isApprox(v, kTol));
    EXPECT_TRUE(flu_from_frd(frd_from_flu(v)).isApprox(v, kTol));
    const double yaw = a(rng);
    EXPECT_NEAR(wrap_angle(yaw_enu_from_ned(yaw_ned_from_enu(yaw)) - yaw), 0.0, 1e-12);
    const Quaterniond q = random_quat(rng);
    expect_same_rotation(q_enu_flu_from_ned_frd(q_ned_frd_from_enu_flu(q)), q);
    // The heading of the converted attitude is the converted heading.
    const double yaw_enu = yaw_of(q.toRotationMatrix());
    const Matrix3d R_ned = q_ned_frd_from_enu_flu(q).toRotationMatrix();
    if (std::abs(R_ned(2, 0)) < 0.99) {  // not pointing straight up or down
      EXPECT_NEAR(wrap_angle(std::atan2(R_ned(1, 0), R_ned(0, 0)) - yaw_ned_from_enu(yaw_enu)), 0.0,
                  1e-9);
    }
  }
}

TEST(MavlinkNedFrd, FloatQuaternionsAreCheckedBeforeUse) {
  const auto f = wxyz_float(Quaterniond(-0.5, 0.5, -0.5, 0.5));
  EXPECT_GE(f[0], 0.0f) << "w >= 0";
  EXPECT_EQ(f[1], -0.5f);
  const auto q = quat_from_wxyz_float({0.0f, 1.0f, 0.0f, 0.0f});
  ASSERT_TRUE(q.has_value());
  EXPECT_NEAR(q->x(), 1.0, 1e-7);
  EXPECT_FALSE(quat_from_wxyz_float({0, 0, 0, 0}).has_value()) << "an unset field";
  EXPECT_FALSE(quat_from_wxyz_float({std::numeric_limits<float>::quiet_NaN(), 0, 0, 1}));
  EXPECT_FALSE(quat_from_wxyz_float({2.0f, 0, 0, 0}).has_value());
  EXPECT_TRUE(quat_from_wxyz_float({1.05f, 0, 0, 0}).has_value()) << "float rounding tolerated";
}

}  // namespace
}  // namespace alight::mavlink
