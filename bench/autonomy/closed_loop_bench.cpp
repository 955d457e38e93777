// Closed-loop Monte Carlo: for each vehicle and each of the paper's three platforms (4.2), N
// seeded landings (platform placement and yaw, sensor noise, oracle-vision noise and outliers,
// vantage draws all follow the seed); N ingress flights. Prints per case: successes, touchdown
// lateral error (median, 90th percentile, max), mission time GO -> LANDED / DONE (median, min,
// max), final-estimate error, waypoints and rejected outliers. The oracle vision is the test
// fixture (test/autonomy/oracle_vision.hpp), not the vision pipeline: these numbers measure
// control and autonomy given measurements of the configured quality.
//
//   build-x/bin/autonomy_closed_loop_bench [--seeds 20] [--vision-rate 5] [--outliers 0.05]

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "closed_loop.hpp"
#include "common/build_paths.hpp"
#include "support/stats.hpp"

using namespace alight;
using namespace alight::autonomy;
using namespace alight::autonomy::test;

namespace {

using alight::test::quantile;

struct Summary {
  int ok = 0, n = 0, collided = 0, tipped = 0;
  std::vector<double> err_cm, time_s, est_cm, lateral_cm;
  int waypoints = 0, rejected = 0, retries = 0, spawn_tipped = 0;
};

void print(const std::string& name, const Summary& s, bool landing) {
  std::printf("%-22s %2d/%2d ok", name.c_str(), s.ok, s.n);
  if (landing) {
    std::printf("  touchdown err cm: median %.2f p90 %.2f max %.2f", quantile(s.err_cm, 0.5),
                quantile(s.err_cm, 0.9), quantile(s.err_cm, 1.0));
  } else {
    std::printf("  collided %d  max offset in wall plane cm: median %.2f max %.2f", s.collided,
                quantile(s.lateral_cm, 0.5), quantile(s.lateral_cm, 1.0));
  }
  std::printf("  mission s: median %.1f min %.1f max %.1f", quantile(s.time_s, 0.5),
              quantile(s.time_s, 0.0), quantile(s.time_s, 1.0));
  std::printf("  estimate err cm: median %.2f max %.2f", quantile(s.est_cm, 0.5),
              quantile(s.est_cm, 1.0));
  std::printf("  waypoints/run %.1f rejected/run %.2f retries %d tipped %d (at spawn %d)\n",
              s.n ? double(s.waypoints) / s.n : 0.0, s.n ? double(s.rejected) / s.n : 0.0,
              s.retries, s.tipped, s.spawn_tipped);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"closed-loop Monte Carlo of landing and ingress with oracle vision"};
  int seeds = 20;
  double rate_hz = 5.0, outliers = 0.05, sigma_xy = 0.01, sigma_z = 0.03;
  double ingress_width = 1.0, ingress_height = 0.6, ingress_span = 0.0;
  app.add_option("--seeds", seeds, "runs per case");
  app.add_option("--vision-rate", rate_hz,
                 "oracle measurements per second (paper: ~5 STARMAC, ~2 Pelican)");
  app.add_option("--outliers", outliers, "oracle outlier probability");
  app.add_option("--sigma-xy", sigma_xy, "oracle lateral noise [m]");
  app.add_option("--sigma-z", sigma_z, "oracle vertical noise [m]");
  app.add_option("--ingress-width", ingress_width, "opening width for the ingress runs [m]");
  app.add_option("--ingress-height", ingress_height, "opening height [m]");
  app.add_option("--ingress-span", ingress_span,
                 "override the STARMAC's rotor tip span for the ingress runs [m] (0: the file's)");
  bool ingress_only = false;
  app.add_flag("--ingress-only", ingress_only, "skip the landings");
  CLI11_PARSE(app, argc, argv);

  const std::string root = alight::build::source_dir();
  std::printf(
      "oracle vision: %.1f Hz, sigma_xy %.3f m, sigma_z %.3f m, outliers %.0f %%; %d seeds\n",
      rate_hz, sigma_xy, sigma_z, 100 * outliers, seeds);
  const char* only = std::getenv("BENCH_ONLY");  // e.g. "starmac/c" for a quick look
  for (const std::string vehicle : {"starmac", "pelican"}) {
    for (const std::string platform : {"a", "b", "c"}) {
      if ((only && vehicle + "/" + platform != only) || ingress_only) continue;
      Summary s;
      for (int seed = 1; seed <= seeds; ++seed) {
        ClosedLoopConfig c;
        c.vehicle_file = root + "/config/vehicles/" + vehicle + ".yaml";
        c.scenario_file = root + "/config/scenarios/landing_" + platform + ".yaml";
        c.mission = Mission::kLanding;
        c.seed = static_cast<uint64_t>(seed);
        c.vision.rate_hz = rate_hz;
        c.vision.outlier_prob = outliers;
        c.vision.sigma_xy_m = sigma_xy;
        c.vision.sigma_z_m = sigma_z;
        const auto r = fly_closed_loop(c);
        ++s.n;
        // The sim's "tipped" is sticky; a run whose random platform overlapped the start spot
        // (rotor rim on the platform at spawn) is tipped before take-off: counted apart.
        if (r.tipped_before_go) ++s.spawn_tipped;
        const bool ok = r.phase == Phase::kLanded && !r.armed &&
                        (r.tipped_before_go ? r.on_platform_top : r.landed && !r.tipped);
        if (std::getenv("BENCH_VERBOSE")) {
          std::printf("    seed %d: final %.2f td %.2f rest %.2f cm yaw %.0f\n", seed,
                      100 * r.error_at_final_descent_m, 100 * r.error_at_touchdown_m,
                      100 * r.touchdown_error_m, r.platform_yaw_rad * 180 / M_PI);
        }
        if (ok) {
          ++s.ok;
          if (r.tipped_before_go) {
            std::printf(
                "  %s/%s seed %d: sim flagged tipped at spawn (platform overlaps the start "
                "spot); landed on the platform top anyway\n",
                vehicle.c_str(), platform.c_str(), seed);
          }
          s.err_cm.push_back(100 * r.touchdown_error_m);
          s.time_s.push_back(r.mission_time_s);
        } else {
          std::printf(
              "  %s/%s seed %d: %s (landed %d tipped %d; platform yaw %.0f deg, lateral "
              "error at final descent %.1f cm, at touch-down %.1f cm)\n",
              vehicle.c_str(), platform.c_str(), seed, r.reason.c_str(), r.landed, r.tipped,
              r.platform_yaw_rad * 180 / M_PI, 100 * r.error_at_final_descent_m,
              100 * r.error_at_touchdown_m);
        }
        s.tipped += r.tipped;
        s.est_cm.push_back(100 * r.estimate_error_W.head<2>().norm());
        s.waypoints += r.n_measurements;
        s.rejected += r.n_rejected;
        s.retries += r.retries;
      }
      print(vehicle + " landing " + platform, s, true);
    }
  }
  Summary s;
  for (int seed = 1; seed <= seeds; ++seed) {
    ClosedLoopConfig c;
    c.vehicle_file = root + "/config/vehicles/starmac.yaml";
    c.scenario_file = root + "/config/scenarios/ingress.yaml";
    c.mission = Mission::kIngress;
    c.seed = static_cast<uint64_t>(seed);
    c.vision.rate_hz = rate_hz;
    c.vision.outlier_prob = outliers;
    c.vision.sigma_xy_m = sigma_xy;
    c.vision.sigma_z_m = sigma_z;
    c.opening_size_m = Vector2d(ingress_width, ingress_height);
    if (ingress_span > 0) c.rotor_span_m = ingress_span;
    const auto r = fly_closed_loop(c);
    ++s.n;
    const bool ok = r.phase == Phase::kDone && !r.collided && r.crossed_wall;
    if (ok) {
      ++s.ok;
      s.time_s.push_back(r.mission_time_s);
    } else {
      std::printf("  ingress seed %d: %s (collided %d, %d contacts)\n", seed, r.reason.c_str(),
                  r.collided, r.n_collisions);
    }
    s.collided += r.collided;
    s.lateral_cm.push_back(100 * r.max_lateral_in_wall_m);
    s.est_cm.push_back(100 * r.estimate_error_W.norm());
    s.waypoints += r.n_measurements;
    s.rejected += r.n_rejected;
    s.retries += r.retries;
  }
  char name[64];
  std::snprintf(
      name, sizeof name, "starmac%s ingress %.2fx%.2f",
      ingress_span > 0 ? ("(span " + std::to_string(ingress_span).substr(0, 4) + ")").c_str() : "",
      ingress_width, ingress_height);
  print(name, s, false);
  return 0;
}
