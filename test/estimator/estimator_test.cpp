// The estimator's behaviour: alignment, analytic motions (constant acceleration, pure rotation),
// a hover, the platform step, gating, delayed measurements and replay, bad inputs, health.

#include "estimator/estimator.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <limits>
#include <random>

#include "common/geometry.hpp"
#include "synthetic.hpp"

namespace alight::estimator {
namespace {

using test::Flight;
using test::SensorConfig;

constexpr int64_t kT0 = test::kStartUtime;
constexpr int64_t kDtUs = 5000;  // 200 Hz
constexpr double kRestZ = 0.12;  // body origin above the floor when resting on the legs

EstimatorParams default_params(double z0 = kRestZ) {
  EstimatorParams p;
  p.init.p_W_B_m = Vector3d(0, 0, z0);
  return p;
}

ImuSample at_rest(int64_t utime, const EstimatorParams& p) {
  return {utime, Vector3d(0, 0, p.gravity_mps2), Vector3d::Zero()};
}

/// Feeds still samples until the estimator has aligned; returns the last stamp.
int64_t align(Estimator& est, int64_t t = kT0) {
  for (int i = 0; i < 1000 && !est.initialised(); ++i)
    est.add_imu(at_rest(t += kDtUs, est.params()));
  return t;
}

/// Bit-for-bit equality of the estimate (not counters, which may legitimately differ).
void expect_same_estimate(const State& a, const State& b) {
  EXPECT_EQ(a.utime, b.utime);
  EXPECT_EQ(a.p_W_B, b.p_W_B);
  EXPECT_EQ(a.v_W_B, b.v_W_B);
  EXPECT_EQ(a.q_WB.coeffs(), b.q_WB.coeffs());
  EXPECT_EQ(a.accel_bias_B, b.accel_bias_B);
  EXPECT_EQ(a.gyro_bias_B, b.gyro_bias_B);
  EXPECT_EQ(a.baro_offset_m, b.baro_offset_m);
  EXPECT_EQ(a.terrain_height_m, b.terrain_height_m);
  EXPECT_EQ(a.cov, b.cov);
}

/// As expect_same_estimate, except the baro offset and its covariance row.
void expect_same_estimate_but_baro(const State& a, const State& b) {
  EXPECT_EQ(a.p_W_B, b.p_W_B);
  EXPECT_EQ(a.v_W_B, b.v_W_B);
  EXPECT_EQ(a.q_WB.coeffs(), b.q_WB.coeffs());
  EXPECT_EQ(a.terrain_height_m, b.terrain_height_m);
  const Eigen::Matrix<double, 15, 15> ca = a.cov.topLeftCorner<15, 15>();
  const Eigen::Matrix<double, 15, 15> cb = b.cov.topLeftCorner<15, 15>();
  EXPECT_EQ(ca, cb);
}

Estimator fly(const Flight& f, const EstimatorParams& p, size_t n_inputs = SIZE_MAX) {
  Estimator est(p);
  for (size_t i = 0; i < f.inputs.size() && i < n_inputs; ++i) test::feed(est, f.inputs[i]);
  return est;
}

const test::Truth& truth_at(const Flight& f, int64_t utime) {
  const auto it = std::lower_bound(f.truth.begin(), f.truth.end(), utime,
                                   [](const test::Truth& t, int64_t u) { return t.utime < u; });
  return *it;
}

// ---- Initialisation

/// A flight over a platform: the largest height error, and the terrain estimate while the truth
/// is over [on_x0, on_x1) and after it, over [after_x0, after_x1) (-1 when never there).
struct PlatformPass {
  double max_z_error = 0, terrain_on_platform = -1, terrain_after = -1;
  State final_state;
};
PlatformPass fly_over(const Flight& f, const EstimatorParams& p, double on_x0, double on_x1,
                      double after_x0, double after_x1) {
  Estimator est(p);
  PlatformPass r;
  for (const auto& in : f.inputs) {
    test::feed(est, in);
    if (in.kind != test::Kind::kImu || !est.initialised()) continue;
    const State s = est.state();
    const test::Truth& truth = truth_at(f, s.utime);
    r.max_z_error = std::max(r.max_z_error, std::abs(s.p_W_B.z() - truth.p_W_B.z()));
    const double x = truth.p_W_B.x();
    if (x > on_x0 && x < on_x1) r.terrain_on_platform = s.terrain_height_m;
    if (x > after_x0 && x < after_x1) r.terrain_after = s.terrain_height_m;
  }
  r.final_state = est.state();
  return r;
}

TEST(EstimatorTest, NotInitialisedUntilStillForTheAlignmentTimeThenLevelledFromTheAccelerometer) {
  EstimatorParams p = default_params();
  p.init.yaw_deg = 30;
  Estimator est(p);
  const Matrix3d R_true = rotation_from_rpy(0.1, -0.05, 30 * M_PI / 180);
  const Vector3d gyro_bias(0.004, -0.002, 0.001);
  const ImuSample still{0, R_true.transpose() * Vector3d(0, 0, p.gravity_mps2), gyro_bias};
  int64_t t = kT0;
  for (int i = 0; i < 100; ++i) {  // 0.5 s still
    ImuSample s = still;
    s.utime = t += kDtUs;
    EXPECT_EQ(est.add_imu(s), Outcome::kFused);
  }
  // A jolt starts the alignment over.
  ImuSample jolt = still;
  jolt.utime = t += kDtUs;
  jolt.gyro_B = Vector3d(0.5, 0, 0);
  est.add_imu(jolt);
  for (int i = 0; i < 150; ++i) {
    ImuSample s = still;
    s.utime = t += kDtUs;
    est.add_imu(s);
  }
  EXPECT_FALSE(est.initialised());
  const State before = est.state();
  EXPECT_EQ(before.health, Health::kLost);
  EXPECT_EQ(before.health_reasons, kNotInitialised);
  EXPECT_EQ(est.add_range({t, 1.0, true}), Outcome::kNotInitialised);
  for (int i = 0; i < 60; ++i) {
    ImuSample s = still;
    s.utime = t += kDtUs;
    est.add_imu(s);
  }
  ASSERT_TRUE(est.initialised());
  const State st = est.state();
  const Vector3d rpy = rpy_from_rotation(st.q_WB.toRotationMatrix());
  EXPECT_NEAR(rpy[0], 0.1, 1e-9);
  EXPECT_NEAR(rpy[1], -0.05, 1e-9);
  EXPECT_NEAR(rpy[2], 30 * M_PI / 180, 1e-9);
  EXPECT_TRUE(st.gyro_bias_B.isApprox(gyro_bias, 1e-12));
  EXPECT_LT((st.p_W_B - p.init.p_W_B_m).norm(), 1e-9);  // 0.3 s of a still IMU since
  EXPECT_EQ(st.terrain_height_m, 0.0);
  EXPECT_EQ(st.counters.count(Sensor::kRange, Outcome::kNotInitialised), 1);
}

// ---- Analytic motions with perfect sensors

TEST(EstimatorTest, ConstantAccelerationGivesHalfATSquared) {
  const EstimatorParams p = default_params(1.0);
  Estimator est(p);
  int64_t t = align(est);
  const Vector3d p0 = est.state().p_W_B;
  const Vector3d a_W(0.8, -0.5, 0.3);
  const int n = 400;  // 2 s
  for (int i = 0; i < n; ++i)
    est.add_imu({t += kDtUs, a_W + Vector3d(0, 0, p.gravity_mps2), Vector3d::Zero()});
  const double T = n * kDtUs * 1e-6;
  const State s = est.state();
  EXPECT_LT((s.p_W_B - (p0 + 0.5 * a_W * T * T)).norm(), 1e-9) << s.p_W_B.transpose();
  EXPECT_LT((s.v_W_B - a_W * T).norm(), 1e-9);
  EXPECT_LT(s.q_WB.angularDistance(Quaterniond::Identity()), 1e-12);
}

TEST(EstimatorTest, PureRotationFollowsTheAnalyticQuaternion) {
  const EstimatorParams p = default_params(1.0);
  Estimator est(p);
  int64_t t = align(est);
  const Vector3d omega_B(0.3, -0.2, 0.5);
  const Vector3d g_up(0, 0, p.gravity_mps2);
  const int n = 600;  // 3 s
  for (int i = 1; i <= n; ++i) {
    // The IMU's mean specific force over the interval of a body spinning at a constant rate.
    Vector3d f = Vector3d::Zero();
    for (int j = 0; j < 16; ++j) {
      const double tau = ((i - 1) + (j + 0.5) / 16.0) * kDtUs * 1e-6;
      f += quat_exp(omega_B * tau).conjugate() * g_up / 16.0;
    }
    est.add_imu({t += kDtUs, f, omega_B});
  }
  const State s = est.state();
  const Quaterniond expected = quat_exp(omega_B * (n * kDtUs * 1e-6));
  EXPECT_LT(test::attitude_error(s.q_WB, expected).norm(), 1e-9);
  // The attitude at a past time, between two IMU samples, for the flow front end.
  const int64_t past = t - 37 * kDtUs - 1234;
  const Quaterniond at_past = quat_exp(omega_B * ((n * kDtUs - (t - past)) * 1e-6));
  ASSERT_TRUE(est.attitude_at(past).has_value());
  EXPECT_LT(test::attitude_error(*est.attitude_at(past), at_past).norm(), 1e-9);
  EXPECT_EQ(est.attitude_at(t)->coeffs(), s.q_WB.coeffs());
  EXPECT_FALSE(est.attitude_at(t + 1).has_value());
  EXPECT_FALSE(est.attitude_at(t - 2'000'000).has_value());
  EXPECT_LT((s.p_W_B - p.init.p_W_B_m).norm(), 1e-3) << s.p_W_B.transpose();
  EXPECT_LT(s.v_W_B.norm(), 1e-3);
}

// ---- A hover with every sensor

TEST(EstimatorTest, StaticHoverStaysPutBiasesConvergeCovarianceBounded) {
  // A perfect hover at 1.2 m (the specific force of a hover is that of rest, so the alignment
  // runs in the air), every sensor with the default noise, true biases drawn at random.
  const EstimatorParams p = default_params(1.2);
  const Flight f = test::simulate(test::hover(1.2, 1.2), 40.0, SensorConfig{}, p, 11);
  Estimator est(p);
  double max_cov_p_h = 0, max_cov_p_z = 0;
  for (const auto& in : f.inputs) {
    test::feed(est, in);
    if (in.kind == test::Kind::kImu && est.initialised()) {
      const Matrix3d cp = est.state().cov_p();
      max_cov_p_h = std::max({max_cov_p_h, cp(0, 0), cp(1, 1)});
      max_cov_p_z = std::max(max_cov_p_z, cp(2, 2));
    }
  }
  const State s = est.state();
  const test::Truth& truth = truth_at(f, s.utime);
  EXPECT_LT((s.p_W_B - truth.p_W_B).head<2>().norm(), 0.1);
  EXPECT_LT(std::abs(s.p_W_B.z() - truth.p_W_B.z()), 0.03);
  EXPECT_LT(s.v_W_B.norm(), 0.03);
  // Observable in a hover: the gyro bias about x and y (a tilt makes the flow drift) and the
  // accelerometer bias along z (height from range and baro). Not yaw, not horizontal accel bias.
  EXPECT_LT((s.gyro_bias_B - f.gyro_bias_B).head<2>().norm(), 5e-4) << s.gyro_bias_B.transpose();
  EXPECT_LT(std::abs(s.accel_bias_B.z() - f.accel_bias_B.z()), 0.03);
  EXPECT_LT(std::sqrt(max_cov_p_h), 0.5);
  EXPECT_LT(std::sqrt(max_cov_p_z), 0.1);
  EXPECT_TRUE(s.cov.isApprox(s.cov.transpose()));
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<CoreMatrix>(s.cov).eigenvalues().minCoeff(), 0.0);
  EXPECT_EQ(s.health, Health::kOk) << health_reasons_text(s.health_reasons);
  EXPECT_EQ(s.counters.rejected(Sensor::kImu), 0);
  EXPECT_GT(s.counters.fused(Sensor::kFlow), 1000);
  EXPECT_GT(s.counters.fused(Sensor::kRange), 1500);
  EXPECT_GT(s.counters.fused(Sensor::kBaro), 800);
}

// ---- Platform step

TEST(EstimatorTest, RangeStepOntoAPlatformResetsTheTerrainNotTheVehicleHeight) {
  // Hover at 1.5 m, then the first leg of a square (+x, 1 m/s) crosses a 0.5 m platform from
  // x = 3 m to x = 5 m.
  const EstimatorParams p = default_params();
  SensorConfig cfg;
  cfg.platform = test::Platform{3.0, 5.0, -1.0, 1.0, 0.5};
  const Flight f = test::simulate(test::square(kRestZ, 1.5, 6.0, 10.0, 1.0), 14.0, cfg, p, 5);
  const PlatformPass r = fly_over(f, p, 4.5, 4.6, 6.5, 6.6);
  const State& s = r.final_state;
  EXPECT_EQ(s.counters.terrain_resets, 2);  // onto and off
  EXPECT_NEAR(r.terrain_on_platform, 0.5, 0.05);
  EXPECT_NEAR(r.terrain_after, 0.0, 0.05);
  EXPECT_LT(r.max_z_error, 0.1);
  EXPECT_GT(s.counters.count(Sensor::kRange, Outcome::kGate), 0);
}

TEST(EstimatorTest, PaperPlatformAIsAStepOfTheTerrainNotAPullOnTheHeight) {
  // Regression: the 10.9 cm of the paper's platform a is within the chi-square gate of a reading
  // at 1.6 m (1 cm + 1 %, 5 sigma), so its readings were fused and pulled the height down by
  // about the platform's height (the vehicle climbed to hold it). The step gate refuses them and
  // they reset the terrain. The flow sees the floor all along (the platform small in the view).
  const EstimatorParams p = default_params();
  SensorConfig cfg;
  cfg.range_rate_hz = 100;  // the simulator's TFmini
  cfg.platform = test::Platform{3.0, 3.4, -1.0, 1.0, 0.109};
  cfg.flow_sees_floor = true;
  const Flight f = test::simulate(test::square(kRestZ, 1.6, 6.0, 10.0, 0.3), 25.0, cfg, p, 5);
  const PlatformPass r = fly_over(f, p, 3.25, 3.3, 4.0, 4.1);
  const State& s = r.final_state;
  EXPECT_EQ(s.counters.terrain_resets, 2);  // onto and off
  EXPECT_NEAR(r.terrain_on_platform, 0.109, 0.02);
  EXPECT_NEAR(r.terrain_after, 0.0, 0.01);  // back on the floor: height 0 again
  EXPECT_LT(r.max_z_error, 0.02);
  EXPECT_GT(s.counters.flow_on_floor, 0);  // over the platform, the floor fitted the flow
}

TEST(EstimatorTest, ABeamGoingBackAndForthOverAnEdgeIsNoStepAndMovesNothing) {
  // Hovering over the platform's edge, every other reading sees its top (10.9 cm up): those are
  // refused, the floor's are fused, the terrain is not reset and the height does not move.
  const EstimatorParams p = default_params();
  SensorConfig cfg;
  cfg.range_rate_hz = 100;
  Flight f = test::simulate(test::hover(kRestZ, 1.5), 12.0, cfg, p, 9);
  int k = 0;
  for (auto& in : f.inputs)
    if (in.kind == test::Kind::kRange && in.range.utime > kT0 + 5'000'000 && ++k % 2 == 0)
      in.range.range_m -= 0.109;
  Estimator est(p);
  double max_z_error = 0;
  for (const auto& in : f.inputs) {
    test::feed(est, in);
    if (in.kind != test::Kind::kImu || !est.initialised()) continue;
    const State s = est.state();
    max_z_error = std::max(max_z_error, std::abs(s.p_W_B.z() - truth_at(f, s.utime).p_W_B.z()));
  }
  const State s = est.state();
  EXPECT_EQ(s.counters.terrain_resets, 0);
  EXPECT_NEAR(s.terrain_height_m, 0.0, 0.01);
  EXPECT_LT(max_z_error, 0.02);
  EXPECT_GT(s.counters.count(Sensor::kRange, Outcome::kGate), 300);
}

// ---- Gating

TEST(EstimatorTest, AnOutlierOfEachSensorIsGatedAndChangesNothing) {
  const EstimatorParams p = default_params(1.2);
  const Flight f = test::simulate(test::hover(1.2, 1.2), 8.0, SensorConfig{}, p, 3);
  Estimator clean = fly(f, p);
  Estimator dirty = fly(f, p);
  const State s0 = clean.state();
  // Stamped on an IMU sample inside the history, so that no IMU interval is split.
  const int64_t t = s0.utime - 10 * kDtUs;
  EXPECT_EQ(dirty.add_range({t, 2.2, true}), Outcome::kGate);
  EXPECT_EQ(dirty.add_baro({t, isa_pressure_pa(1.2 + 40 + 15)}), Outcome::kGate);
  FlowSample flow;
  flow.utime_from = t - 6 * kDtUs;
  flow.utime_to = t;
  flow.t_over_d_C1 = Vector3d(0.4, 0, 0);
  flow.cov = Matrix3d::Identity() * 1e-5;
  flow.inliers = 50;
  EXPECT_EQ(dirty.add_flow(flow), Outcome::kGate);
  const State s1 = dirty.state();
  EXPECT_EQ(s1.counters.count(Sensor::kRange, Outcome::kGate) -
                s0.counters.count(Sensor::kRange, Outcome::kGate),
            1);
  EXPECT_EQ(s1.counters.count(Sensor::kBaro, Outcome::kGate) -
                s0.counters.count(Sensor::kBaro, Outcome::kGate),
            1);
  EXPECT_EQ(s1.counters.count(Sensor::kFlow, Outcome::kGate) -
                s0.counters.count(Sensor::kFlow, Outcome::kGate),
            1);
  expect_same_estimate(s0, s1);
}

// ---- Delayed measurements and replay

TEST(EstimatorTest, DelayedMeasurementsGiveTheSameBitsAsOnTimeOnes) {
  const EstimatorParams p = default_params();
  SensorConfig late;  // range 20 ms, baro 30 ms, flow 50 ms after their stamps
  SensorConfig on_time = late;
  on_time.range_delay_s = on_time.baro_delay_s = on_time.flow_delay_s = 0.0;
  const auto traj = test::figure(kRestZ, 1.5, 6.0);
  const Flight f_late = test::simulate(traj, 12.0, late, p, 21);
  const Flight f_on_time = test::simulate(traj, 12.0, on_time, p, 21);
  const Estimator a = fly(f_on_time, p);
  const Estimator b = fly(f_late, p);
  const State sa = a.state(), sb = b.state();
  expect_same_estimate(sa, sb);
  EXPECT_GT(sb.counters.replays, 1000);
  // Around the alignment a late sample may be too old where an early one was not yet
  // welcome; after it every sample gets the same verdict.
  for (int sensor = 1; sensor < kSensorCount; ++sensor)
    for (int o = 0; o < kOutcomeCount; ++o) {
      if (Outcome(o) == Outcome::kTooOld || Outcome(o) == Outcome::kNotInitialised) continue;
      EXPECT_EQ(sa.counters.by_outcome[sensor][o], sb.counters.by_outcome[sensor][o])
          << to_string(Sensor(sensor)) << " " << to_string(Outcome(o));
    }
}

TEST(EstimatorTest, TheSameInputsTwiceGiveBitIdenticalStates) {
  const EstimatorParams p = default_params();
  const Flight f = test::simulate(test::figure(kRestZ, 1.5, 6.0), 10.0, SensorConfig{}, p, 8);
  const State a = fly(f, p).state();
  const State b = fly(f, p).state();
  expect_same_estimate(a, b);
  EXPECT_EQ(a.counters.by_outcome, b.counters.by_outcome);
  EXPECT_EQ(a.counters.replays, b.counters.replays);
}

// ---- Bad inputs

TEST(EstimatorTest, BadInputsAreCountedAndDroppedWithoutTouchingTheEstimate) {
  const EstimatorParams p = default_params(1.2);
  const Flight f = test::simulate(test::hover(1.2, 1.2), 5.0, SensorConfig{}, p, 9);
  Estimator clean = fly(f, p);
  Estimator dirty = fly(f, p);
  const State s0 = clean.state();
  const int64_t now = s0.utime;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const double g = p.gravity_mps2;

  EXPECT_EQ(dirty.add_imu({now + kDtUs, Vector3d(nan, 0, g), Vector3d::Zero()}),
            Outcome::kNonFinite);
  EXPECT_EQ(dirty.add_imu({now + kDtUs, Vector3d(0, 0, g), Vector3d(0, inf, 0)}),
            Outcome::kNonFinite);
  EXPECT_EQ(dirty.add_imu({now + kDtUs, Vector3d(0, 0, 1e4), Vector3d::Zero()}), Outcome::kAbsurd);
  EXPECT_EQ(dirty.add_imu({now + kDtUs, Vector3d(0, 0, g), Vector3d(100, 0, 0)}), Outcome::kAbsurd);
  EXPECT_EQ(dirty.add_imu({now, Vector3d(0, 0, g), Vector3d::Zero()}), Outcome::kOutOfOrder);
  EXPECT_EQ(dirty.add_imu({now - 3 * kDtUs, Vector3d(0, 0, g), Vector3d::Zero()}),
            Outcome::kOutOfOrder);
  EXPECT_EQ(dirty.add_imu({-5, Vector3d(0, 0, g), Vector3d::Zero()}), Outcome::kAbsurd);

  EXPECT_EQ(dirty.add_range({now, nan, true}), Outcome::kNonFinite);
  EXPECT_EQ(dirty.add_range({now, 1.1, false}), Outcome::kInvalid);
  EXPECT_EQ(dirty.add_range({now, 0.02, true}), Outcome::kOutOfRange);
  EXPECT_EQ(dirty.add_range({now, 50.0, true}), Outcome::kOutOfRange);
  EXPECT_EQ(dirty.add_range({now - 2'000'000, 1.1, true}), Outcome::kTooOld);
  EXPECT_EQ(dirty.add_range({now + 5'000'000, 1.1, true}), Outcome::kTooNew);
  EXPECT_EQ(dirty.add_range({0, 1.1, true}), Outcome::kAbsurd);

  EXPECT_EQ(dirty.add_baro({now, nan}), Outcome::kNonFinite);
  EXPECT_EQ(dirty.add_baro({now, 5000.0}), Outcome::kAbsurd);
  EXPECT_EQ(dirty.add_baro({now - 2'000'000, 100000.0}), Outcome::kTooOld);

  FlowSample good;
  good.utime_from = now - 8 * kDtUs;
  good.utime_to = now;
  good.cov = Matrix3d::Identity() * 1e-5;
  good.inliers = 50;
  FlowSample bad = good;
  bad.t_over_d_C1.x() = nan;
  EXPECT_EQ(dirty.add_flow(bad), Outcome::kNonFinite);
  bad = good;
  bad.cov(0, 1) = inf;
  EXPECT_EQ(dirty.add_flow(bad), Outcome::kNonFinite);
  bad = good;
  bad.cov(0, 1) = 1e-3;  // not symmetric
  EXPECT_EQ(dirty.add_flow(bad), Outcome::kAbsurd);
  bad = good;
  bad.cov = -Matrix3d::Identity();
  EXPECT_EQ(dirty.add_flow(bad), Outcome::kAbsurd);
  bad = good;
  bad.utime_to = bad.utime_from;
  EXPECT_EQ(dirty.add_flow(bad), Outcome::kAbsurd);
  bad = good;
  bad.t_over_d_C1 = Vector3d(100, 0, 0);
  EXPECT_EQ(dirty.add_flow(bad), Outcome::kAbsurd);
  bad = good;
  bad.inliers = 3;
  EXPECT_EQ(dirty.add_flow(bad), Outcome::kTooFewInliers);
  bad = good;
  bad.utime_from = now - 1'000'000;
  EXPECT_EQ(dirty.add_flow(bad), Outcome::kGeometry);  // longer than max_span_s
  bad = good;
  bad.utime_from = now - 700'000;
  bad.utime_to = now - 600'000;
  EXPECT_EQ(dirty.add_flow(bad), Outcome::kTooOld);

  const State s1 = dirty.state();
  expect_same_estimate(s0, s1);
  EXPECT_EQ(s1.counters.count(Sensor::kImu, Outcome::kNonFinite), 2);
  EXPECT_EQ(s1.counters.count(Sensor::kImu, Outcome::kAbsurd), 3);
  EXPECT_EQ(s1.counters.count(Sensor::kImu, Outcome::kOutOfOrder), 2);
  EXPECT_EQ(s1.counters.count(Sensor::kRange, Outcome::kOutOfRange) -
                s0.counters.count(Sensor::kRange, Outcome::kOutOfRange),
            2);
  EXPECT_EQ(s1.counters.count(Sensor::kFlow, Outcome::kAbsurd), 4);
  // And it goes on: the next sample is fused as usual.
  EXPECT_EQ(dirty.add_imu({now + kDtUs, Vector3d(0, 0, g), Vector3d::Zero()}), Outcome::kFused);
}

TEST(EstimatorTest, GarbageAmongTheInputsNeverCrashesNorCorruptsTheEstimate) {
  // A hover with a third of the inputs spoiled: non-finite, huge or negative values, IMU stamps
  // going back, measurement stamps anywhere within +-5 s, random covariances, repeats.
  const EstimatorParams p = default_params(1.2);
  const Flight f = test::simulate(test::hover(1.2, 1.2), 12.0, SensorConfig{}, p, 4);
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  auto junk = [&] {
    const double r = U(rng);
    return r < 0.2 ? nan : r < 0.3 ? -inf : r < 0.5 ? 1e9 * (U(rng) - 0.5) : 40 * (U(rng) - 0.5);
  };
  Estimator est(p);
  int spoiled = 0;
  for (test::Input in : f.inputs) {
    if (U(rng) < 0.33) {
      ++spoiled;
      const int64_t jitter = static_cast<int64_t>((U(rng) - 0.5) * 10e6);
      switch (in.kind) {
        case test::Kind::kImu:
          if (U(rng) < 0.5)
            in.imu.accel_B[rng() % 3] = U(rng) < 0.5 ? nan : 1e6;
          else
            in.imu.utime -= static_cast<int64_t>(U(rng) * 1e6);
          break;
        case test::Kind::kRange:
          in.range.range_m = junk();
          in.range.utime += jitter;
          in.range.valid = U(rng) < 0.8;
          break;
        case test::Kind::kBaro:
          in.baro.pressure_pa = U(rng) < 0.5 ? junk() : 30000 + U(rng) * 80000;
          in.baro.utime += U(rng) < 0.5 ? jitter : 0;
          break;
        case test::Kind::kFlow:
          in.flow.t_over_d_C1[rng() % 3] = junk();
          in.flow.cov(rng() % 3, rng() % 3) = junk();
          in.flow.utime_from += U(rng) < 0.3 ? jitter : 0;
          in.flow.inliers = static_cast<int>(rng() % 200) - 50;
          break;
      }
    }
    test::feed(est, in);
    if (U(rng) < 0.05) test::feed(est, in);  // a repeated message
    const State s = est.state();
    ASSERT_TRUE(s.p_W_B.allFinite() && s.v_W_B.allFinite() && s.q_WB.coeffs().allFinite() &&
                s.cov.allFinite());
  }
  const State s = est.state();
  ASSERT_TRUE(s.initialised);
  const test::Truth& truth = truth_at(f, s.utime);
  EXPECT_LT((s.p_W_B - truth.p_W_B).norm(), 0.3) << s.p_W_B.transpose();
  EXPECT_LT(s.v_W_B.norm(), 0.1);
  EXPECT_GT(spoiled, 1000);
  EXPECT_GT(s.counters.count(Sensor::kRange, Outcome::kDuplicate) +
                s.counters.count(Sensor::kBaro, Outcome::kDuplicate) +
                s.counters.count(Sensor::kFlow, Outcome::kDuplicate),
            0);
}

TEST(EstimatorTest, MoreOverlappingFlowSamplesThanClonesAreRefused) {
  const EstimatorParams p = default_params(1.2);
  Estimator est(p);
  int64_t t = align(est);
  for (int i = 0; i < 20; ++i) est.add_imu(at_rest(t += kDtUs, p));
  // Four samples that all span the future: each needs its own clone until utime_to.
  for (int i = 0; i < kMaxClones + 1; ++i) {
    FlowSample f;
    f.utime_from = t - (10 - i) * kDtUs;
    f.utime_to = t + (10 + i) * kDtUs;
    f.cov = Matrix3d::Identity() * 1e-4;
    f.inliers = 50;
    EXPECT_EQ(est.add_flow(f), Outcome::kQueued);
  }
  for (int i = 0; i < 20; ++i) est.add_imu(at_rest(t += kDtUs, p));
  const State s = est.state();
  EXPECT_EQ(s.counters.count(Sensor::kFlow, Outcome::kNoClone), 1);
  EXPECT_EQ(s.counters.fused(Sensor::kFlow), kMaxClones);
}

TEST(EstimatorTest, TheFirstBaroReadingSetsTheOffsetWithoutMovingTheHeight) {
  const EstimatorParams p = default_params();
  Estimator est(p);
  int64_t t = align(est);
  est.add_imu(at_rest(t += kDtUs, p));
  const State before = est.state();
  EXPECT_EQ(est.add_baro({t, isa_pressure_pa(412.0)}), Outcome::kFused);
  const State after = est.state();
  EXPECT_NEAR(after.baro_offset_m, 412.0 - kRestZ, 1e-6);
  expect_same_estimate_but_baro(before, after);
  // Later readings are fused against it; one 3 m off is refused.
  est.add_imu(at_rest(t += kDtUs, p));
  EXPECT_EQ(est.add_baro({t, isa_pressure_pa(412.05)}), Outcome::kFused);
  est.add_imu(at_rest(t += kDtUs, p));
  EXPECT_EQ(est.add_baro({t, isa_pressure_pa(415.0)}), Outcome::kGate);
}

TEST(EstimatorTest, ABadFirstBaroReadingIsOutlivedByAnOffsetReset) {
  // The first reading after the alignment is 30 m off: every good one after it is refused until
  // baro.reset_after_s has passed; then the offset starts over and the baro is fused again.
  const EstimatorParams p = default_params(1.2);
  const Flight f = test::simulate(test::hover(1.2, 1.2), 8.0, SensorConfig{}, p, 14);
  Estimator est(p);
  int64_t init_utime = 0, bad_utime = 0;
  for (const auto& in : f.inputs) {
    if (est.initialised() && init_utime == 0) init_utime = est.state().utime;
    if (bad_utime == 0 && init_utime != 0 && est.state().utime >= init_utime + 5 * kDtUs) {
      bad_utime = est.state().utime;
      EXPECT_EQ(est.add_baro({bad_utime, isa_pressure_pa(1.2 + 40 + 30)}), Outcome::kFused);
    }
    // The good readings up to the bad one's stamp never come.
    if (in.kind == test::Kind::kBaro && (bad_utime == 0 || in.baro.utime <= bad_utime)) continue;
    test::feed(est, in);
  }
  const State s = est.state();
  EXPECT_EQ(s.counters.baro_resets, 1);
  const int64_t gated = s.counters.count(Sensor::kBaro, Outcome::kGate);
  EXPECT_GE(gated, 2.0 * 25 - 3);
  EXPECT_LE(gated, 2.0 * 25 + 3);
  EXPECT_NEAR(s.baro_offset_m, 40.0, 0.3);
  EXPECT_FALSE(s.health_reasons & kNoBaro);
  EXPECT_NEAR(s.p_W_B.z(), 1.2, 0.05);
}

TEST(EstimatorTest, AFlowErrorAsAVelocityKeepsTheTakeOffsFlowFused) {
  // The front end claims a sigma of a tenth of a mm/s at 1 m (its residuals over many points),
  // and its samples carry 3 mm/s the claim does not hold, as its samples over the simulator's
  // floor do. Near the floor that error is a large t/d: the filter's noise floor, a velocity
  // (sigma_floor_mps), keeps the take-off's samples passing its gate, where a fixed t/d floor
  // makes the filter sure of the first samples and then refuses the climb's.
  const EstimatorParams p = default_params(1.2);
  SensorConfig cfg;
  cfg.flow_sigma = 3e-6;
  cfg.flow_velocity_error_W_mps = Vector3d(0.003, -0.002, 0.0);
  const Flight f = test::simulate(test::hover(kRestZ, 1.2), 8.0, cfg, p, 3);
  const Estimator est = fly(f, p);
  const State s = est.state();
  EXPECT_EQ(s.health, Health::kOk) << health_reasons_text(s.health_reasons);
  const int64_t fused = s.counters.fused(Sensor::kFlow);
  const int64_t gated = s.counters.count(Sensor::kFlow, Outcome::kGate);
  std::printf("flow fused %lld, gated %lld\n", static_cast<long long>(fused),
              static_cast<long long>(gated));
  EXPECT_LT(gated, fused / 4);  // a fixed t/d floor of 1e-4 refuses nearly as many as it fuses
  EXPECT_LT((s.v_W_B - f.truth.back().v_W_B).head<2>().norm(), 0.01);
}

TEST(EstimatorTest, OnTheFloorNoRangeIsExpectedAndHealthIsOk) {
  // Resting on the floor: the rangefinder sits in its blind zone (readings invalid), the flow
  // sees no motion, the baro reads the take-off altitude.
  const EstimatorParams p = default_params();
  const Flight f = test::simulate(test::hover(kRestZ, kRestZ), 5.0, SensorConfig{}, p, 6);
  const Estimator est = fly(f, p);
  const State s = est.state();
  EXPECT_EQ(s.health, Health::kOk) << health_reasons_text(s.health_reasons);
  EXPECT_EQ(s.counters.fused(Sensor::kRange), 0);
  EXPECT_GT(s.counters.count(Sensor::kRange, Outcome::kInvalid), 100);
  EXPECT_LT((s.p_W_B - Vector3d(0, 0, kRestZ)).norm(), 0.02);
}

// ---- Health

TEST(EstimatorTest, ARangefinderSilentInFlightIsFlaggedThoughRestingOneIsNot) {
  // Hovering at 1.2 m the rangefinder's beam is a metre past its blind zone, far beyond the
  // estimate's doubt about its height: its silence is a fault (compare the resting vehicle of
  // OnTheFloorNoRangeIsExpectedAndHealthIsOk).
  const EstimatorParams p = default_params(1.2);
  SensorConfig cfg;
  cfg.range = false;
  const Flight f = test::simulate(test::hover(1.2, 1.2), 4.0, cfg, p, 2);
  const State s = fly(f, p).state();
  EXPECT_EQ(s.health, Health::kDegraded);
  EXPECT_TRUE(s.health_reasons & kNoRange) << health_reasons_text(s.health_reasons);
}

TEST(EstimatorTest, HealthDegradesWithoutFlowAndIsLostWhenTheImuStops) {
  const EstimatorParams p = default_params(1.2);
  SensorConfig cfg;
  cfg.flow = false;
  const Flight f = test::simulate(test::hover(1.2, 1.2), 4.0, cfg, p, 2);
  Estimator est = fly(f, p);
  State s = est.state();
  EXPECT_EQ(s.health, Health::kDegraded);
  EXPECT_TRUE(s.health_reasons & kNoFlow);
  EXPECT_FALSE(s.health_reasons & kNoRange);
  EXPECT_FALSE(s.health_reasons & kNoBaro);
  // One sample stamped far ahead is refused and tells nothing about the IMU.
  EXPECT_EQ(est.add_range({s.utime + 3'600'000'000LL, 1.15, true}), Outcome::kTooNew);
  EXPECT_FALSE(est.state().health_reasons & kImuStopped);
  // The IMU stops; the rangefinder goes on.
  for (int i = 1; i <= 30; ++i) est.add_range({s.utime + i * 20000, 1.15, true});
  s = est.state();
  EXPECT_EQ(s.health, Health::kLost);
  EXPECT_TRUE(s.health_reasons & kImuStopped);
}

TEST(EstimatorTest, ARunOfFlowFromAPlaneTheModelLacksIsFollowedLooselyNotLeftToTheImu) {
  // For 3 s of a 1 m/s square the front end's plane is 12 % nearer than the floor the
  // rangefinder sees (a top filling part of the view over a sparse floor): t/d 1 / 0.88 of the
  // floor's, twenty of the samples' sigmas off. The gate refuses them; after half the flow timeout
  // of refusals each is fused with its noise inflated to its innovation, so the estimate stays
  // within the plane's bias of the truth and never goes DEGRADED for want of flow, as it did when
  // the refused samples left it to the IMU.
  const EstimatorParams p = default_params();
  SensorConfig cfg;
  cfg.flow_sigma = 3e-4;
  const double start_s = 6.0, side_m = 2.0, speed_mps = 1.0;
  const Flight f = test::simulate(test::square(kRestZ, 1.2, start_s, side_m, speed_mps),
                                  start_s + test::square_duration_s(side_m, speed_mps), cfg, p, 4);
  const int64_t bias_from = kT0 + 8'000'000, bias_to = kT0 + 11'000'000;
  Estimator est(p);
  double worst_v_error = 0, worst_v_error_after = 0;
  bool degraded_for_flow = false;
  for (test::Input in : f.inputs) {
    if (in.kind == test::Kind::kFlow && in.flow.utime_to >= bias_from && in.flow.utime_to < bias_to)
      in.flow.t_over_d_C1 /= 0.88;
    test::feed(est, in);
    if (in.kind != test::Kind::kImu || !est.initialised()) continue;
    const State st = est.state();
    if (st.utime < kT0 + 5'000'000) continue;  // aligned, climbed
    degraded_for_flow |= (st.health_reasons & kNoFlow) != 0;
    const double e = (st.v_W_B - truth_at(f, st.utime).v_W_B).norm();
    worst_v_error = std::max(worst_v_error, e);
    if (st.utime > bias_to + 1'000'000) worst_v_error_after = std::max(worst_v_error_after, e);
  }
  const State st = est.state();
  std::printf(
      "flow refused %lld, inflated %lld; velocity error worst %.3f, a second after %.3f m/s\n",
      static_cast<long long>(st.counters.count(Sensor::kFlow, Outcome::kGate)),
      static_cast<long long>(st.counters.flow_inflated), worst_v_error, worst_v_error_after);
  EXPECT_GT(st.counters.count(Sensor::kFlow, Outcome::kGate), 0);
  EXPECT_GT(st.counters.flow_inflated, 0);
  EXPECT_FALSE(degraded_for_flow);
  EXPECT_LT(worst_v_error, 0.15 * speed_mps);  // the plane's bias: 12 %
  EXPECT_LT(worst_v_error_after, 0.05);
  EXPECT_EQ(st.health, Health::kOk);
}

// Flow samples of 4 s of `f` replaced by a platform's motion under the camera: the truth's t/d
// less the platform's velocity (relative, camera axes) over the camera's height, the floor's own
// as the sample's second motion when floor_as_second. The filter's worst velocity error from 5 s
// on, and whether the estimate went DEGRADED for want of flow.
struct PlatformRun {
  State end;
  double worst_v_error = 0;
  bool degraded_for_flow = false;
};
PlatformRun fly_over_platform(const Flight& f, const EstimatorParams& p, const Vector3d& v_rel,
                              double height_m, bool floor_as_second) {
  const int64_t from = kT0 + 6'000'000, to = kT0 + 10'000'000;
  Estimator est(p);
  PlatformRun run;
  for (test::Input in : f.inputs) {
    if (in.kind == test::Kind::kFlow && in.flow.utime_to >= from && in.flow.utime_to < to) {
      const FlowSample floor = in.flow;
      const double dt = 1e-6 * static_cast<double>(in.flow.utime_to - in.flow.utime_from);
      in.flow.t_over_d_C1 += v_rel * dt / height_m;
      if (floor_as_second)
        in.flow.others.push_back(
            {floor.t_over_d_C1, floor.cov, 40, floor.J_rotation, floor.J_normal});
    }
    test::feed(est, in);
    if (in.kind != test::Kind::kImu || !est.initialised()) continue;
    const State st = est.state();
    if (st.utime < kT0 + 5'000'000) continue;
    run.degraded_for_flow |= (st.health_reasons & kNoFlow) != 0;
    run.worst_v_error =
        std::max(run.worst_v_error, (st.v_W_B - truth_at(f, st.utime).v_W_B).norm());
  }
  run.end = est.state();
  return run;
}

TEST(EstimatorTest, APlatformsMotionOutnumberingTheFloorsIsNotFollowed) {
  // For 4 s of a hover the front end's first motion is a platform's moving at 0.3 m/s under the
  // camera (its features outnumber a sparse floor's) and the floor's is its second: the filter
  // fuses the floor's, which its prediction explains.
  const EstimatorParams p = default_params(1.2);
  SensorConfig cfg;
  cfg.flow_sigma = 3e-4;
  const Flight f = test::simulate(test::hover(1.2, 1.2), 12.0, cfg, p, 6);
  const PlatformRun run = fly_over_platform(f, p, Vector3d(0.3, 0, 0), 1.2, true);
  std::printf("velocity error worst %.3f m/s, %lld samples on the second motion\n",
              run.worst_v_error, static_cast<long long>(run.end.counters.flow_second));
  EXPECT_GT(run.end.counters.flow_second, 100);  // 4 s at 30 Hz
  EXPECT_EQ(run.end.counters.flow_inflated, 0);
  EXPECT_LT(run.worst_v_error, 0.03);
  EXPECT_FALSE(run.degraded_for_flow);
  EXPECT_EQ(run.end.health, Health::kOk);
}

struct MovingTopRun {
  State end;
  State at_start_of_top_alone, at_end_of_top_alone;
  double worst_v_error = 0;  // while the top's motion was the only one in view
  /// The worst error of the vehicle's velocity relative to the top's over the same time.
  double worst_relative_v_error = 0;
  int64_t inflated_alone = 0;
};
/// The first leg of a square at 1.2 m (+x, 1 m/s) over a 0.3 m top from x = 3 m to 7 m that moves
/// at top_v_W: first the floor's motion with the top's as the second, then for 2 s the top's
/// alone (filling the view), the rangefinder on the top all along.
MovingTopRun fly_over_moving_top(const Vector2d& top_v_W) {
  const EstimatorParams p = default_params();
  SensorConfig cfg;
  cfg.flow_sigma = 3e-4;
  cfg.platform = test::Platform{3.0, 7.0, -1.0, 1.0, 0.3};
  cfg.flow_sees_floor = true;
  const Flight f = test::simulate(test::square(kRestZ, 1.2, 6.0, 10.0, 1.0), 16.0, cfg, p, 8);
  const int64_t both_from = kT0 + 9'800'000, alone_from = kT0 + 11'300'000,
                alone_to = kT0 + 13'300'000;
  const Matrix3d R_CB = p.flow.R_BC().transpose();
  Estimator est(p);
  MovingTopRun run;
  for (test::Input in : f.inputs) {
    if (in.kind == test::Kind::kFlow && in.flow.utime_to >= both_from &&
        in.flow.utime_to < alone_to) {
      // The top's motion from the floor's: the same displacement less the top's, over the
      // camera's height above the top instead of above the floor.
      const test::Truth& k = truth_at(f, in.flow.utime_from);
      const double d_floor = (k.p_W_B + k.q_WB * p.flow.t_B_C_m).z();
      const double dt = 1e-6 * static_cast<double>(in.flow.utime_to - in.flow.utime_from);
      const Vector3d top_W(top_v_W.x() * dt, top_v_W.y() * dt, 0.0);
      const FlowMotion top{
          (in.flow.t_over_d_C1 * d_floor - R_CB * (k.q_WB.conjugate() * top_W)) / (d_floor - 0.3),
          in.flow.cov, 40, in.flow.J_rotation, in.flow.J_normal};
      if (in.flow.utime_to < alone_from) {
        in.flow.others.push_back(top);
      } else {
        in.flow.t_over_d_C1 = top.t_over_d_C1;
      }
    }
    test::feed(est, in);
    if (in.kind != test::Kind::kImu || !est.initialised()) continue;
    const State st = est.state();
    if (st.utime < alone_from) run.at_start_of_top_alone = st;
    if (st.utime < alone_from || st.utime >= alone_to) continue;
    const Vector2d v_error = (st.v_W_B - truth_at(f, st.utime).v_W_B).head<2>();
    run.worst_v_error = std::max(run.worst_v_error, v_error.norm());
    run.worst_relative_v_error =
        std::max(run.worst_relative_v_error, (v_error - (st.top_velocity_W - top_v_W)).norm());
    run.at_end_of_top_alone = st;
  }
  run.end = est.state();
  run.inflated_alone = run.at_end_of_top_alone.counters.flow_inflated;
  return run;
}

TEST(EstimatorTest, ATopMovingUnderTheCameraIsMeasuredAndItsMotionAloneFollowedRelativeToIt) {
  // While the floor's motion and a moving top's are both in view the top's measures its
  // velocity; when the top then fills the view, its motion is the camera's relative to it, not
  // the floor's: the estimate's velocity stays the vehicle's. Without the top's velocity the
  // filter refused those samples, then fused them inflated as the floor's and took on the top's
  // velocity.
  const MovingTopRun run = fly_over_moving_top(Vector2d(0.3, 0.1));
  const State& measured = run.at_start_of_top_alone;
  const State& st = run.at_end_of_top_alone;
  std::printf(
      "top velocity %.3f %.3f measured (moving %d); with the top alone: worst velocity "
      "error %.3f m/s, relative to the top %.3f m/s, %lld fused relative to it, %lld "
      "inflated\n",
      measured.top_velocity_W.x(), measured.top_velocity_W.y(), measured.top_moving ? 1 : 0,
      run.worst_v_error, run.worst_relative_v_error, static_cast<long long>(st.counters.flow_top),
      static_cast<long long>(run.inflated_alone));
  EXPECT_TRUE(measured.top_moving);
  EXPECT_NEAR(measured.top_velocity_W.x(), 0.3, 0.02);
  EXPECT_NEAR(measured.top_velocity_W.y(), 0.1, 0.02);
  EXPECT_TRUE(st.top_moving);
  EXPECT_GT(st.counters.flow_top, 90);  // 1.5 s of both and 2 s alone, at 30 Hz
  // Alone, the top's motion fixes the vehicle's velocity relative to the top's, to the top's
  // velocity's own noise (its state walks as fast as a top may turn); the two drift together on
  // the IMU, as any velocity without a still reference.
  EXPECT_LT(run.worst_relative_v_error, 0.03);
  EXPECT_LT(run.worst_v_error, 0.05);
  EXPECT_EQ(run.inflated_alone, 0);
  EXPECT_EQ(run.end.health, Health::kOk) << health_reasons_text(run.end.health_reasons);
}

TEST(EstimatorTest, AStillTopIsNotTakenForAMovingOne) {
  // The same flight over a top standing still: its motion is the floor's but for the heights,
  // its velocity measured as zero, and the top's motion alone is then judged as a still plane's.
  const MovingTopRun run = fly_over_moving_top(Vector2d::Zero());
  const State& st = run.at_end_of_top_alone;
  EXPECT_FALSE(run.at_start_of_top_alone.top_moving);
  EXPECT_LT(run.at_start_of_top_alone.top_velocity_W.norm(), 0.02);
  EXPECT_FALSE(st.top_moving);
  EXPECT_LT(run.worst_v_error, 0.05);
  EXPECT_EQ(run.end.health, Health::kOk) << health_reasons_text(run.end.health_reasons);
}

TEST(EstimatorTest, ASecondFlowMotionThatIsNotOneIsLeftOut) {
  // A second motion with a broken covariance or too few inliers is dropped; the sample's own
  // motion is fused as if it came alone.
  const EstimatorParams p = default_params(1.2);
  const Flight f = test::simulate(test::hover(1.2, 1.2), 6.0, SensorConfig{}, p, 7);
  Estimator alone(p), with_bad(p);
  for (test::Input in : f.inputs) {
    test::feed(alone, in);
    if (in.kind == test::Kind::kFlow) {
      FlowMotion nan_cov{in.flow.t_over_d_C1 * 2, Matrix3d::Constant(NAN), 40, Matrix3d::Zero(),
                         Matrix3d::Zero()};
      FlowMotion few{Vector3d(0.2, 0, 0), in.flow.cov, p.flow.min_inliers - 1, Matrix3d::Zero(),
                     Matrix3d::Zero()};
      in.flow.others = {nan_cov, few};
    }
    test::feed(with_bad, in);
  }
  expect_same_estimate(alone.state(), with_bad.state());
  EXPECT_EQ(with_bad.state().counters.flow_second, 0);
}

TEST(EstimatorTest, AVelocityTheFlowRefusesForItsTimeoutIsSetToTheFlows) {
  // For a second of a hover the front end gives no flow (a blank floor) while the IMU carries an
  // error its model lacks (0.4 m/s^2 along x: a knock, a mis-scaled axis): the estimate ends the
  // second 0.4 m/s off and sure of it, so that the floor's flow, back, is refused, and inflating
  // its noise does not pass it either (the state's own doubt over a frame's interval is larger).
  // Left so, the estimate stays DEGRADED and runs off. After the flow timeout of refusals, two
  // samples in a row implying the same error set the horizontal velocity to the flow's: fused
  // again at once, the position kept (no step a pose gate downstream would refuse).
  const EstimatorParams p = default_params(1.2);
  SensorConfig cfg;
  cfg.flow_sigma = 3e-4;
  const Flight f = test::simulate(test::hover(1.2, 1.2), 12.0, cfg, p, 5);
  const int64_t knock_from = kT0 + 6'000'000, knock_to = kT0 + 7'000'000;
  Estimator est(p);
  double worst_step_m = 0, v_error_at_return = 0;
  bool degraded_after_return = false;
  std::optional<Vector3d> last_p;
  for (test::Input in : f.inputs) {
    if (in.kind == test::Kind::kFlow && in.flow.utime_to >= knock_from &&
        in.flow.utime_to < knock_to)
      continue;
    if (in.kind == test::Kind::kImu && in.imu.utime >= knock_from && in.imu.utime < knock_to)
      in.imu.accel_B.x() += 0.4;
    test::feed(est, in);
    if (in.kind != test::Kind::kImu || !est.initialised()) continue;
    const State st = est.state();
    if (st.utime < kT0 + 5'000'000) continue;
    if (last_p) worst_step_m = std::max(worst_step_m, (st.p_W_B - *last_p).norm());
    last_p = st.p_W_B;
    if (st.utime < knock_to) {
      v_error_at_return = (st.v_W_B - truth_at(f, st.utime).v_W_B).norm();
      continue;
    }
    if (st.utime > knock_to + 2'000'000) degraded_after_return |= st.health != Health::kOk;
  }
  const State st = est.state();
  const double v_error = (st.v_W_B - f.truth.back().v_W_B).norm();
  std::printf(
      "velocity error %.3f m/s at the flow's return, %.3f at the end; resets %lld, "
      "refused %lld, inflated %lld; largest position step %.4f m\n",
      v_error_at_return, v_error, static_cast<long long>(st.counters.flow_velocity_resets),
      static_cast<long long>(st.counters.count(Sensor::kFlow, Outcome::kGate)),
      static_cast<long long>(st.counters.flow_inflated), worst_step_m);
  EXPECT_GT(v_error_at_return, 0.3);
  EXPECT_GE(st.counters.flow_velocity_resets, 1);
  EXPECT_LE(st.counters.flow_velocity_resets, 2);
  EXPECT_LT(v_error, 0.03);
  EXPECT_FALSE(degraded_after_return);
  EXPECT_EQ(st.health, Health::kOk) << health_reasons_text(st.health_reasons);
  // The reset is applied at the sample's time and the state run forward from there: the position
  // now moves by the velocity's change over the flow's delay (0.4 m/s over 50 ms), well inside
  // the 5 cm a pose gate downstream allows; a reset of the position would be 0.2 m.
  EXPECT_LT(worst_step_m, 0.4 * cfg.flow_delay_s + 0.005);
}

TEST(EstimatorTest, AFlowOutlierAfterSilenceIsRefusedNotInflated) {
  // A run of refusals needs refusals: one sample after a second without flow (the front end
  // starved) starts a run and is refused, however long since the flow was last fused.
  const EstimatorParams p = default_params(1.2);
  const Flight f = test::simulate(test::hover(1.2, 1.2), 8.0, SensorConfig{}, p, 3);
  Estimator est(p);
  int64_t last_flow = 0;
  for (const auto& in : f.inputs) {
    if (in.kind == test::Kind::kFlow && in.flow.utime_to > kT0 + 6'000'000) continue;
    if (in.kind == test::Kind::kFlow) last_flow = in.flow.utime_to;
    test::feed(est, in);
  }
  const State s0 = est.state();
  ASSERT_GT(s0.utime - last_flow, 1'500'000);
  FlowSample flow;
  flow.utime_to = s0.utime - 10 * kDtUs;
  flow.utime_from = flow.utime_to - 6 * kDtUs;
  flow.t_over_d_C1 = Vector3d(0.4, 0, 0);
  flow.cov = Matrix3d::Identity() * 1e-5;
  flow.inliers = 50;
  EXPECT_EQ(est.add_flow(flow), Outcome::kGate);
  EXPECT_EQ(est.state().counters.flow_inflated, 0);
  expect_same_estimate(s0, est.state());
}

TEST(EstimatorTest, AnImuGapDegradesForAWhileAndALongOneStartsOver) {
  const EstimatorParams p = default_params();
  Estimator est(p);
  int64_t t = align(est);
  for (int i = 0; i < 10; ++i) est.add_imu(at_rest(t += kDtUs, p));
  est.add_imu(at_rest(t += 100'000, p));  // 0.1 s without samples
  State s = est.state();
  EXPECT_TRUE(s.health_reasons & kImuGap);
  EXPECT_EQ(s.counters.imu_gaps, 1);
  for (int i = 0; i < 220; ++i) est.add_imu(at_rest(t += kDtUs, p));
  EXPECT_FALSE(est.state().health_reasons & kImuGap);
  est.add_imu(at_rest(t += 3'000'000, p));  // 3 s: the state cannot be bridged
  EXPECT_FALSE(est.initialised());
  EXPECT_EQ(est.state().counters.imu_gaps, 2);
  t = align(est, t);
  EXPECT_TRUE(est.initialised());
}

TEST(EstimatorTest, WithoutAidingThePositionBecomesUncertainAndTheEstimateLost) {
  const EstimatorParams p = default_params(1.2);
  Estimator est(p);
  int64_t t = align(est);
  Health worst = Health::kOk;
  for (int i = 0; i < 200 * 60 && worst != Health::kLost; ++i) {
    est.add_imu(at_rest(t += kDtUs, p));
    worst = std::max(worst, est.state().health);
  }
  const State s = est.state();
  EXPECT_EQ(s.health, Health::kLost);
  EXPECT_TRUE(s.health_reasons & (kPositionUncertain | kVelocityUncertain | kHeightUncertain));
}

}  // namespace
}  // namespace alight::estimator
