// Filter consistency (Bar-Shalom, Li, Kirubarajan, "Estimation with Applications to Tracking and
// Navigation", 2001, 5.4.2): over N seeded Monte Carlo runs of a synthetic flight with every
// sensor, the average normalised estimation error squared of position, velocity and attitude
// must lie within the two-sided 95 % chi-square bounds of N * 3 degrees of freedom over N. The
// runs differ in sensor noise, true biases, the baro offset's walk and the error of the take-off
// pose given to the filter, each drawn as the filter's parameters model them.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "common/geometry.hpp"
#include "estimator/estimator.hpp"
#include "synthetic.hpp"

namespace alight::estimator {
namespace {

/// Wilson-Hilferty approximation of the chi-square quantile (within 0.1 % for k >= 30).
double chi2_quantile(double k, double z) {
  const double c = 2.0 / (9.0 * k);
  return k * std::pow(1.0 - c + z * std::sqrt(c), 3);
}

TEST(EstimatorConsistencyTest, NeesOfPositionVelocityAttitudeWithinChiSquareBounds) {
  constexpr int kRuns = 50;
  constexpr double kDuration = 20.0;
  constexpr double kRestZ = 0.12;
  constexpr int kEvery = 20;  // IMU samples between evaluations (10 Hz)
  const auto traj = test::figure(kRestZ, 1.5, 6.0);

  std::vector<double> sum_p, sum_v, sum_a;
  std::vector<int> n_runs;
  for (int run = 0; run < kRuns; ++run) {
    EstimatorParams p;
    // What the alignment really achieves here (the truth has no mounting error and the gyro is
    // averaged over 1 s): the filter is told so, so that its covariance can be judged.
    p.init.sigma_gyro_bias_radps = 3e-4;
    p.init.sigma_roll_pitch_rad = 5e-4;
    // The synthetic floor is flat and the synthetic baro offset walks as the filter models it.
    p.range.terrain_rw = 1e-4;
    p.range.terrain_gradient = 0.0;
    std::mt19937_64 rng(1000 + run);
    std::normal_distribution<double> N;
    // The take-off pose given to the filter is off by its stated sigmas.
    p.init.p_W_B_m = Vector3d(0, 0, kRestZ) + p.init.sigma_p_m * Vector3d(N(rng), N(rng), N(rng));
    p.init.yaw_deg = p.init.sigma_yaw_rad * N(rng) * 180.0 / M_PI;
    const test::Flight f = test::simulate(traj, kDuration, test::SensorConfig{}, p, 77 + run);

    Estimator est(p);
    size_t truth_i = 0;
    int imu_count = 0, eval = 0;
    for (const auto& in : f.inputs) {
      test::feed(est, in);
      if (in.kind != test::Kind::kImu || !est.initialised() || ++imu_count % kEvery) continue;
      const State s = est.state();
      while (f.truth[truth_i].utime < s.utime) ++truth_i;
      const test::Truth& t = f.truth[truth_i];
      ASSERT_EQ(t.utime, s.utime);
      const Vector3d ep = t.p_W_B - s.p_W_B;
      const Vector3d ev = t.v_W_B - s.v_W_B;
      const Vector3d ea = test::attitude_error(s.q_WB, t.q_WB);
      if (static_cast<int>(sum_p.size()) <= eval) {
        sum_p.push_back(0), sum_v.push_back(0), sum_a.push_back(0), n_runs.push_back(0);
      }
      sum_p[eval] += ep.dot(s.cov_p().ldlt().solve(ep));
      sum_v[eval] += ev.dot(s.cov_v().ldlt().solve(ev));
      sum_a[eval] += ea.dot(s.cov_attitude().ldlt().solve(ea));
      ++n_runs[eval];
      ++eval;
    }
    // Every run aligned on the floor and was evaluated throughout; no platform, so no reset.
    const State s = est.state();
    EXPECT_EQ(s.counters.terrain_resets, 0) << "run " << run;
    EXPECT_EQ(s.health, Health::kOk)
        << "run " << run << " " << health_reasons_text(s.health_reasons);
  }

  const double lo = chi2_quantile(3.0 * kRuns, -1.959964) / kRuns;
  const double hi = chi2_quantile(3.0 * kRuns, 1.959964) / kRuns;
  auto report = [&](const char* name, const std::vector<double>& sums) {
    double mean = 0;
    int inside = 0, n = 0;
    for (size_t j = 0; j < sums.size(); ++j) {
      if (n_runs[j] != kRuns) continue;
      const double anees = sums[j] / kRuns;
      mean += anees;
      inside += anees >= lo && anees <= hi;
      ++n;
    }
    ASSERT_GT(n, 100) << name;
    mean /= n;
    std::printf("%s: average NEES %.2f (95%% bounds [%.2f, %.2f]), %d of %d times inside\n", name,
                mean, lo, hi, inside, n);
    EXPECT_GT(mean, lo) << name;
    EXPECT_LT(mean, hi) << name;
  };
  report("position", sum_p);
  report("velocity", sum_v);
  report("attitude", sum_a);
}

}  // namespace
}  // namespace alight::estimator
