// Landing and ingress without motion capture, Monte Carlo: for each scenario, N
// seeded missions flown in process on the onboard estimate (test/autonomy/closed_loop.hpp with
// onboard_estimate: the simulator's IMU, rangefinder, barometer and downward frames through
// alight-estimator's work, real vision on the mission's camera; no motion capture; the truth
// only scores). A scenario named ingress* flies ingress: the simulator renders the forward camera
// for the vision and the downward one for the flow. Deterministic per seed: the same seed gives
// the same flight at any --jobs.
//
// Per landing scenario: landings, touchdown lateral error (body origin to the platform top's
// centre) p50 / p95 / max, the platform estimate's error relative to the vehicle (what flying on
// the estimate needs), the estimate's largest error against the truth in flight, retries and
// every failure's and retry's reason. Per ingress scenario: flights through the opening without
// contact, the body origin's offset from the opening's centre where it crossed the opening's
// plane (lateral, vertical, the distance as alight-score's crossing_offset_m) p50 / p95 / max,
// contacts, the opening estimate's error relative to the vehicle, the estimate's error at the
// crossing and its largest in flight.
//
//   build/bin/estimator_nomocap_landing [--seeds 20] [--first-seed 1] [--jobs 2]
//       [--scenarios landing_a,landing_b,landing_c] [--vehicle config/vehicles/pelican.yaml]
//   build/bin/estimator_nomocap_ingress   (the same; --scenarios ingress_wide by default)
// --mocap flies the same missions on motion capture instead, for comparison.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <opencv2/core.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "closed_loop.hpp"
#include "common/build_paths.hpp"
#include "common/params.hpp"
#include "estimator/flow_odometry.hpp"
#include "real_vision.hpp"
#include "support/parallel_runs.hpp"
#include "support/stats.hpp"

using namespace alight;
using namespace alight::autonomy;
using namespace alight::autonomy::test;

namespace {

using alight::test::quantile;

struct Run {
  std::string scenario;
  int seed = 0;
  ClosedLoopResult r;
  bool ok = false;
};

// A name under config/scenarios, or a scenario file (ends in .yaml).
bool is_file(const std::string& scenario) {
  return scenario.size() > 5 && scenario.compare(scenario.size() - 5, 5, ".yaml") == 0;
}

std::string scenario_file(const std::string& scenario) {
  return is_file(scenario)
             ? scenario
             : std::string(alight::build::source_dir()) + "/config/scenarios/" + scenario + ".yaml";
}

// Ingress scenarios are named ingress*; a file by its name.
bool is_ingress(const std::string& scenario) {
  const std::string base = scenario.substr(scenario.find_last_of('/') + 1);
  return base.rfind("ingress", 0) == 0;
}

bool success(const std::string& scenario, const ClosedLoopResult& r) {
  // Through the opening without touching the wall or its frame (the referee's rule).
  if (is_ingress(scenario))
    return r.phase == Phase::kDone && r.crossed_wall && r.crossing_offset_m && !r.collided &&
           r.n_collisions == 0;
  // As bench/autonomy: a platform overlapping the start spot flags "tipped" before take-off.
  return r.phase == Phase::kLanded && !r.armed &&
         (r.tipped_before_go ? r.on_platform_top : r.landed && !r.tipped);
}

// The flow front end's frame pairs by outcome, those that happened: " ok 812, too_few_tracks 3".
std::string flow_pairs_text(const std::vector<int64_t>& counts) {
  std::string out;
  for (size_t i = 0; i < counts.size(); ++i)
    if (counts[i] > 0)
      out += std::string(out.empty() ? " " : ", ") +
             estimator::to_string(static_cast<estimator::FlowReason>(i)) + " " +
             std::to_string(counts[i]);
  return out.empty() ? " none" : out;
}

std::string one_line(const Run& x) {
  const auto& r = x.r;
  char buf[768];
  if (is_ingress(x.scenario)) {
    const Vector2d off = r.crossing_offset_m.value_or(Vector2d::Constant(NAN));
    std::snprintf(
        buf, sizeof buf,
        "%s seed %2d: %s crossing offset lateral %+.2f vertical %+.2f cm, contacts %d, opening "
        "rel. error %.2f cm, pose error at the crossing %.2f cm (z %+.2f), max %.2f cm (z %.2f), "
        "retries %d, mission %.1f s, terrain resets %d, health not OK %d+%d steps%s%s",
        x.scenario.c_str(), x.seed, x.ok ? "through" : "FAILED", 100 * off.x(), 100 * off.y(),
        r.n_collisions, 100 * r.estimate_error_rel_W.norm(),
        100 * r.pose_error_at_crossing_W.head<2>().norm(), 100 * r.pose_error_at_crossing_W.z(),
        100 * r.max_pose_error_h_m, 100 * r.max_pose_error_z_m, r.retries, r.mission_time_s,
        r.terrain_resets, r.estimate_degraded_steps, r.estimate_lost_steps,
        r.estimate_reasons.empty() ? "" : (" (" + r.estimate_reasons + ")").c_str(),
        x.ok ? "" : (": " + r.reason).c_str());
    return buf;
  }
  std::snprintf(buf, sizeof buf,
                "%s seed %2d: %s touchdown %.2f cm, platform rel. error %.2f cm (z %+.2f), pose "
                "error max %.2f cm (z %.2f), retries %d, mission %.1f s, flow on floor %lld, "
                "inflated %lld, velocity resets %lld, terrain resets %d, health not OK %d+%d "
                "steps%s, flow pairs%s%s",
                x.scenario.c_str(), x.seed, x.ok ? "landed" : "FAILED", 100 * r.touchdown_error_m,
                100 * r.estimate_error_rel_W.norm(), 100 * r.estimate_error_rel_W.z(),
                100 * r.max_pose_error_h_m, 100 * r.max_pose_error_z_m, r.retries, r.mission_time_s,
                static_cast<long long>(r.flow_on_floor), static_cast<long long>(r.flow_inflated),
                static_cast<long long>(r.flow_velocity_resets), r.terrain_resets,
                r.estimate_degraded_steps, r.estimate_lost_steps,
                r.estimate_reasons.empty() ? "" : (" (" + r.estimate_reasons + ")").c_str(),
                flow_pairs_text(r.flow_reasons).c_str(), x.ok ? "" : (": " + r.reason).c_str());
  return buf;
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{
      "landing and ingress without motion capture on the onboard estimate, real vision, Monte "
      "Carlo"};
  int seeds = 20, first = 1, jobs = 1;
  std::string scenarios = ALIGHT_NOMOCAP_SCENARIOS;
  std::string vehicle = std::string(alight::build::source_dir()) + "/config/vehicles/pelican.yaml";
  double time_limit_s = 150;
  app.add_option("--seeds", seeds, "missions per scenario")->check(CLI::Range(1, 1000));
  app.add_option("--first-seed", first, "seed of the first mission");
  app.add_option("--jobs", jobs, "missions flown at once (threads)")->check(CLI::Range(1, 64));
  app.add_option(
      "--scenarios", scenarios,
      "scenario names under config/scenarios or scenario files (*.yaml), comma-separated "
      "(ingress* fly ingress)");
  app.add_option("--vehicle", vehicle, "vehicle file");
  app.add_option("--time-limit", time_limit_s, "simulated seconds per mission at most");
  bool mocap = false;
  app.add_flag("--mocap", mocap,
               "fly on motion capture instead of the onboard estimate (the same missions, for "
               "comparison)");
  CLI11_PARSE(app, argc, argv);
  cv::setNumThreads(1);  // the jobs are the parallelism

  std::vector<std::string> names;
  for (std::stringstream ss(scenarios); ss.good();) {
    std::string n;
    std::getline(ss, n, ',');
    if (!n.empty()) names.push_back(n);
  }
  std::vector<Run> runs;
  for (const auto& n : names)
    for (int s = first; s < first + seeds; ++s) runs.push_back(Run{n, s, {}, false});

  std::mutex out;
  alight::test::run_parallel(runs.size(), jobs, [&](size_t i) {
    Run& x = runs[i];
    const Mission mission = is_ingress(x.scenario) ? Mission::kIngress : Mission::kLanding;
    RealVision vision(vehicle, mission);
    ClosedLoopConfig c;
    c.vehicle_file = vehicle;
    c.scenario_file = scenario_file(x.scenario);
    c.mission = mission;
    c.seed = static_cast<uint64_t>(x.seed);
    c.time_limit_s = time_limit_s;
    c.onboard_estimate = !mocap;
    c.camera_vision = [&vision](const sim::CameraFrame& f, const std::optional<PoseSample>& p) {
      return vision(f, p);
    };
    x.r = fly_closed_loop(c);
    x.ok = success(x.scenario, x.r);
    // On motion capture the vehicle's frame is the true one: the target's error relative to
    // the vehicle is its error.
    if (mocap) x.r.estimate_error_rel_W = x.r.estimate_error_W;
    std::lock_guard<std::mutex> lock(out);
    std::printf("%s\n", one_line(x).c_str());
    for (const auto& why : x.r.retry_reasons) std::printf("    retry: %s\n", why.c_str());
    std::fflush(stdout);
  });

  std::printf("\n%s, %s, seeds %d-%d:\n", mocap ? "on motion capture" : "without motion capture",
              vehicle.c_str(), first, first + seeds - 1);
  for (const auto& n : names) {
    if (is_ingress(n)) {
      // Every flight's crossing counts, through or not: a contact is the tail that matters.
      std::vector<double> lat_cm, vert_cm, off_cm, rel_cm, cross_h_cm, cross_z_cm, pose_h_cm,
          pose_z_cm, time_s;
      int ok = 0, n_runs = 0, retries = 0, contacts = 0, with_contact = 0, crossed = 0;
      std::map<std::string, int> failures, retry_reasons;
      for (const auto& x : runs) {
        if (x.scenario != n) continue;
        const auto& r = x.r;
        ++n_runs;
        retries += r.retries;
        contacts += r.n_collisions;
        with_contact += r.collided;
        for (const auto& why : r.retry_reasons) ++retry_reasons[why.substr(0, why.find(':'))];
        rel_cm.push_back(100 * r.estimate_error_rel_W.norm());
        pose_h_cm.push_back(100 * r.max_pose_error_h_m);
        pose_z_cm.push_back(100 * r.max_pose_error_z_m);
        if (r.crossing_offset_m) {
          ++crossed;
          lat_cm.push_back(100 * std::abs(r.crossing_offset_m->x()));
          vert_cm.push_back(100 * std::abs(r.crossing_offset_m->y()));
          off_cm.push_back(100 * r.crossing_offset_m->norm());
          cross_h_cm.push_back(100 * r.pose_error_at_crossing_W.head<2>().norm());
          cross_z_cm.push_back(100 * std::abs(r.pose_error_at_crossing_W.z()));
        }
        if (x.ok) {
          ++ok;
          time_s.push_back(r.mission_time_s);
        } else {
          ++failures[r.reason];
        }
      }
      std::printf(
          "%s: %d/%d through without contact (%d crossed, %d with contact, %d contacts); crossing "
          "offset from the opening's centre |lateral| p50 %.2f p95 %.2f max %.2f cm, |vertical| "
          "p50 %.2f p95 %.2f max %.2f cm, distance p50 %.2f p95 %.2f max %.2f cm; opening "
          "estimate relative to the vehicle p50 %.2f max %.2f cm; estimate error at the crossing "
          "horizontal p50 %.2f max %.2f cm, vertical p50 %.2f max %.2f cm; largest in flight "
          "horizontal p50 %.2f max %.2f cm, vertical p50 %.2f max %.2f cm; mission p50 %.1f s; "
          "retries %d\n",
          n.c_str(), ok, n_runs, crossed, with_contact, contacts, quantile(lat_cm, 0.5),
          quantile(lat_cm, 0.95), quantile(lat_cm, 1.0), quantile(vert_cm, 0.5),
          quantile(vert_cm, 0.95), quantile(vert_cm, 1.0), quantile(off_cm, 0.5),
          quantile(off_cm, 0.95), quantile(off_cm, 1.0), quantile(rel_cm, 0.5),
          quantile(rel_cm, 1.0), quantile(cross_h_cm, 0.5), quantile(cross_h_cm, 1.0),
          quantile(cross_z_cm, 0.5), quantile(cross_z_cm, 1.0), quantile(pose_h_cm, 0.5),
          quantile(pose_h_cm, 1.0), quantile(pose_z_cm, 0.5), quantile(pose_z_cm, 1.0),
          quantile(time_s, 0.5), retries);
      for (const auto& [why, k] : failures) std::printf("    failed %dx: %s\n", k, why.c_str());
      for (const auto& [why, k] : retry_reasons) std::printf("    retry %dx: %s\n", k, why.c_str());
      continue;
    }
    std::vector<double> err_cm, rel_cm, rel_z_cm, pose_h_cm, pose_z_cm, time_s;
    int ok = 0, n_runs = 0, retries = 0;
    std::map<std::string, int> failures, retry_reasons;
    for (const auto& x : runs) {
      if (x.scenario != n) continue;
      ++n_runs;
      retries += x.r.retries;
      for (const auto& why : x.r.retry_reasons) ++retry_reasons[why.substr(0, why.find(':'))];
      rel_cm.push_back(100 * x.r.estimate_error_rel_W.norm());
      rel_z_cm.push_back(100 * std::abs(x.r.estimate_error_rel_W.z()));
      pose_h_cm.push_back(100 * x.r.max_pose_error_h_m);
      pose_z_cm.push_back(100 * x.r.max_pose_error_z_m);
      if (x.ok) {
        ++ok;
        err_cm.push_back(100 * x.r.touchdown_error_m);
        time_s.push_back(x.r.mission_time_s);
      } else {
        ++failures[x.r.reason];
      }
    }
    std::printf(
        "%s: %d/%d landed; touchdown lateral error p50 %.2f p95 %.2f max %.2f cm; platform "
        "estimate relative to the vehicle p50 %.2f max %.2f cm (|z| p50 %.2f max %.2f); estimate "
        "error in flight, largest per run: horizontal p50 %.2f max %.2f cm, vertical p50 %.2f max "
        "%.2f cm; mission p50 %.1f s; retries %d\n",
        n.c_str(), ok, n_runs, quantile(err_cm, 0.5), quantile(err_cm, 0.95), quantile(err_cm, 1.0),
        quantile(rel_cm, 0.5), quantile(rel_cm, 1.0), quantile(rel_z_cm, 0.5),
        quantile(rel_z_cm, 1.0), quantile(pose_h_cm, 0.5), quantile(pose_h_cm, 1.0),
        quantile(pose_z_cm, 0.5), quantile(pose_z_cm, 1.0), quantile(time_s, 0.5), retries);
    for (const auto& [why, k] : failures) std::printf("    failed %dx: %s\n", k, why.c_str());
    for (const auto& [why, k] : retry_reasons) std::printf("    retry %dx: %s\n", k, why.c_str());
  }
  std::fflush(stdout);
  return 0;
} catch (const alight::ParamError& e) {
  // A bad scenario or vehicle file: the message names the file, the key and the value.
  std::fprintf(stderr, "estimator_nomocap_landing: configuration error: %s\n", e.what());
  return 2;
}
