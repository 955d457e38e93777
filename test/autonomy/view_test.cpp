// The vantages' view of a top too big for it (mission_profile.hpp, view_to_fit): the height and
// turn from which a top cut by the view's border fits it, the vantages kept inside the room it
// leaves, and the autonomy flying them on cut views only.

#include <gtest/gtest.h>

#include <cmath>

#include "autonomy/autonomy.hpp"
#include "autonomy/mission_profile.hpp"
#include "kinematic_world.hpp"

namespace alight::autonomy {
namespace {

// The paper's camera (640 x 480, f = 666.7 px) looking down, image right = vehicle right.
DownwardView firefly_down() {
  return downward_view(CameraModel::firefly_mv_4mm(), R_BC_downward());
}

TEST(DownwardViewTest, TheUsableHalfAnglesLeaveTheVisionsBorderAndTheLongAxisIsTheImagesWidth) {
  const DownwardView v = firefly_down();
  EXPECT_NEAR(v.tan_long, (320.0 - kViewBorderPx) / 666.667, 1e-6);
  EXPECT_NEAR(v.tan_short, (240.0 - kViewBorderPx) / 666.667, 1e-6);
  // Image right (x_C) is the body's -y: the long axis lies across the vehicle.
  EXPECT_NEAR(std::abs(std::sin(v.long_axis_yaw_B_rad)), 1.0, 1e-9);
  // A camera turned a quarter about its axis: the long axis along the body's x.
  const Matrix3d turned =
      R_BC_downward() * Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_NEAR(
      std::abs(std::cos(downward_view(CameraModel::firefly_mv_4mm(), turned).long_axis_yaw_B_rad)),
      1.0, 1e-9);
}

TEST(ViewToFitTest, ATopAlongTheImagesLongAxisFitsFromNearerThanOneAcrossIt) {
  const DownwardView v = firefly_down();
  const Vector2d size(1.2, 0.5);
  const double along = range_to_fit(v, size, 0.3, 0.3, 0.0);
  const double across = range_to_fit(v, size, 0.3 + M_PI / 2, 0.3, 0.0);
  EXPECT_NEAR(along, std::max(0.6 / v.tan_long, 0.25 / v.tan_short), 1e-12);
  EXPECT_NEAR(across, std::max(0.25 / v.tan_long, 0.6 / v.tan_short), 1e-12);
  EXPECT_LT(along, across);
  // The pad widens the top on every side.
  EXPECT_NEAR(range_to_fit(v, size, 0.3, 0.3, 0.1), std::max(0.7 / v.tan_long, 0.35 / v.tan_short),
              1e-12);
}

TEST(ViewToFitTest, ACutPartThatFitsAsTheBodyIsTurnedMovesNothing) {
  const DownwardView v = firefly_down();
  // A 30 x 20 cm part of a top 20 cm high seen from 1.6 m: it fits whichever way it lies.
  EXPECT_FALSE(view_to_fit(v, Vector2d(0.3, 0.2), 0.7, 0.2, 0.0, 1.6, 2.2));
  EXPECT_FALSE(view_to_fit(v, Vector2d(NAN, 0.2), 0.7, 0.2, 0.0, 1.6, 2.2));
  EXPECT_FALSE(view_to_fit(DownwardView{}, Vector2d(1.3, 0.6), 0.7, 0.2, 0.0, 1.6, 2.2));
}

TEST(ViewToFitTest, ATopLongerThanTheViewTurnsItAlongTheImageAndClimbsToFitWithinTheCeiling) {
  const DownwardView v = firefly_down();
  const double top_yaw = -0.9;
  const Vector2d size(1.3, 0.6);
  const auto fit = view_to_fit(v, size, top_yaw, 0.1, 0.0, 1.6, 2.5);
  ASSERT_TRUE(fit);
  // The image's long axis along the top's, the nearer of the two turns.
  EXPECT_NEAR(std::abs(std::cos(fit->yaw_rad + v.long_axis_yaw_B_rad - top_yaw)), 1.0, 1e-9);
  EXPECT_LE(std::abs(wrap_angle(fit->yaw_rad)), M_PI / 2);
  EXPECT_NEAR(fit->z_m, 0.1 + range_to_fit(v, size, top_yaw, top_yaw, kViewPadM), 1e-9);
  EXPECT_GT(fit->z_m, 1.6);
  // The room left around the top is the pad (the long side decides the range).
  EXPECT_NEAR(fit->slack_m.x(), kViewPadM, 1e-9);
  EXPECT_GT(fit->slack_m.y(), kViewPadM);
  // Under a low ceiling it climbs to the ceiling, with the room there (none along the long axis
  // when even the ceiling does not fit it).
  const auto low = view_to_fit(v, Vector2d(1.4, 0.6), top_yaw, 0.1, 0.0, 1.6, 1.7);
  ASSERT_TRUE(low);
  EXPECT_DOUBLE_EQ(low->z_m, 1.7);
  EXPECT_DOUBLE_EQ(low->slack_m.x(), 0.0);
}

TEST(ViewToFitTest, AVantageStraysFromTheTopsCentreByHalfTheRoomAtMost) {
  ViewToFit fit;
  fit.z_m = 2.0;
  fit.top_yaw_rad = M_PI / 2;  // the top's long axis along world y
  fit.slack_m = Vector2d(0.2, 0.1);
  const Vector3d mu(1.0, 0.5, 0.1);
  const Vector3d p = vantage_in_view(fit, mu, Vector3d(1.3, 0.9, 1.6));
  EXPECT_NEAR(p.x(), 1.0 + 0.05, 1e-12);  // across the top: half of 0.1
  EXPECT_NEAR(p.y(), 0.5 + 0.1, 1e-12);   // along it: half of 0.2
  EXPECT_DOUBLE_EQ(p.z(), 2.0);
  const Vector3d near = vantage_in_view(fit, mu, Vector3d(1.02, 0.45, 1.6));
  EXPECT_NEAR(near.x(), 1.02, 1e-12);
  EXPECT_NEAR(near.y(), 0.45, 1e-12);
}

// Refinement on a top that every view cuts: the vantages climb and turn to fit it; on a top the
// views cut only at the search path's edge, they stay where they were.
TEST(ViewToFitTest, CutViewsOfATopTooBigForTheViewRaiseAndTurnTheVantages) {
  for (const bool big : {false, true}) {
    AutonomyParams params = test::test_params();
    params.downward_view = firefly_down();
    test::KinematicWorld w(params);
    const double top_yaw = 0.6;
    w.corrupt_target = [&](TargetMeasurement& m) {
      m.found = false;
      m.partial = m.cut = true;
      m.size_m = big ? Vector2d(1.3, 0.6) : Vector2d(0.3, 0.2);
      m.yaw_rad = top_yaw;
    };
    w.takeoff_and_hover();
    w.send(Command::kGo, Mission::kLanding);
    ASSERT_TRUE(w.run_until_phase(Phase::kRefinement, 60));
    ASSERT_EQ(w.run_until([&] { return w.p.z() > 1.9; }, big ? 15 : 8), big);
    const double vantage_z = w.autonomy.current_vantage().z();
    if (!big) {
      EXPECT_NEAR(vantage_z, params.detection.landing_height_m, 1e-9);
      continue;
    }
    const DownwardView v = *params.downward_view;
    EXPECT_NEAR(std::abs(std::cos(w.out.setpoint.yaw_rad + v.long_axis_yaw_B_rad - top_yaw)), 1.0,
                1e-6);
    EXPECT_GT(vantage_z, params.detection.landing_height_m + 0.3);
    EXPECT_LE(vantage_z, params.geofence.max_W_m.z());
  }
}

// One cut view in five measuring the top at four times its size (a seam taken for a rim) moves
// no vantage; the same size in most of the latest views raises them.
TEST(ViewToFitTest, ALoneOversizedCutViewRaisesNoVantage) {
  for (const int every : {5, 1}) {
    AutonomyParams params = test::test_params();
    params.downward_view = firefly_down();
    test::KinematicWorld w(params);
    int n = 0;
    w.corrupt_target = [&](TargetMeasurement& m) {
      m.found = false;
      m.partial = m.cut = true;
      m.size_m = ++n % every == 0 ? Vector2d(1.3, 0.6) : Vector2d(0.3, 0.2);
      m.yaw_rad = 0.6;
    };
    w.takeoff_and_hover();
    w.send(Command::kGo, Mission::kLanding);
    ASSERT_TRUE(w.run_until_phase(Phase::kRefinement, 60));
    const bool climbed = w.run_until([&] { return w.p.z() > 1.9; }, 15);
    EXPECT_EQ(climbed, every == 1) << "every " << every;
    if (every != 1) {
      EXPECT_GE(n, 50);  // the oversized views kept coming
      EXPECT_NEAR(w.autonomy.current_vantage().z(), params.detection.landing_height_m, 1e-9);
    }
  }
}

}  // namespace
}  // namespace alight::autonomy
