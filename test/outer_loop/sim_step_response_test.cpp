// Step responses of the position controller flying the simulator (issue 4 asks for them there,
// not only on the lag model): the gains of each vehicle file, the sim's rigid body with drag,
// inner attitude loop, motor lag, and its motion capture (sub-mm noise, ~10 ms latency) as the
// only feedback. The bounds are the ones documented in outer_loop/README.md:
//   lateral 1 m step:  overshoot <= 10 %, settling to 5 % (5 cm) within 3.0 s
//   vertical 1 m step: overshoot <= 10 %, settling to 5 % within 3.5 s
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "common/build_paths.hpp"
#include "outer_loop/params.hpp"
#include "outer_loop/position_controller.hpp"
#include "sim/params.hpp"
#include "sim/simulator.hpp"

namespace alight::outer_loop {
namespace {

struct SimStep {
  double overshoot_frac = 0;  // largest travel beyond the target along the step / step size
  double settling_s = 0;      // last time the true error exceeded 5 % of the step
  double final_error_m = 0;
};

SimStep fly_step(const std::string& vehicle, const Vector3d& p0, const Vector3d& p1) {
  const std::string root = alight::build::source_dir();
  const std::string vehicle_file = root + "/config/vehicles/" + vehicle + ".yaml";
  const auto scenario = sim::load_scenario(root + "/config/scenarios/landing_none.yaml");
  const auto vehicle_params = sim::load_vehicle_params(vehicle_file);
  sim::Simulator simulator(scenario, vehicle_params, /*seed=*/7);
  PositionController ctrl(load_params(vehicle_file));

  sim::VehicleState hover;
  hover.p_W_B = p0;
  hover.armed = true;
  hover.thrust_N = vehicle_params.hover_thrust_N();
  simulator.set_state(hover);

  PositionSetpoint sp;
  sp.p_W = p0;
  sp.motors_on = true;
  std::optional<PoseSample> pose;
  sim::AttitudeCommand cmd;
  cmd.armed = true;
  cmd.thrust_N = hover.thrust_N;
  const int64_t t0 = simulator.now_utime();
  const int64_t settle_us = 3'000'000, step_us = 10'000'000;
  const Vector3d dir = (p1 - p0).normalized();
  const double size = (p1 - p0).norm();
  SimStep r;
  for (int64_t t = t0 + 1000; t <= t0 + settle_us + step_us; t += 1000) {
    simulator.step(cmd, t);
    bool new_pose = false;
    for (const auto& m : simulator.take_mocap()) {
      pose = m.pose;
      new_pose = true;
    }
    if (t >= t0 + settle_us) sp.p_W = p1;
    if (new_pose) {  // the node computes one command per MOCAP_POSE, at the pose's time
      sp.utime = pose->utime;
      const AttitudeCommand c = ctrl.update(sp, pose, pose->utime);
      EXPECT_EQ(c.mode, Mode::kNormal) << mode_name(c.mode);
      cmd.roll_rad = c.roll_rad;
      cmd.pitch_rad = c.pitch_rad;
      cmd.yaw_rate_radps = c.yaw_rate_radps;
      cmd.thrust_N = c.thrust_N;
      cmd.armed = c.armed;
    }
    if (t < t0 + settle_us) continue;
    const Vector3d p = simulator.truth().state.p_W_B;
    r.overshoot_frac = std::max(r.overshoot_frac, ((p - p0).dot(dir) - size) / size);
    if ((p - p1).norm() > 0.05 * size)
      r.settling_s = 1e-6 * static_cast<double>(t - t0 - settle_us);
    r.final_error_m = (p - p1).norm();
  }
  return r;
}

class SimStepResponseTest : public ::testing::TestWithParam<const char*> {};

TEST_P(SimStepResponseTest, LateralAndVerticalStepsMeetTheDocumentedBounds) {
  const char* vehicle = GetParam();
  struct Case {
    const char* name;
    Vector3d p0, p1;
    double max_settling_s;
  };
  for (const Case& c :
       {Case{"lateral x", {0, 0, 1.5}, {1, 0, 1.5}, 3.0},
        Case{"lateral y", {0, 0, 1.5}, {0, -1, 1.5}, 3.0},
        Case{"up", {0, 0, 1.0}, {0, 0, 2.0}, 3.5}, Case{"down", {0, 0, 2.0}, {0, 0, 1.0}, 3.5}}) {
    const SimStep r = fly_step(vehicle, c.p0, c.p1);
    std::printf("%-8s %-9s overshoot %4.1f %%, settling %.2f s, final error %.1f mm\n", vehicle,
                c.name, 100 * r.overshoot_frac, r.settling_s, 1000 * r.final_error_m);
    EXPECT_LE(r.overshoot_frac, 0.10) << vehicle << " " << c.name;
    EXPECT_LE(r.settling_s, c.max_settling_s) << vehicle << " " << c.name;
    EXPECT_LT(r.final_error_m, 0.02) << vehicle << " " << c.name;
  }
}

INSTANTIATE_TEST_SUITE_P(Vehicles, SimStepResponseTest, ::testing::Values("starmac", "pelican"));

}  // namespace
}  // namespace alight::outer_loop
