// Drift of the onboard estimator on synthetic flights with IMU + rangefinder + baro +
// flow at the default noise (estimator/params.hpp; flow sigma 0.003 + the 0.002 floor per axis of
// t/d, delays 20 / 30 / 50 ms): a 60 s hover at 1.5 m, and a 10 m square at 1 m/s (1 s ramps, a
// second's pause at each corner) back to its start. For each seed: the final error of the
// estimate against the truth (horizontal, vertical, heading) and the filter's own 1-sigma;
// then the median and the largest over the seeds. A figure of the filter, not of a front end: the
// flow samples are the synthetic truth plus white noise of the stated covariance.
//
//   build/bin/estimator_drift [--seeds 10] [--first-seed 1]

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "synthetic.hpp"

using namespace alight;
using namespace alight::estimator;

namespace {

struct Drift {
  double horizontal_m, vertical_m, heading_deg, sigma_h_m, sigma_z_m;
  Health health;
};

Drift run(const test::Trajectory& traj, double duration_s, uint64_t seed) {
  EstimatorParams p;
  p.init.p_W_B_m = Vector3d(0, 0, 0.12);
  const test::Flight f = test::simulate(traj, duration_s, test::SensorConfig{}, p, seed);
  Estimator est(p);
  for (const auto& in : f.inputs) test::feed(est, in);
  const State s = est.state();
  const auto it = std::lower_bound(f.truth.begin(), f.truth.end(), s.utime,
                                   [](const test::Truth& t, int64_t u) { return t.utime < u; });
  const Vector3d e = s.p_W_B - it->p_W_B;
  const double yaw_err =
      wrap_angle(yaw_of(s.q_WB.toRotationMatrix()) - yaw_of(it->q_WB.toRotationMatrix()));
  return {e.head<2>().norm(),
          std::abs(e.z()),
          std::abs(yaw_err) * 180 / M_PI,
          std::sqrt(s.cov(0, 0) + s.cov(1, 1)),
          std::sqrt(s.cov(2, 2)),
          s.health};
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

void report(const char* name, const std::vector<Drift>& d) {
  std::vector<double> h, z, yaw, sh, sz;
  int ok = 0;
  for (const auto& x : d) {
    h.push_back(x.horizontal_m), z.push_back(x.vertical_m), yaw.push_back(x.heading_deg);
    sh.push_back(x.sigma_h_m), sz.push_back(x.sigma_z_m);
    ok += x.health == Health::kOk;
  }
  auto mx = [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); };
  std::printf(
      "%s (%zu seeds): horizontal %.3f m median, %.3f m max (filter 1-sigma %.3f m); "
      "vertical %.3f / %.3f m (sigma %.3f m); heading %.2f / %.2f deg; health OK at the "
      "end in %d\n",
      name, d.size(), median(h), mx(h), median(sh), median(z), mx(z), median(sz), median(yaw),
      mx(yaw), ok);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("alight estimator drift on synthetic flights");
  int seeds = 10, first = 1;
  app.add_option("--seeds", seeds, "flights per case")->check(CLI::Range(1, 1000));
  app.add_option("--first-seed", first, "seed of the first flight");
  CLI11_PARSE(app, argc, argv);

  constexpr double kRestZ = 0.12, kHeight = 1.5, kStart = 6.0;
  std::vector<Drift> hover, square;
  const double square_s = test::square_duration_s(10.0, 1.0);
  for (int s = first; s < first + seeds; ++s) {
    hover.push_back(run(test::hover(kRestZ, kHeight), kStart + 60.0, s));
    square.push_back(
        run(test::square(kRestZ, kHeight, kStart, 10.0, 1.0), kStart + square_s + 1.0, s));
  }
  report("hover 60 s at 1.5 m", hover);
  std::printf("square 10 m at 1 m/s (%.0f s, 40 m flown):\n  ", square_s);
  report("end point", square);
  return 0;
}
