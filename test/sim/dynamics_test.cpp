#include <gtest/gtest.h>

#include <cmath>

#include "sim/simulator.hpp"
#include "sim_test_util.hpp"

namespace alight::sim {
namespace {

using test::hover;
using test::place;

double energy(const VehicleParams& v, const VehicleState& s) {
  const Vector3d Jw = v.inertia_kgm2.cwiseProduct(s.omega_B);
  return 0.5 * v.mass_kg * s.v_W_B.squaredNorm() + v.mass_kg * 9.81 * s.p_W_B.z() +
         0.5 * s.omega_B.dot(Jw);
}

Vector3d rpy(const VehicleState& s) { return rpy_from_rotation(s.q_WB.toRotationMatrix()); }

class SimDynamicsTest : public ::testing::Test {
 protected:
  Scenario scenario_ = test::quiet(test::scenario("landing_none"));
  VehicleParams vehicle_ = test::starmac();
};

TEST_F(SimDynamicsTest, HoverThrustHoldsTheVehicleStill) {
  Simulator sim(scenario_, vehicle_, 1);
  place(sim, Vector3d(0, 0, 1.5));
  sim.step(hover(vehicle_), sim.now_utime() + 2000000);
  EXPECT_LT((sim.state().p_W_B - Vector3d(0, 0, 1.5)).norm(), 1e-3);
  EXPECT_LT(sim.state().v_W_B.norm(), 1e-3);
  EXPECT_LT(std::abs(rpy(sim.state()).x()) + std::abs(rpy(sim.state()).y()), 1e-4);
  // Noise-free specific force in hover: gravity's reaction along body z.
  EXPECT_NEAR(sim.specific_force_B().z(), 9.81, 1e-3);
}

TEST_F(SimDynamicsTest, RollAndPitchStepsSettleWithBoundedOvershootAndAccelerateTheRightWay) {
  for (int axis = 0; axis < 2; ++axis) {
    SCOPED_TRACE(axis == 0 ? "roll" : "pitch");
    Simulator sim(scenario_, vehicle_, 1);
    place(sim, Vector3d(0, 0, 2.0));
    AttitudeCommand cmd = hover(vehicle_);
    const double step = 0.2;
    (axis == 0 ? cmd.roll_rad : cmd.pitch_rad) = step;
    cmd.thrust_N = vehicle_.hover_thrust_N() / std::cos(step);
    double peak = 0, t90 = -1;
    for (int ms = 1; ms <= 1000; ++ms) {
      sim.step(cmd, sim.now_utime() + 1000);
      const double a = rpy(sim.state())[axis];
      peak = std::max(peak, a);
      if (t90 < 0 && a >= 0.9 * step) t90 = ms * 1e-3;
    }
    EXPECT_NEAR(rpy(sim.state())[axis], step, 0.02 * step);
    EXPECT_LT(peak, 1.15 * step);  // a damped inner loop
    EXPECT_GT(t90, 0.03);          // not instantaneous: finite bandwidth
    EXPECT_LT(t90, 0.3);           // but quick, like an autopilot's
    if (axis == 0) {
      EXPECT_LT(sim.state().v_W_B.y(), -0.5);  // right side down: to -y
    } else {
      EXPECT_GT(sim.state().v_W_B.x(), 0.5);  // nose down: to +x
    }
    EXPECT_NEAR(sim.state().p_W_B.z(), 2.0, 0.05);  // thrust compensates the tilt
  }
}

TEST_F(SimDynamicsTest, TiltCommandsSaturateAtTheVehicleLimit) {
  Simulator sim(scenario_, vehicle_, 1);
  place(sim, Vector3d(0, 0, 3.0));
  AttitudeCommand cmd = hover(vehicle_);
  cmd.roll_rad = 1.2;
  sim.step(cmd, sim.now_utime() + 800000);
  EXPECT_NEAR(rpy(sim.state()).x(), vehicle_.max_tilt_deg * M_PI / 180, 0.01);
}

TEST_F(SimDynamicsTest, YawRateIsTracked) {
  Simulator sim(scenario_, vehicle_, 1);
  place(sim, Vector3d(0, 0, 1.5));
  AttitudeCommand cmd = hover(vehicle_);
  cmd.yaw_rate_radps = 0.5;
  sim.step(cmd, sim.now_utime() + 1000000);
  const double yaw1 = rpy(sim.state()).z();
  sim.step(cmd, sim.now_utime() + 1000000);
  const double yaw2 = rpy(sim.state()).z();
  EXPECT_NEAR(wrap_angle(yaw2 - yaw1), 0.5, 0.02);
  EXPECT_NEAR((sim.state().q_WB.toRotationMatrix() * sim.state().omega_B).z(), 0.5, 0.02);
}

TEST_F(SimDynamicsTest, DisarmedMotorsGiveNoThrustAtOnce) {
  Simulator sim(scenario_, vehicle_, 1);
  place(sim, Vector3d(0, 0, 3.0));
  AttitudeCommand cmd = hover(vehicle_);
  cmd.armed = false;
  sim.step(cmd, sim.now_utime() + 200000);
  EXPECT_EQ(sim.state().thrust_N, 0.0);
  EXPECT_NEAR(sim.state().v_W_B.z(), -9.81 * 0.2, 0.08);  // free fall, a little drag
  EXPECT_LT(sim.specific_force_B().norm(), 0.6);          // an accelerometer in free fall
}

TEST_F(SimDynamicsTest, NoEnergyGainWithoutInput) {
  // Dropped, spinning and tilted, motors off: gravity, drag and contact may only take energy.
  Simulator sim(scenario_, vehicle_, 1);
  VehicleState s;
  s.p_W_B = Vector3d(0, 0, 0.6);
  s.q_WB = Quaterniond(rotation_from_rpy(0.2, -0.1, 0.5));
  s.v_W_B = Vector3d(0.5, 0.2, 0.0);
  s.omega_B = Vector3d(1.0, -0.5, 2.0);
  sim.set_state(s);
  AttitudeCommand off;
  const double e0 = energy(vehicle_, sim.state());
  double e_max = e0;
  for (int ms = 0; ms < 3000; ++ms) {
    sim.step(off, sim.now_utime() + 1000);
    e_max = std::max(e_max, energy(vehicle_, sim.state()));
  }
  // The contact springs store a little energy (compression); allow that and nothing more.
  const double spring_J =
      4 * 0.5 * vehicle_.contact_stiffness_Npm *
      std::pow(vehicle_.mass_kg * 9.81 / (4 * vehicle_.contact_stiffness_Npm), 2);
  EXPECT_LE(e_max, e0 + 1e-6 + spring_J);
  EXPECT_LT(sim.state().v_W_B.norm(), 0.01);  // came to rest on the floor
  EXPECT_LT(sim.state().omega_B.norm(), 0.05);
}

TEST_F(SimDynamicsTest, SteadyWindPushesAnUncontrolledHoverDownwind) {
  scenario_.wind.steady_mps = Vector3d(2.0, 0, 0);
  Simulator sim(scenario_, vehicle_, 1);
  place(sim, Vector3d(0, 0, 2.0));
  sim.step(hover(vehicle_), sim.now_utime() + 3000000);
  EXPECT_GT(sim.state().v_W_B.x(), 0.5);
  EXPECT_LT(sim.state().v_W_B.x(), 2.0 + 1e-6);  // never faster than the wind by drag alone
  EXPECT_NEAR(sim.truth().wind_W.x(), 2.0, 1e-12);
}

TEST_F(SimDynamicsTest, GustsHaveTheConfiguredSpread) {
  scenario_.wind.gust_sigma_mps = 0.5;
  scenario_.wind.gust_tau_s = 0.2;
  Simulator sim(scenario_, vehicle_, 3);
  place(sim, Vector3d(0, 0, 2.0));
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int i = 0; i < 600; ++i) {  // 60 s, 300 correlation times
    sim.step(hover(vehicle_), sim.now_utime() + 100000);
    const double w = sim.truth().wind_W.x();
    sum += w;
    sum2 += w * w;
    ++n;
    place(sim, Vector3d(0, 0, 2.0));  // keep it in the air
  }
  const double sd = std::sqrt(sum2 / n - (sum / n) * (sum / n));
  EXPECT_NEAR(sd, 0.5, 0.1);
}

TEST_F(SimDynamicsTest, SameSeedAndCommandsGiveIdenticalRuns) {
  scenario_.wind.gust_sigma_mps = 0.3;
  auto run = [&](uint64_t seed) {
    Simulator sim(scenario_, vehicle_, seed);
    place(sim, Vector3d(0, 0, 1.0));
    std::vector<double> out;
    for (int i = 0; i < 300; ++i) {
      AttitudeCommand cmd = hover(vehicle_);
      cmd.roll_rad = 0.1 * std::sin(i * 0.05);
      cmd.yaw_rate_radps = 0.2;
      sim.step(cmd, sim.now_utime() + 3333);
      for (const auto& m : sim.take_mocap()) out.push_back(m.pose.p_W_B.x());
      for (const auto& m : sim.take_imu()) out.push_back(m.accel_B.y());
    }
    for (int k = 0; k < 3; ++k) out.push_back(sim.state().p_W_B[k]);
    return out;
  };
  const auto a = run(7), b = run(7), c = run(8);
  ASSERT_GT(a.size(), 250u);
  EXPECT_EQ(a, b);  // bit for bit
  EXPECT_NE(a, c);
}

}  // namespace
}  // namespace alight::sim
