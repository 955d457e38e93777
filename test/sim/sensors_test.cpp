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

// ---- Rangefinder -------------------------------------------------------------------------

Isometry3d level_at(const Vector3d& p_W_B, double roll_rad = 0.0) {
  return make_transform(rotation_from_rpy(roll_rad, 0, 0), p_W_B);
}

RangefinderParams noiseless_rangefinder() {
  RangefinderParams p;
  p.sigma_m = 0.0;
  p.sigma_frac = 0.0;
  p.dropout_prob = 0.0;
  p.latency_s = 0.0;
  p.offset_B_m = Vector3d::Zero();
  return p;
}

// Runs the emulator at a fixed pose for `seconds`, returning every sample.
std::vector<RangeSample> range_samples(const RangefinderParams& p, const Scene& scene,
                                       const Isometry3d& X_WB, double seconds, uint64_t seed = 7) {
  constexpr int64_t t0 = 1'700'000'000'000'000;
  RangefinderEmulator rf(p, t0, seed);
  std::vector<RangeSample> out;
  for (int64_t t = t0; t <= t0 + static_cast<int64_t>(seconds * 1e6); t += 1000) {
    rf.update(t, X_WB, scene);
    for (const auto& s : rf.take(t)) out.push_back(s);
  }
  return out;
}

TEST_F(SimSensorsTest, RangefinderKnownAnswersOverFloorPlatformAndOutOfRange) {
  const Scene floor = build_scene(scenario_, 1);
  const Scene platform = build_scene(test::quiet(test::scenario("landing_a")), 1);
  RangefinderParams p = noiseless_rangefinder();
  p.offset_B_m = Vector3d(0.1, 0.0, -0.05);  // ahead of and below the body origin
  auto one = [&](const Scene& scene, const Isometry3d& X_WB) {
    const auto s = range_samples(p, scene, X_WB, 0.02);
    EXPECT_FALSE(s.empty());
    return s.empty() ? RangeSample{} : s.back();
  };
  RangeSample s = one(floor, level_at(Vector3d(0, 0, 2.0)));
  EXPECT_EQ(s.status, RangeStatus::kOk);
  EXPECT_NEAR(s.distance_m, 1.95, 1e-12);
  EXPECT_TRUE(s.t_B_R.isApprox(p.offset_B_m));
  EXPECT_TRUE(s.beam_B.isApprox(-Vector3d::UnitZ()));
  // Rolled by 20 deg: the sensor swings with the body, the beam slants.
  const double roll = 20.0 * M_PI / 180.0;
  s = one(floor, level_at(Vector3d(0, 0, 2.0), roll));
  const double z_sensor = 2.0 - 0.05 * std::cos(roll);
  EXPECT_NEAR(s.distance_m, z_sensor / std::cos(roll), 1e-12);
  // Over the platform's top (landing_a: 10.9 cm high, centred at (1.0, 0.5)): the body origin
  // 0.1 m behind the platform's centre puts the sensor over it.
  s = one(platform, level_at(Vector3d(0.9, 0.5, 1.0)));
  EXPECT_EQ(s.status, RangeStatus::kOk);
  EXPECT_NEAR(s.distance_m, 0.95 - 0.109, 1e-12);
  s = one(platform, level_at(Vector3d(1.0 + 0.216 - 0.1 + 0.01, 0.5, 1.0)));  // past its edge
  EXPECT_NEAR(s.distance_m, 0.95, 1e-12);
  // Out of range: higher than max_range_m, upside down, or nearer than min_range_m.
  s = one(floor, level_at(Vector3d(0, 0, 9.0)));
  EXPECT_EQ(s.status, RangeStatus::kOutOfRange);
  EXPECT_EQ(s.distance_m, 0.0);
  s = one(floor, level_at(Vector3d(0, 0, 2.0), M_PI));
  EXPECT_EQ(s.status, RangeStatus::kOutOfRange);
  s = one(floor, level_at(Vector3d(0, 0, 0.1)));  // sensor 5 cm above the floor
  EXPECT_EQ(s.status, RangeStatus::kTooNear);
  EXPECT_EQ(s.distance_m, 0.0);
  // The message carries the status and no number without a measurement.
  const range_t m = to_msg(s);
  EXPECT_EQ(m.status, range_t::STATUS_TOO_NEAR);
  EXPECT_EQ(m.distance_m, 0.0);
  EXPECT_EQ(m.min_range_m, p.min_range_m);
  EXPECT_EQ(m.max_range_m, p.max_range_m);
  EXPECT_EQ(m.t_B_R[0], 0.1);
  EXPECT_EQ(m.beam_B[2], -1.0);
}

TEST_F(SimSensorsTest, RangefinderNoiseGrowsWithTheDistanceAsConfigured) {
  const Scene floor = build_scene(scenario_, 1);
  RangefinderParams p = noiseless_rangefinder();
  p.sigma_m = 0.01;
  p.sigma_frac = 0.01;
  for (const double h : {1.0, 5.0}) {
    SCOPED_TRACE(h);
    const auto samples = range_samples(p, floor, level_at(Vector3d(0, 0, h)), 100.0);
    Stats d;
    for (const auto& s : samples) {
      ASSERT_EQ(s.status, RangeStatus::kOk);
      d.add(s.distance_m);
    }
    EXPECT_NEAR(d.n, 10000, 1);  // 100 Hz
    const double sigma = 0.01 + 0.01 * h;
    EXPECT_NEAR(d.mean(), h, 4 * sigma / std::sqrt(d.n));
    EXPECT_NEAR(d.sd(), sigma, 0.03 * sigma);
  }
}

TEST_F(SimSensorsTest, RangefinderReadingsNearItsLimitsAreNeverOutsideThem) {
  const Scene floor = build_scene(scenario_, 1);
  RangefinderParams p = noiseless_rangefinder();
  p.sigma_m = 0.2;
  for (const double h : {p.max_range_m - 0.1, p.min_range_m + 0.1}) {
    int ok = 0, out = 0;
    for (const auto& s : range_samples(p, floor, level_at(Vector3d(0, 0, h)), 20.0)) {
      if (s.status == RangeStatus::kOk) {
        ++ok;
        EXPECT_GE(s.distance_m, p.min_range_m);
        EXPECT_LE(s.distance_m, p.max_range_m);
      } else {
        ++out;
        EXPECT_EQ(s.status, h > 1 ? RangeStatus::kOutOfRange : RangeStatus::kTooNear);
        EXPECT_EQ(s.distance_m, 0.0);
      }
    }
    // Half a sigma inside the limit: about 31 % of the readings fall beyond it.
    EXPECT_NEAR(out / double(ok + out), 0.31, 0.03) << h;
  }
}

TEST_F(SimSensorsTest, RangefinderDropoutsComeAtTheConfiguredRateAndInBursts) {
  const Scene floor = build_scene(scenario_, 1);
  RangefinderParams p = noiseless_rangefinder();
  p.dropout_prob = 0.1;
  for (const double burst_s : {0.0, 0.05}) {
    SCOPED_TRACE(burst_s);
    p.dropout_burst_s = burst_s;
    const auto samples = range_samples(p, floor, level_at(Vector3d(0, 0, 2.0)), 500.0);
    int lost = 0, runs = 0;
    bool in_run = false;
    int64_t last_seq = 0;
    for (const auto& s : samples) {
      EXPECT_EQ(s.seq, last_seq + 1);  // a lost return is still a sample
      last_seq = s.seq;
      const bool l = s.status == RangeStatus::kNoEcho;
      if (l) {
        EXPECT_EQ(s.distance_m, 0.0);
        ++lost;
      }
      if (l && !in_run) ++runs;
      in_run = l;
    }
    ASSERT_EQ(samples.size(), 50000u);
    EXPECT_NEAR(lost / 50000.0, 0.1, 0.015);
    // Mean run length: max(1, burst_s x 100 Hz) samples.
    EXPECT_NEAR(lost / double(runs), std::max(1.0, burst_s * 100), burst_s > 0 ? 0.5 : 0.05);
  }
}

TEST_F(SimSensorsTest, RangefinderRateLatencyAndSeeds) {
  const Scene floor = build_scene(scenario_, 1);
  RangefinderParams p;  // the defaults: noise and dropouts
  p.rate_hz = 50;
  p.latency_s = 0.015;
  constexpr int64_t t0 = 1'700'000'000'000'000;
  RangefinderEmulator rf(p, t0, 3);
  int64_t last = 0, n = 0;
  for (int64_t t = t0; t < t0 + 2'000'000; t += 1000) {
    rf.update(t, level_at(Vector3d(0, 0, 1.5)), floor);
    for (const auto& s : rf.take(t)) {
      EXPECT_GE(t - s.utime, 15000);
      EXPECT_LT(t - s.utime, 16000);
      if (last) {
        EXPECT_EQ(s.utime - last, 20000);
      }
      last = s.utime;
      ++n;
    }
  }
  EXPECT_NEAR(n, 99, 1);
  auto distances = [&](uint64_t seed) {
    std::vector<double> d;
    for (const auto& s : range_samples(p, floor, level_at(Vector3d(0, 0, 1.5)), 1.0, seed))
      d.push_back(s.distance_m);
    return d;
  };
  EXPECT_EQ(distances(4), distances(4));
  EXPECT_NE(distances(4), distances(5));
}

TEST_F(SimSensorsTest, TheSimulatorsRangefinderSeesThePlatformTopWhenOverIt) {
  Scenario sc = test::quiet(test::scenario("landing_a"));
  sc.rangefinder = noiseless_rangefinder();
  sc.rangefinder.offset_B_m = Vector3d(0, 0, -0.05);
  Simulator sim(sc, vehicle_, 2);
  const Vector3d top = sim.truth().platform->top_center_W;
  place(sim, Vector3d(top.x(), top.y(), 1.2));
  sim.step(hover(vehicle_), sim.now_utime() + 100'000);
  const auto over = sim.take_range();
  ASSERT_GE(over.size(), 9u);
  for (const auto& s : over) {
    ASSERT_EQ(s.status, RangeStatus::kOk);
    EXPECT_NEAR(s.distance_m, 1.15 - top.z(), 0.005);  // hovering: it barely moves
  }
  place(sim, Vector3d(top.x() - 0.6, top.y(), 1.2));
  sim.step(hover(vehicle_), sim.now_utime() + 100'000);
  const auto beside = sim.take_range();
  ASSERT_GE(beside.size(), 9u);
  for (const auto& s : beside) EXPECT_NEAR(s.distance_m, 1.15, 0.005);
}

// ---- Barometer ---------------------------------------------------------------------------

TEST(SimBaroTest, StandardAtmosphereKnownAnswers) {
  // ICAO Doc 7488 / ISO 2533 tables.
  EXPECT_NEAR(isa_pressure_pa(0.0), 101325.0, 1e-9);
  EXPECT_NEAR(isa_pressure_pa(1000.0), 89874.6, 0.1);
  EXPECT_NEAR(isa_pressure_pa(5000.0), 54019.9, 0.5);
  EXPECT_NEAR(isa_pressure_pa(11000.0), 22632.1, 0.5);
  EXPECT_NEAR(isa_pressure_pa(-500.0), 107477.7, 0.5);
  EXPECT_NEAR(isa_temperature_c(1000.0), 8.5, 1e-12);
  EXPECT_NEAR(isa_temperature_c(11000.0), -56.5, 1e-12);
  // About 12 Pa per metre near sea level.
  EXPECT_NEAR(isa_pressure_pa(0.0) - isa_pressure_pa(1.0), 12.0, 0.1);
  for (const double h : {-300.0, 0.0, 1.5, 250.0, 1000.0, 4000.0})
    EXPECT_NEAR(isa_altitude_m(isa_pressure_pa(h, 100800, 22), 100800, 22), h, 1e-6);
  // Another day: the sea-level values scale it.
  EXPECT_NEAR(isa_pressure_pa(0.0, 100000.0, 25.0), 100000.0, 1e-9);
}

BaroParams noiseless_baro() {
  BaroParams p;
  p.sigma_pa = 0.0;
  p.offset_sigma_pa = 0.0;
  p.drift_pa_per_sqrt_s = 0.0;
  p.latency_s = 0.0;
  return p;
}

std::vector<BaroSample> baro_samples(const BaroParams& p, const Vector3d& p_W_B, double seconds,
                                     uint64_t seed = 1) {
  constexpr int64_t t0 = 1'700'000'000'000'000;
  BaroEmulator baro(p, t0, seed);
  std::vector<BaroSample> out;
  for (int64_t t = t0; t <= t0 + static_cast<int64_t>(seconds * 1e6); t += 1000) {
    baro.update(t, p_W_B);
    for (const auto& s : baro.take(t)) out.push_back(s);
  }
  return out;
}

TEST(SimBaroTest, PressureAndTemperatureAreTheStandardAtmospheresAtTheSensor) {
  BaroParams p = noiseless_baro();
  p.ground_altitude_m = 1000.0;
  const auto s = baro_samples(p, Vector3d(0.5, -1, 0.0), 0.1);
  ASSERT_EQ(s.size(), 5u);  // 50 Hz
  EXPECT_NEAR(s.back().pressure_pa, 89874.6, 0.1);
  EXPECT_NEAR(s.back().temperature_c, 8.5, 1e-9);
  const auto up = baro_samples(p, Vector3d(0.5, -1, 2.0), 0.1);
  EXPECT_NEAR(up.back().pressure_pa, isa_pressure_pa(1002.0), 1e-6);
  const baro_t m = to_msg(up.back());
  EXPECT_EQ(m.utime, up.back().utime);
  EXPECT_EQ(m.seq, up.back().seq);
  EXPECT_EQ(m.pressure_pa, up.back().pressure_pa);
  EXPECT_EQ(m.temperature_c, up.back().temperature_c);
}

TEST(SimBaroTest, NoiseOffsetRateAndLatencyAreAsConfigured) {
  BaroParams p = noiseless_baro();
  p.sigma_pa = 2.0;
  p.latency_s = 0.02;
  constexpr int64_t t0 = 1'700'000'000'000'000;
  BaroEmulator baro(p, t0, 11);
  Stats d;
  int64_t last = 0;
  for (int64_t t = t0; t < t0 + 200'000'000; t += 1000) {
    baro.update(t, Vector3d::Zero());
    for (const auto& s : baro.take(t)) {
      EXPECT_GE(t - s.utime, 20000);
      EXPECT_LT(t - s.utime, 21000);
      if (last) {
        EXPECT_EQ(s.utime - last, 20000);
      }
      last = s.utime;
      d.add(s.pressure_pa - 101325.0);
    }
  }
  EXPECT_NEAR(d.n, 10000, 2);
  EXPECT_NEAR(d.mean(), 0.0, 4 * 2.0 / 100);
  EXPECT_NEAR(d.sd(), 2.0, 0.06);
  // The offset is drawn once per run, with the configured spread across runs.
  p = noiseless_baro();
  p.offset_sigma_pa = 50.0;
  Stats offsets;
  for (uint64_t seed = 0; seed < 2000; ++seed) {
    const BaroEmulator b(p, t0, seed);
    offsets.add(b.offset_pa());
  }
  EXPECT_NEAR(offsets.sd(), 50.0, 3.0);
}

TEST(SimBaroTest, TheDriftWalksAsSqrtTimeAndStaysBoundedByItsCorrelationTime) {
  BaroParams p = noiseless_baro();
  p.drift_pa_per_sqrt_s = 0.2;
  p.drift_tau_s = 300.0;
  // Across runs, after t seconds: sd = q sqrt(tau / 2 (1 - exp(-2 t / tau))).
  auto drift_sd = [&](double t_s) {
    Stats d;
    for (uint64_t seed = 0; seed < 400; ++seed) {
      const auto s = baro_samples(p, Vector3d::Zero(), t_s, seed);
      d.add(s.back().pressure_pa - 101325.0);
    }
    return d.sd();
  };
  const double q = p.drift_pa_per_sqrt_s;
  double tau = p.drift_tau_s;
  auto expected = [&](double t) { return q * std::sqrt(0.5 * tau * (1 - std::exp(-2 * t / tau))); };
  EXPECT_NEAR(drift_sd(10.0), expected(10.0), 0.1 * expected(10.0));  // ~ q sqrt(10)
  EXPECT_NEAR(expected(10.0), q * std::sqrt(10.0), 0.02 * q * std::sqrt(10.0));
  p.drift_tau_s = tau = 20.0;
  EXPECT_NEAR(drift_sd(100.0), q * std::sqrt(tau / 2), 0.1 * q * std::sqrt(tau / 2));
  // And it is a slow wander: one run's samples 20 ms apart differ by q sqrt(0.02) at most
  // about, not by the drift's whole spread.
  p.drift_tau_s = 300.0;
  const auto run = baro_samples(p, Vector3d::Zero(), 60.0, 5);
  Stats step;
  for (size_t i = 1; i < run.size(); ++i) step.add(run[i].pressure_pa - run[i - 1].pressure_pa);
  EXPECT_NEAR(step.sd(), q * std::sqrt(0.02), 0.1 * q * std::sqrt(0.02));
}

// ---- IMU bias walk and the switches -------------------------------------------------------

TEST_F(SimSensorsTest, ImuBiasRandomWalksAsConfigured) {
  ImuParams p = scenario_.imu;
  p.accel_bias_sigma_mps2 = 0.0;
  p.gyro_bias_sigma_radps = 0.0;
  p.accel_bias_walk_mps2_per_sqrt_s = 4e-4;
  p.gyro_bias_walk_radps_per_sqrt_s = 3e-5;
  constexpr int64_t t0 = 1'700'000'000'000'000;
  Stats accel, gyro;
  for (uint64_t seed = 0; seed < 200; ++seed) {
    ImuEmulator imu(p, t0, seed);
    for (int64_t t = t0 + 5000; t <= t0 + 100'000'000; t += 5000)
      imu.update(t, 5000, Vector3d(0, 0, 9.81), Vector3d::Zero());
    for (int k = 0; k < 3; ++k) {
      accel.add(imu.accel_bias()[k]);
      gyro.add(imu.gyro_bias()[k]);
    }
  }
  // After 100 s: q sqrt(100) = 10 q.
  EXPECT_NEAR(accel.sd(), 4e-3, 4e-4);
  EXPECT_NEAR(gyro.sd(), 3e-4, 3e-5);
  // The walk has a stream of its own: the white noise of a run is unchanged by it.
  ImuParams still = p;
  still.accel_bias_walk_mps2_per_sqrt_s = 0.0;
  still.gyro_bias_walk_radps_per_sqrt_s = 0.0;
  ImuEmulator a(p, t0, 1), b(still, t0, 1);
  a.update(t0 + 5000, 5000, Vector3d::Zero(), Vector3d::Zero());
  b.update(t0 + 5000, 5000, Vector3d::Zero(), Vector3d::Zero());
  const ImuSample sa = a.take().at(0), sb = b.take().at(0);
  EXPECT_NEAR((sa.accel_B - a.accel_bias() - (sb.accel_B - b.accel_bias())).norm(), 0.0, 1e-12);
}

TEST_F(SimSensorsTest, ASensorSwitchedOffDeliversNothingAndTheOthersAreUnchanged) {
  Scenario on = scenario_;
  Scenario off = scenario_;
  off.mocap.enabled = false;
  off.imu.enabled = false;
  off.rangefinder.enabled = false;
  off.baro.enabled = false;
  Simulator a(on, vehicle_, 4), b(off, vehicle_, 4);
  place(a, Vector3d(0, 0, 1.0));
  place(b, Vector3d(0, 0, 1.0));
  a.step(hover(vehicle_), a.now_utime() + 1'000'000);
  b.step(hover(vehicle_), b.now_utime() + 1'000'000);
  EXPECT_NEAR(a.take_mocap().size(), 100, 1);
  EXPECT_EQ(a.take_imu().size(), 200u);
  EXPECT_NEAR(a.take_range().size(), 99, 1);
  EXPECT_NEAR(a.take_baro().size(), 49, 1);
  EXPECT_TRUE(b.take_mocap().empty());
  EXPECT_TRUE(b.take_imu().empty());
  EXPECT_TRUE(b.take_range().empty());
  EXPECT_TRUE(b.take_baro().empty());
  // The flight itself does not depend on what is measured.
  EXPECT_EQ(a.truth().state.p_W_B, b.truth().state.p_W_B);
  // Each switch alone: the rangefinder off leaves the barometer's samples as they were.
  Scenario no_range = scenario_;
  no_range.rangefinder.enabled = false;
  Simulator c(no_range, vehicle_, 4), d(scenario_, vehicle_, 4);
  c.advance_to(c.now_utime() + 500'000);
  d.advance_to(d.now_utime() + 500'000);
  EXPECT_TRUE(c.take_range().empty());
  const auto bc = c.take_baro(), bd = d.take_baro();
  ASSERT_EQ(bc.size(), bd.size());
  for (size_t i = 0; i < bc.size(); ++i) EXPECT_EQ(bc[i].pressure_pa, bd[i].pressure_pa);
}

}  // namespace
}  // namespace alight::sim
