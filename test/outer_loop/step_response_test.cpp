// Step responses of the position controller flying the lag model (test/outer_loop/lag_model.hpp:
// double integrator with drag, a 4 Hz / zeta 0.8 attitude loop and a 30 ms motor lag, like the
// simulator's default inner loop). The bounds we set and document (README of outer_loop):
//   lateral 1 m step:  overshoot <= 10 %, settling to 5 % (5 cm) within 3.0 s
//   vertical 1 m step: overshoot <= 10 %, settling to 5 % within 3.5 s
//   20 % mass mismatch: steady-state altitude error < 1 cm after 15 s (integrator)
// The same bounds hold at any heading (the lateral loop works in the heading frame).

#include <gtest/gtest.h>

#include <cmath>

#include "lag_model.hpp"
#include "outer_loop/position_controller.hpp"

namespace alight::outer_loop {
namespace {

constexpr int64_t kStepT0 = 1'700'000'000'000'000;
constexpr double kPhysicsDt = 0.001;
constexpr int kControlEvery = 10;  // 100 Hz pose / control rate

struct StepResult {
  double overshoot_frac = 0;  // largest travel beyond the target along the step / step size
  double settling_s = 0;      // last time the error exceeded 5 % of the step
  double final_error_m = 0;
  double max_tilt_rad = 0;
  Vector3d final_p = Vector3d::Zero();
};

OuterLoopParams default_params() {
  OuterLoopParams p;
  p.mass_kg = 1.2;
  return p;
}

StepResult fly_step(const OuterLoopParams& params, test::LagModel& model, const Vector3d& p0,
                    const Vector3d& p1, double yaw, double duration_s) {
  PositionController ctrl(params);
  model.hover_at(p0, yaw);
  PositionSetpoint sp;
  sp.p_W = p1;
  sp.yaw_rad = yaw;
  sp.motors_on = true;
  const Vector3d dir = (p1 - p0).normalized();
  const double size = (p1 - p0).norm();
  StepResult r;
  AttitudeCommand cmd;
  const int n = static_cast<int>(duration_s / kPhysicsDt);
  for (int i = 0; i < n; ++i) {
    const int64_t t = kStepT0 + static_cast<int64_t>(i * kPhysicsDt * 1e6);
    if (i % kControlEvery == 0) {
      sp.utime = t;
      cmd = ctrl.update(sp, model.pose(t), t);
      EXPECT_EQ(cmd.mode, Mode::kNormal);
    }
    model.step(cmd, kPhysicsDt);
    const double along = (model.p - p0).dot(dir);
    r.overshoot_frac = std::max(r.overshoot_frac, (along - size) / size);
    if ((model.p - p1).norm() > 0.05 * size) r.settling_s = (i + 1) * kPhysicsDt;
    r.max_tilt_rad = std::max(r.max_tilt_rad, std::hypot(model.roll, model.pitch));
  }
  r.final_p = model.p;
  r.final_error_m = (model.p - p1).norm();
  return r;
}

TEST(StepResponseTest, LateralStepMeetsSettlingAndOvershootBounds) {
  test::LagModel model;
  const auto r = fly_step(default_params(), model, {0, 0, 1}, {1, 0, 1}, 0.0, 10.0);
  EXPECT_LE(r.overshoot_frac, 0.10);
  EXPECT_LE(r.settling_s, 3.0);
  EXPECT_LT(r.final_error_m, 0.01);
  RecordProperty("lateral_overshoot_pct", std::to_string(100 * r.overshoot_frac));
  RecordProperty("lateral_settling_s", std::to_string(r.settling_s));
}

TEST(StepResponseTest, LateralStepIsTheSameAtAnyHeading) {
  for (double yaw : {M_PI / 2, -2.5, M_PI}) {
    test::LagModel model;
    const auto r = fly_step(default_params(), model, {0, 0, 1}, {0.3, -0.95, 1}, yaw, 10.0);
    EXPECT_LE(r.overshoot_frac, 0.10) << "yaw " << yaw;
    EXPECT_LE(r.settling_s, 3.0) << "yaw " << yaw;
    EXPECT_LT(r.final_error_m, 0.01) << "yaw " << yaw;
    EXPECT_NEAR(wrap_angle(model.yaw - yaw), 0.0, 0.01) << "yaw is held constant";
  }
}

TEST(StepResponseTest, VerticalStepMeetsSettlingAndOvershootBounds) {
  for (double dz : {1.0, -1.0}) {
    test::LagModel model;
    const auto r = fly_step(default_params(), model, {0, 0, 1.5}, {0, 0, 1.5 + dz}, 0.0, 10.0);
    EXPECT_LE(r.overshoot_frac, 0.10) << "dz " << dz;
    EXPECT_LE(r.settling_s, 3.5) << "dz " << dz;
    EXPECT_LT(r.final_error_m, 0.01) << "dz " << dz;
    RecordProperty(dz > 0 ? "up_overshoot_pct" : "down_overshoot_pct",
                   std::to_string(100 * r.overshoot_frac));
    RecordProperty(dz > 0 ? "up_settling_s" : "down_settling_s", std::to_string(r.settling_s));
  }
}

TEST(StepResponseTest, LargeStepRespectsTheTiltLimit) {
  test::LagModel model;
  auto params = default_params();
  const auto r = fly_step(params, model, {0, 0, 1}, {5, 5, 1}, 0.0, 15.0);
  // The attitude loop may overshoot the command a little; the command itself is clamped.
  EXPECT_LE(r.max_tilt_rad, params.max_tilt_deg * M_PI / 180 * 1.15);
  EXPECT_LT(r.final_error_m, 0.02);
}

TEST(StepResponseTest, IntegratorRemovesAltitudeErrorOfAWrongMass) {
  test::LagModel model;
  model.mass_kg = 1.2 * 1.2;  // 20 % heavier than the controller believes
  const auto r = fly_step(default_params(), model, {0, 0, 1}, {0, 0, 1}, 0.0, 15.0);
  EXPECT_LT(r.final_error_m, 0.01);
}

TEST(StepResponseTest, WithoutIntegratorAWrongMassLeavesAnOffset) {
  // The contrast that shows the integrator test above is meaningful.
  test::LagModel model;
  model.mass_kg = 1.2 * 1.2;
  auto params = default_params();
  params.ki_z_per_s3 = 0.0;
  params.ki_xy_per_s3 = 0.0;
  const auto r = fly_step(params, model, {0, 0, 1}, {0, 0, 1}, 0.0, 15.0);
  EXPECT_GT(r.final_error_m, 0.1);  // 0.2 g / kp_z = 0.33 m
}

TEST(StepResponseTest, AntiWindupBoundsTheOvershootAfterBeingHeld) {
  // Held on the ground for 10 s with the setpoint 1 m above, then released.
  auto params = default_params();
  PositionController ctrl(params);
  test::LagModel model;
  model.hover_at({0, 0, 0});
  PositionSetpoint sp;
  sp.p_W = {0, 0, 1.0};
  sp.motors_on = true;
  AttitudeCommand cmd;
  double max_z = 0;
  for (int i = 0; i < 25000; ++i) {
    const int64_t t = kStepT0 + i * 1000;
    const bool held = i < 10000;
    if (i % kControlEvery == 0) {
      sp.utime = t;
      cmd = ctrl.update(sp, model.pose(t), t);
      if (held) {
        EXPECT_LE(std::abs(ctrl.integral().z()), params.i_limit_z_mps2 + 1e-9);
      }
    }
    if (held) {
      model.p.setZero();
      model.v.setZero();
    } else {
      model.step(cmd, kPhysicsDt);
      max_z = std::max(max_z, model.p.z());
    }
  }
  EXPECT_LT(max_z, 1.0 + 0.5);  // bounded, not a runaway
  EXPECT_NEAR(model.p.z(), 1.0, 0.02);
}

}  // namespace
}  // namespace alight::outer_loop
