#include "common/geometry.hpp"

#include <gtest/gtest.h>

#include <random>

namespace alight {
namespace {

TEST(GeometryTest, RpyRoundTripIsExactOverTheRange) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> a(-M_PI, M_PI), p(-1.5, 1.5);
  for (int i = 0; i < 1000; ++i) {
    const Vector3d rpy(a(rng), p(rng), a(rng));
    const Matrix3d R = rotation_from_rpy(rpy[0], rpy[1], rpy[2]);
    ASSERT_TRUE(is_rotation(R, 1e-12));
    EXPECT_NEAR(std::abs(R.determinant() - 1.0), 0.0, 1e-12);
    const Vector3d back = rpy_from_rotation(R);
    EXPECT_TRUE(rotation_from_rpy(back[0], back[1], back[2]).isApprox(R, 1e-12));
    EXPECT_NEAR(yaw_of(R), rpy[2], 1e-9);
  }
}

TEST(GeometryTest, QuaternionWxyzRoundTrip) {
  const Quaterniond q(Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()));
  double wxyz[4];
  quat_to_wxyz(q, wxyz);
  EXPECT_DOUBLE_EQ(wxyz[0], q.w());
  EXPECT_TRUE(quat_from_wxyz(wxyz).isApprox(q));
  // -q is the same rotation; the canonical form has w >= 0.
  quat_to_wxyz(Quaterniond(-q.coeffs()), wxyz);
  EXPECT_GE(wxyz[0], 0.0);
}

TEST(GeometryTest, StandardMountsAreRotationsWithTheDocumentedAxes) {
  const Matrix3d down = R_BC_downward();
  const Matrix3d fwd = R_BC_forward();
  EXPECT_TRUE(is_rotation(down));
  EXPECT_TRUE(is_rotation(fwd));
  // Downward camera looks along -z_B, image up is the nose.
  EXPECT_TRUE((down * Vector3d::UnitZ()).isApprox(-Vector3d::UnitZ()));
  EXPECT_TRUE((down * -Vector3d::UnitY()).isApprox(Vector3d::UnitX()));
  // Forward camera looks along x_B, image down is -z_B.
  EXPECT_TRUE((fwd * Vector3d::UnitZ()).isApprox(Vector3d::UnitX()));
  EXPECT_TRUE((fwd * Vector3d::UnitY()).isApprox(-Vector3d::UnitZ()));
}

TEST(GeometryTest, NearestRotationProjectsNoisyMatrices) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0, 0.01);
  const Matrix3d R = rotation_from_rpy(0.1, -0.3, 2.0);
  Matrix3d M = R;
  for (int i = 0; i < 9; ++i) M.data()[i] += n(rng);
  const Matrix3d P = nearest_rotation(M);
  EXPECT_TRUE(is_rotation(P, 1e-12));
  EXPECT_LT((P - R).norm(), 0.05);
}

TEST(GeometryTest, WrapAngle) {
  EXPECT_NEAR(wrap_angle(3 * M_PI), M_PI, 1e-12);
  EXPECT_NEAR(wrap_angle(-3 * M_PI), M_PI, 1e-12);
  EXPECT_NEAR(wrap_angle(0.5), 0.5, 1e-15);
  EXPECT_NEAR(wrap_angle(2 * M_PI + 0.1), 0.1, 1e-12);
}

TEST(GeometryTest, WrapAxisAngleTakesALineToTheHalfTurnAboutZero) {
  EXPECT_EQ(wrap_axis_angle(M_PI / 2), M_PI / 2);
  EXPECT_NEAR(wrap_axis_angle(-M_PI / 2), M_PI / 2, 1e-15);
  EXPECT_NEAR(wrap_axis_angle(0.75 * M_PI), -0.25 * M_PI, 1e-12);
  EXPECT_NEAR(wrap_axis_angle(-0.75 * M_PI), 0.25 * M_PI, 1e-12);
  EXPECT_NEAR(wrap_axis_angle(2 * M_PI + 0.3), 0.3, 1e-12);
}

TEST(GeometryTest, RayAtHeightOnlyInFrontOfItsOrigin) {
  const Vector3d c(1, 2, 1.5);
  const auto p = ray_at_height(c, Vector3d(0.1, 0.2, -1), 0.5);
  ASSERT_TRUE(p.has_value());
  EXPECT_LT((*p - Vector3d(1.1, 2.2, 0.5)).norm(), 1e-12);
  EXPECT_FALSE(ray_at_height(c, Vector3d(0.1, 0.2, 1), 0.5));  // pointing away
  EXPECT_FALSE(ray_at_height(c, Vector3d(1, 0, 0), 0.5));      // parallel
}

TEST(GeometryTest, CameraInWorldComposesBodyAndMount) {
  const Isometry3d X_WB = make_transform(rotation_from_rpy(0, 0, M_PI / 2), Vector3d(1, 2, 3));
  const Isometry3d X_BC = make_transform(R_BC_downward(), Vector3d(0.1, 0, -0.05));
  const Isometry3d X_WC = camera_in_world(X_WB, X_BC);
  // Camera centre: body at (1,2,3) yawed 90 deg, offset 0.1 forward -> +y in world.
  EXPECT_TRUE(X_WC.translation().isApprox(Vector3d(1, 2.1, 2.95)));
  EXPECT_TRUE((X_WC.linear() * Vector3d::UnitZ()).isApprox(-Vector3d::UnitZ()));
}

}  // namespace
}  // namespace alight
