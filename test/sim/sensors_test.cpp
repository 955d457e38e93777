#include <gtest/gtest.h>

#include <cmath>

#include "common/msg_convert.hpp"
#include "sim/sim_msgs.hpp"
#include "sim/simulator.hpp"
#include "sim_test_util.hpp"

namespace alight::sim {
namespace {

using test::hover;
using test::place;

struct Stats {
  double n = 0, sum = 0, sum2 = 0;
  void add(double x) {
    ++n;
    sum += x;
    sum2 += x * x;
  }
  double mean() const { return sum / n; }
  double sd() const { return std::sqrt(std::max(0.0, sum2 / n - mean() * mean())); }
};

class SimSensorsTest : public ::testing::Test {
 protected:
  Scenario scenario_ = test::quiet(test::scenario("landing_none"));
  VehicleParams vehicle_ = test::starmac();
};

TEST_F(SimSensorsTest, MocapNoiseRateAndLatencyAreAsConfigured) {
  scenario_.mocap.pos_sigma_m = 0.0005;
  scenario_.mocap.rot_sigma_rad = 0.002;
  scenario_.mocap.latency_s = 0.012;
  Simulator sim(scenario_, vehicle_, 5);  // resting on the floor: the true pose is constant
  sim.step(AttitudeCommand{}, sim.now_utime() + 500000);
  sim.take_mocap();
  const Vector3d p_true = sim.state().p_W_B;
  const Quaterniond q_true = sim.state().q_WB;
  Stats pos, rot;
  int64_t last_seq = -1, n = 0;
  for (int ms = 0; ms < 10000; ++ms) {
    sim.advance_to(sim.now_utime() + 1000);
    for (const auto& m : sim.take_mocap()) {
      const int64_t age = sim.now_utime() - m.pose.utime;
      EXPECT_GE(age, 12000);  // never before its latency
      EXPECT_LT(age, 13000);  // and delivered as soon as it has passed
      if (last_seq >= 0) {
        EXPECT_EQ(m.seq, last_seq + 1);
      }
      last_seq = m.seq;
      ++n;
      for (int k = 0; k < 3; ++k) pos.add(m.pose.p_W_B[k] - p_true[k]);
      const Eigen::AngleAxisd d(q_true.inverse() * m.pose.q_WB);
      for (int k = 0; k < 3; ++k) rot.add(d.angle() * d.axis()[k]);
    }
  }
  EXPECT_NEAR(n, 1000, 1);  // 100 Hz
  EXPECT_NEAR(pos.mean(), 0.0, 0.00005);
  EXPECT_NEAR(pos.sd(), 0.0005, 0.00005);
  EXPECT_NEAR(rot.sd(), 0.002, 0.0002);
}

TEST_F(SimSensorsTest, AnInjectedDropoutDeliversNothingAndLeavesASequenceGap) {
  Simulator sim(scenario_, vehicle_, 5);
  const int64_t t0 = sim.now_utime() + 300000, t1 = t0 + 250000;
  sim.inject_mocap_dropout(t0, t1);
  std::vector<MocapSample> all;
  for (int i = 0; i < 100; ++i) {
    sim.advance_to(sim.now_utime() + 10000);
    for (const auto& m : sim.take_mocap()) all.push_back(m);
  }
  int in_gap = 0, gaps = 0;
  for (size_t i = 0; i < all.size(); ++i) {
    if (all[i].pose.utime >= t0 && all[i].pose.utime < t1) ++in_gap;
    if (i > 0 && all[i].seq != all[i - 1].seq + 1) {
      ++gaps;
      EXPECT_EQ(all[i].seq - all[i - 1].seq, 26);  // 25 samples lost at 100 Hz
      EXPECT_GE(all[i].pose.utime, t1);
    }
  }
  EXPECT_EQ(in_gap, 0);
  EXPECT_EQ(gaps, 1);
}

TEST_F(SimSensorsTest, ScenarioDropoutsAndRandomLossesApply) {
  scenario_.mocap.dropouts_s = {{0.5, 1.0}};
  scenario_.mocap.dropout_probability = 0.2;
  Simulator sim(scenario_, vehicle_, 5);
  const int64_t start = sim.now_utime();
  int n = 0, in_window = 0;
  for (int i = 0; i < 300; ++i) {
    sim.advance_to(sim.now_utime() + 10000);
    for (const auto& m : sim.take_mocap()) {
      ++n;
      if (m.pose.utime >= start + 500000 && m.pose.utime < start + 1000000) ++in_window;
    }
  }
  EXPECT_EQ(in_window, 0);
  EXPECT_NEAR(n, 0.8 * 250, 25);  // 300 samples, 50 in the window, a fifth of the rest lost
}

TEST_F(SimSensorsTest, ImuAtRestReadsGravityWithTheConfiguredNoise) {
  scenario_.imu.accel_bias_sigma_mps2 = 0.0;
  scenario_.imu.gyro_bias_sigma_radps = 0.0;
  scenario_.imu.accel_sigma_mps2 = 0.05;
  scenario_.imu.gyro_sigma_radps = 0.004;
  Simulator sim(scenario_, vehicle_, 9);
  sim.advance_to(sim.now_utime() + 500000);
  sim.take_imu();
  Stats az, ax, gz;
  int64_t n = 0;
  int64_t last_utime = 0;
  for (int i = 0; i < 100; ++i) {
    sim.advance_to(sim.now_utime() + 50000);
    for (const auto& s : sim.take_imu()) {
      if (last_utime) {
        EXPECT_EQ(s.utime - last_utime, 5000);  // 200 Hz
      }
      last_utime = s.utime;
      az.add(s.accel_B.z());
      ax.add(s.accel_B.x());
      gz.add(s.gyro_B.z());
      ++n;
    }
  }
  EXPECT_EQ(n, 1000);
  EXPECT_NEAR(az.mean(), 9.81, 0.01);
  EXPECT_NEAR(ax.mean(), 0.0, 0.01);
  EXPECT_NEAR(az.sd(), 0.05, 0.005);
  EXPECT_NEAR(gz.sd(), 0.004, 0.0004);
}

TEST_F(SimSensorsTest, ImuBiasIsDrawnPerSeed) {
  auto mean_ax = [&](uint64_t seed) {
    Simulator sim(scenario_, vehicle_, seed);
    sim.advance_to(sim.now_utime() + 500000);
    Stats ax;
    for (const auto& s : sim.take_imu()) ax.add(s.accel_B.x());
    return ax.mean();
  };
  EXPECT_GT(std::abs(mean_ax(1) - mean_ax(2)), 1e-3);
  EXPECT_EQ(mean_ax(3), mean_ax(3));
}

TEST_F(SimSensorsTest, TouchDownGivesAnAccelerometerSpike) {
  // Paper 3.4.1: the final descent cuts the motors when the accelerometer sees touch-down.
  Simulator sim(scenario_, vehicle_, 2);
  place(sim, Vector3d(0, 0, vehicle_.gear_height_m + 0.2));
  AttitudeCommand cmd = hover(vehicle_);
  cmd.thrust_N *= 0.85;
  double peak_before = 0, peak_after = 0;
  int64_t touch_utime = 0;
  for (int ms = 0; ms < 1500; ++ms) {
    sim.step(cmd, sim.now_utime() + 1000);
    if (!touch_utime && sim.truth().contact != Contact::kNone) touch_utime = sim.now_utime();
    for (const auto& s : sim.take_imu()) {
      const double a = s.accel_B.z();
      if (!touch_utime)
        peak_before = std::max(peak_before, a);
      else if (s.utime < touch_utime + 100000)
        peak_after = std::max(peak_after, a);
    }
  }
  ASSERT_NE(touch_utime, 0);
  EXPECT_LT(peak_before, 9.81);       // descending under less than the weight
  EXPECT_GT(peak_after, 2.0 * 9.81);  // the gear stops the vehicle hard
}

TEST_F(SimSensorsTest, MessagesCarryTheSamples) {
  Simulator sim(scenario_, vehicle_, 2);
  sim.advance_to(sim.now_utime() + 100000);
  const auto mocap = sim.take_mocap();
  ASSERT_FALSE(mocap.empty());
  const pose_t pm = to_msg(mocap.back());
  EXPECT_EQ(pm.utime, mocap.back().pose.utime);
  EXPECT_EQ(pm.seq, mocap.back().seq);
  EXPECT_DOUBLE_EQ(pm.pos[2], mocap.back().pose.p_W_B.z());
  const auto imu = sim.take_imu();
  ASSERT_FALSE(imu.empty());
  const imu_t im = to_msg(imu.back());
  EXPECT_EQ(im.seq, imu.back().seq);
  EXPECT_DOUBLE_EQ(im.accel_B[2], imu.back().accel_B.z());

  Simulator land(test::quiet(test::scenario("landing_b")), vehicle_, 2);
  land.advance_to(land.now_utime() + 100000);
  const sim_truth_t tm = to_msg(land.truth());
  EXPECT_TRUE(tm.has_platform);
  EXPECT_FALSE(tm.has_opening);
  EXPECT_DOUBLE_EQ(tm.platform_center_W[2], 0.219);
  EXPECT_EQ(tm.contact, sim_truth_t::CONTACT_FLOOR);
  EXPECT_EQ(tm.scenario, "landing_b");

  attitude_cmd_t cm{};
  cm.roll_rad = 0.1;
  cm.thrust_N = 11.0;
  cm.armed = true;
  const AttitudeCommand c = from_msg(cm);
  EXPECT_EQ(c.roll_rad, 0.1);
  EXPECT_EQ(c.thrust_N, 11.0);
  EXPECT_TRUE(c.armed);
}

}  // namespace
}  // namespace alight::sim
