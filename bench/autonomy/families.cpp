// Scene families, Monte Carlo in process: for each family (scripts/scene_families.py)
// N scenes freshly drawn (scripts/scenes, seed0 .. seed0 + N - 1; seed0 random unless given, and
// printed so a run can be redone), each flown with the real vision pipeline in the tests' closed
// loop (test/autonomy/closed_loop.hpp: simulator, outer loop, autonomy; motion capture, or the
// onboard estimate with --no-mocap). Deterministic per scene: the same family, seed and vehicle
// give the same flight at any --jobs.
//
// Per family: missions completed (landed on the platform top, motors off / through the opening
// without contact), touchdown lateral error p50 / p95 / max (landing), opening width error (the
// median of the full views' widths minus the true width, as alight-score) p50 / p95 of |error| and
// its sign, opening centre error and the largest offset from the opening centre while crossing
// (ingress), false targets (families without a target: any frame the vision reported found or a
// partial view of, since autonomy refines on both),
// retries and every failure's reason, and the vision's thread CPU time per frame p50 / p99 / max
// (the in-process pipeline on the frames of the flights; at --jobs 2 the two flights share the
// machine's caches).
//
//   build/bin/alight_families_bench [--families landing_tiles,ingress_photo] [--runs 20]
//       [--seed0 S] [--purpose any|tune|report] [--jobs 2] [--no-mocap]
//       [--vehicle config/vehicles/pelican.yaml] [--verbose] [--csv FILE]
//       [--scenarios landing_moving_cart,landing_deck]
//
// --scenarios flies shipped scenarios (config/scenarios/NAME.yaml, or a scenario file's path)
// instead of drawn scenes, each at the seeds seed0 .. seed0 + N - 1 (the seed draws what the
// scenario's `randomize:` leaves open, as alight-sim --seed does; seed0 1 unless given),
// summarised as a family is: the in-process figures of the scenario scripts/montecarlo
// --scenarios flies over LCM. The tune/report split below is of drawn scenes' seeds only.
//
// The seeds are judged against the tune/report split of config/seeds.yaml (tools/seed_split):
// the summary says which they are, --purpose tune refuses report seeds and --purpose report
// refuses any other, and without --seed0 a fresh block of report seeds is drawn.
//
// --csv writes one row per run with scripts/montecarlo's column names (it runs this bench with
// --in-process and summarises and plots the rows as it does its flights over LCM); with
// --no-mocap two more: the relative estimate error (autonomy's platform estimate against the
// vehicle's own estimated pose, taken into the true frame) entering the approach and at the
// touch-down, whose difference is the onboard estimate's drift over the approach. The column
// `collided` (as alight-score's) marks a flight that touched the wall or the opening's frame: a
// failed flight that hit the wall is no safe hold, and the summary counts them. The last,
// `candidate_looks`, counts the search's pauses over a believed platform not yet shown moving
// (autonomy/moving_landing.hpp, step 0).

#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <opencv2/core.hpp>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "closed_loop.hpp"
#include "common/build_paths.hpp"
#include "common/heap.hpp"
#include "common/params.hpp"
#include "real_vision.hpp"
#include "sim/params.hpp"
#include "support/parallel_runs.hpp"
#include "support/stats.hpp"
#include "tools/seed_split.hpp"

using namespace alight;
using namespace alight::autonomy;
using namespace alight::autonomy::test;

namespace {

using alight::test::quantile;

double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

Mission mission_of(const std::string& family) {
  return family.rfind("ingress", 0) == 0 ? Mission::kIngress : Mission::kLanding;
}

/// A family without a target: the vision must never report one.
bool targetless(const std::string& family) {
  return family.find("_none") != std::string::npos || family.find("_solid") != std::string::npos;
}

struct Run {
  std::string family;
  uint64_t seed = 0;
  std::string scenario_file;
  ClosedLoopResult r;
  bool ok = false;
  int frames = 0, found = 0, partial = 0;
  int platform_found = 0;        ///< frames with a moving top measured (VISION_PLATFORM found)
  std::vector<double> widths_m;  ///< full views' opening widths (ingress)
  std::vector<double> cpu_ms;    ///< the vision's thread CPU time per frame
  double true_width_m = std::nan("");
  sim::CameraEffects effects;  ///< the scenario's camera effects (its lens: the vision's model)
};

/// The families whose platform moves (platform.motion): their extra figures (relative to it).
bool moving(const std::string& family) {
  return family.rfind("landing_moving_cart", 0) == 0 || family.rfind("landing_deck", 0) == 0;
}

bool success(const Run& x) {
  const auto& r = x.r;
  if (targetless(x.family)) return x.found == 0 && x.partial == 0 && !r.collided;
  if (mission_of(x.family) == Mission::kIngress)
    return r.phase == Phase::kDone && r.crossed_wall && !r.collided;
  // As bench/autonomy: a platform overlapping the start spot flags "tipped" before take-off.
  return r.phase == Phase::kLanded && !r.armed &&
         (r.tipped_before_go ? r.on_platform_top : r.landed && !r.tipped);
}

double width_error_m(const Run& x) {
  if (x.widths_m.empty() || !std::isfinite(x.true_width_m)) return std::nan("");
  return quantile(x.widths_m, 0.5) - x.true_width_m;
}

std::string one_line(const Run& x) {
  const auto& r = x.r;
  char what[448];
  if (targetless(x.family))
    std::snprintf(what, sizeof what, "found in %d and a partial view in %d of %d frames", x.found,
                  x.partial, x.frames);
  else if (mission_of(x.family) == Mission::kLanding)
    std::snprintf(what, sizeof what,
                  "touchdown %.2f cm (entering the final descent %.2f, at the detected "
                  "touch-down %.2f), platform estimate error %.2f cm",
                  100 * r.touchdown_error_m, 100 * r.error_at_final_descent_m,
                  100 * r.error_at_touchdown_m, 100 * r.estimate_error_W.norm());
  else
    std::snprintf(what, sizeof what,
                  "width error %+.2f cm (true %.3f m), centre error %.2f cm, max offset in the "
                  "wall %.2f cm",
                  100 * width_error_m(x), x.true_width_m, 100 * r.estimate_error_W.norm(),
                  100 * r.max_lateral_in_wall_m);
  if (moving(x.family)) {
    const size_t n = std::strlen(what);
    std::snprintf(what + n, sizeof what - n,
                  ", heading error %.1f deg, contact relative vz %+.2f m/s, platform measured in "
                  "%d of %d frames",
                  r.heading_error_at_touchdown_deg, r.contact_rel_vz_mps, x.platform_found,
                  x.frames);
  }
  if (r.flow_velocity_resets > 0) {
    const size_t n = std::strlen(what);
    std::snprintf(what + n, sizeof what - n,
                  ", the estimate's velocity set to the flow's %lld times",
                  static_cast<long long>(r.flow_velocity_resets));
  }
  char buf[768];
  std::snprintf(buf, sizeof buf, "%s seed %llu: %s, %s; %s; retries %d, mission %.1f s%s",
                x.family.c_str(), static_cast<unsigned long long>(x.seed), x.ok ? "ok" : "FAILED",
                r.reason.c_str(), what, r.retries, r.mission_time_s,
                r.collided ? "; COLLIDED" : "");
  return buf;
}

/// One row per run; empty cells where a figure does not apply (as alight-score leaves it out);
/// `onboard`: flown on the onboard estimate (its relative estimate errors are written).
bool write_csv(const std::string& path, const std::vector<Run>& all, bool onboard) {
  std::ofstream f(path);
  f << "scenario,seed,mission,success,outcome,touchdown_lateral_error_m,touchdown_along_m,"
       "touchdown_across_m,platform_length_m,platform_width_m,opening_width_error_m,"
       "opening_width_m,opening_center_error_m,crossing_offset_m,retries,mission_time_s,"
       "vision_frames,vision_found,vision_partial,vision_process_cpu_p50_ms,vision_process_cpu_p99_"
       "ms,"
       "vision_process_cpu_max_ms,estimate_rel_error_at_approach_m,"
       "estimate_rel_error_at_touchdown_m,collided,candidate_looks\n";
  const auto num = [](double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.6g", v);
    return std::isfinite(v) ? std::string(b) : std::string();
  };
  for (const auto& x : all) {
    const auto& r = x.r;
    const bool landing = mission_of(x.family) == Mission::kLanding && !targetless(x.family);
    const bool ingress = mission_of(x.family) == Mission::kIngress && !targetless(x.family);
    std::string reason = r.reason;
    std::replace(reason.begin(), reason.end(), ',', ';');
    std::replace(reason.begin(), reason.end(), '"', '\'');
    f << x.family << ',' << x.seed << ','
      << (mission_of(x.family) == Mission::kLanding ? "landing" : "ingress") << ','
      << (x.ok ? "True" : "False") << ",\"" << reason << "\","
      << (landing && x.ok ? num(r.touchdown_error_m) : "") << ','
      << (landing ? num(r.final_in_platform_m.x()) : "") << ','
      << (landing ? num(r.final_in_platform_m.y()) : "") << ','
      << (landing ? num(r.platform_size_m.x()) : "") << ','
      << (landing ? num(r.platform_size_m.y()) : "") << ','
      << (ingress ? num(width_error_m(x)) : "") << ',' << (ingress ? num(x.true_width_m) : "")
      << ',' << (ingress ? num(r.estimate_error_W.norm()) : "") << ','
      << (ingress && r.crossed_wall ? num(r.max_lateral_in_wall_m) : "") << ',' << r.retries << ','
      << (x.ok ? num(r.mission_time_s) : "") << ',' << x.frames << ',' << x.found << ','
      << x.partial << ',' << num(quantile(x.cpu_ms, 0.5)) << ',' << num(quantile(x.cpu_ms, 0.99))
      << ',' << num(quantile(x.cpu_ms, 1.0)) << ','
      << (landing && onboard ? num(r.estimate_error_rel_at_approach_W.head<2>().norm()) : "") << ','
      << (landing && onboard ? num(r.estimate_error_rel_at_touchdown_W.head<2>().norm()) : "")
      << ',' << (r.collided ? "True" : "False") << ',' << r.candidate_looks << '\n';
  }
  return static_cast<bool>(f);
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  for (std::stringstream ss(s); ss.good();) {
    std::string n;
    std::getline(ss, n, ',');
    if (!n.empty()) out.push_back(n);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"scene families: real-vision closed-loop Monte Carlo over freshly drawn scenes"};
  int runs = 20, jobs = 1;
  int64_t seed0 = -1;
  bool no_mocap = false, verbose = false;
  std::string families =
      "landing_photo,landing_tiles,landing_lowtex,landing_none_photo,ingress_photo,"
      "ingress_solid_photo";
  std::string vehicle = std::string(alight::build::source_dir()) + "/config/vehicles/pelican.yaml";
  double time_limit_s = 240;
  auto* families_option =
      app.add_option("--families", families, "comma-separated families (scripts/scenes --list)");
  std::string scenarios;
  app.add_option("--scenarios", scenarios,
                 "comma-separated shipped scenarios (config/scenarios/NAME.yaml) or scenario "
                 "files, each flown at every seed (with --families: both)");
  app.add_option("--runs", runs, "scenes drawn and flown per family")->check(CLI::Range(1, 10000));
  app.add_option("--seed0", seed0, "first seed (default: a fresh random one)")
      ->check(CLI::Range(int64_t{0}, int64_t{1} << 40));
  app.add_option("--jobs", jobs, "flights at once (threads)")->check(CLI::Range(1, 64));
  app.add_flag("--no-mocap", no_mocap, "fly on the onboard estimate instead of motion capture");
  app.add_option("--vehicle", vehicle, "vehicle file");
  app.add_option("--time-limit", time_limit_s, "simulated seconds per mission at most")
      ->check(CLI::Range(10.0, 3600.0));
  app.add_flag("--verbose", verbose, "print each run's retries");
  bool dry_run = false;
  app.add_flag("--dry-run", dry_run,
               "check the seeds against the split, draw and read every scene and the vehicle's "
               "cameras, list the runs, fly nothing");
  std::string csv_path;
  app.add_option("--csv", csv_path, "write one row per run to this file");
  std::string purpose_text = "any";
  app.add_option("--purpose", purpose_text,
                 "tune (refuse report seeds), report (refuse all but report seeds) or any")
      ->check(CLI::IsMember({"any", "tune", "report"}));
  std::string seeds_file = std::string(alight::build::source_dir()) + "/config/seeds.yaml";
  app.add_option("--seeds-file", seeds_file, "the tune/report split of scene seeds");
  CLI11_PARSE(app, argc, argv);
  cv::setNumThreads(1);  // the jobs are the parallelism
  // The vision's CPU per frame is the node's (common/node.cpp keeps freed memory): under glibc's
  // defaults every frame's large buffers fault in again and the faults count as the vision's.
  if (!alight::retain_freed_memory()) std::fprintf(stderr, "glibc refused the heap settings\n");

  // A shipped scenario's summary goes under its name, as a family's does.
  std::vector<std::string> names;
  std::map<std::string, std::string> scenario_files;  // shipped scenario name -> file
  if (scenarios.empty() || families_option->count() > 0) names = split(families);
  for (const auto& s : split(scenarios)) {
    const bool file = s.find('/') != std::string::npos || s.ends_with(".yaml");
    const std::string name = file ? std::filesystem::path(s).stem().string() : s;
    if (std::find(names.begin(), names.end(), name) != names.end()) {
      std::fprintf(stderr, "alight_families_bench: '%s' named twice (--families, --scenarios)\n",
                   name.c_str());
      return 2;
    }
    names.push_back(name);
    scenario_files[name] =
        file ? s : std::string(alight::build::source_dir()) + "/config/scenarios/" + s + ".yaml";
  }
  // The split is of drawn scenes; a shipped scenario's seeds are its own (its `randomize:`).
  const bool drawn = names.size() > scenario_files.size();
  std::string seed_kind = "a shipped scenario's own seeds, outside the drawn scenes' split";
  if (drawn) {
    const auto seed_split =
        alight::tools::SeedSplit::from(alight::ParamNode::load_file(seeds_file));
    if (seed0 < 0)
      seed0 = alight::tools::fresh_report_seed0(seed_split, runs, std::random_device{}());
    if (const std::string why = alight::tools::check_seeds(
            seed_split, alight::tools::parse_seed_purpose(purpose_text), seed0, seed0 + runs - 1);
        !why.empty()) {
      std::fprintf(stderr, "alight_families_bench: %s (%s)\n", why.c_str(), seeds_file.c_str());
      return 2;
    }
    seed_kind = alight::tools::describe_seeds(seed_split, seed0, seed0 + runs - 1);
  } else if (purpose_text != "any") {
    std::fprintf(stderr,
                 "alight_families_bench: --purpose %s judges drawn scenes' seeds; a shipped "
                 "scenario's are its own (--purpose any)\n",
                 purpose_text.c_str());
    return 2;
  } else if (seed0 < 0) {
    seed0 = 1;
  }
  namespace fs = std::filesystem;
  std::string dir_template = (fs::temp_directory_path() / "alight-families-XXXXXX").string();
  if (!mkdtemp(dir_template.data())) {
    std::fprintf(stderr, "alight_families_bench: cannot create a temporary folder\n");
    return 2;
  }
  const fs::path dir = dir_template;
  // The drawn scenes go with the run, however it ends (scripts/scenes draws them again).
  struct RemoveOnExit {
    fs::path path;
    ~RemoveOnExit() {
      std::error_code ignored;
      fs::remove_all(path, ignored);
    }
  } remove_scenes{dir};
  std::string listed;
  for (const auto& n : names) listed += (listed.empty() ? "" : ",") + n;
  std::printf("families %s, seeds %lld..%lld, %s, scenes in %s\n", listed.c_str(),
              static_cast<long long>(seed0), static_cast<long long>(seed0 + runs - 1),
              no_mocap ? "on the onboard estimate" : "on motion capture", dir.c_str());

  std::vector<Run> all;
  for (const auto& fam : names) {
    for (int i = 0; i < runs; ++i) {
      const uint64_t seed = static_cast<uint64_t>(seed0 + i);
      Run x;
      x.family = fam;
      x.seed = seed;
      if (const auto shipped = scenario_files.find(fam); shipped != scenario_files.end()) {
        x.scenario_file = shipped->second;
      } else {
        const std::string cmd = "'" + std::string(alight::build::source_dir()) +
                                "/scripts/scenes' '" + fam + "' --seed " + std::to_string(seed) +
                                " --out '" + dir.string() + "' > /dev/null";
        if (std::system(cmd.c_str()) != 0) {
          std::fprintf(stderr, "alight_families_bench: scripts/scenes failed for family '%s'\n",
                       fam.c_str());
          return 2;
        }
        x.scenario_file = (dir / (fam + "-" + std::to_string(seed) + ".yaml")).string();
      }
      const auto scenario = sim::load_scenario(x.scenario_file);
      if (scenario.wall && scenario.wall->has_opening)
        x.true_width_m = scenario.wall->opening_size_m.x();
      x.effects = scenario.camera.effects;
      all.push_back(std::move(x));
    }
  }

  if (dry_run) {
    // What a flight would read first: the vehicle's camera for the family's mission, once per
    // mount.
    std::map<std::string, CameraModel> cameras;
    for (const auto& x : all) {
      const std::string mount = mission_of(x.family) == Mission::kLanding ? "downward" : "forward";
      if (!cameras.count(mount)) cameras.emplace(mount, sim::load_camera_rig(vehicle, mount).model);
      const CameraModel& camera = cameras.at(mount);
      std::printf("%s seed %llu: %s, %s camera %dx%d\n", x.family.c_str(),
                  static_cast<unsigned long long>(x.seed), x.scenario_file.c_str(), mount.c_str(),
                  camera.width, camera.height);
    }
    std::printf("dry run: %zu runs (%s), none flown\n", all.size(), seed_kind.c_str());
    return 0;
  }

  std::mutex out;
  alight::test::run_parallel(all.size(), jobs, [&](size_t i) {
    Run& x = all[i];
    const Mission mission = mission_of(x.family);
    // The vision undistorts with the lens the simulator renders (camera.effects.lens).
    const auto rig =
        sim::load_camera_rig(vehicle, mission == Mission::kLanding ? "downward" : "forward");
    RealVision vision(
        vehicle, mission, [](vision::PipelineParams&) {}, sim::with_lens(rig.model, x.effects));
    ClosedLoopConfig c;
    c.vehicle_file = vehicle;
    c.scenario_file = x.scenario_file;
    c.mission = mission;
    c.seed = x.seed;
    c.time_limit_s = time_limit_s;
    c.onboard_estimate = no_mocap;
    c.camera_vision = [&](const sim::CameraFrame& f, const std::optional<PoseSample>& p) {
      const double t0 = thread_cpu_ms();
      auto m = vision(f, p);
      x.cpu_ms.push_back(thread_cpu_ms() - t0);
      if (m && m->found && !m->partial && mission == Mission::kIngress)
        x.widths_m.push_back(m->size_m.x());
      return m;
    };
    c.camera_platform = [&] { return vision.take_platform(); };
    x.r = fly_closed_loop(c);
    x.frames = vision.frames;
    x.found = vision.found;
    x.partial = vision.partial;
    x.platform_found = vision.platform_found;
    x.ok = success(x);
    std::lock_guard<std::mutex> lock(out);
    std::printf("%s\n", one_line(x).c_str());
    if (verbose)
      for (const auto& why : x.r.retry_reasons) std::printf("    retry: %s\n", why.c_str());
    std::fflush(stdout);
  });

  std::printf("\n%s, seeds %lld..%lld (%s), %s:\n", vehicle.c_str(), static_cast<long long>(seed0),
              static_cast<long long>(seed0 + runs - 1), seed_kind.c_str(),
              no_mocap ? "on the onboard estimate" : "on motion capture");
  for (const auto& fam : names) {
    std::vector<double> heading_deg, rel_vz_mps;
    std::vector<double> touch_cm, werr_cm, wabs_cm, centre_cm, offset_cm, cpu, time_s;
    int ok = 0, n = 0, retries = 0, false_runs = 0, false_frames = 0, partial_frames = 0;
    int looks = 0;     // the search paused over a believed platform
    int collided = 0;  // a failed flight that also hit something is the worst outcome
    std::map<std::string, int> failures;
    for (const auto& x : all) {
      if (x.family != fam) continue;
      ++n;
      retries += x.r.retries;
      looks += x.r.candidate_looks;
      collided += x.r.collided;
      cpu.insert(cpu.end(), x.cpu_ms.begin(), x.cpu_ms.end());
      false_runs += targetless(fam) && (x.found > 0 || x.partial > 0);
      false_frames += targetless(fam) ? x.found : 0;
      partial_frames += targetless(fam) ? x.partial : 0;
      if (x.ok) {
        ++ok;
        time_s.push_back(x.r.mission_time_s);
      } else {
        ++failures[x.r.reason.empty() ? "(no reason)" : x.r.reason];
      }
      if (targetless(fam)) continue;
      if (mission_of(fam) == Mission::kLanding) {
        if (x.ok) touch_cm.push_back(100 * x.r.touchdown_error_m);
        if (x.ok && moving(fam)) {
          heading_deg.push_back(x.r.heading_error_at_touchdown_deg);
          rel_vz_mps.push_back(std::abs(x.r.contact_rel_vz_mps));
        }
      } else {
        const double w = width_error_m(x);
        if (std::isfinite(w)) {
          werr_cm.push_back(100 * w);
          wabs_cm.push_back(100 * std::abs(w));
        }
        centre_cm.push_back(100 * x.r.estimate_error_W.norm());
        if (x.r.crossed_wall) offset_cm.push_back(100 * x.r.max_lateral_in_wall_m);
      }
    }
    std::printf("%s: %d/%d %s", fam.c_str(), ok, n,
                targetless(fam)                        ? "without a false target"
                : mission_of(fam) == Mission::kLanding ? "landed"
                                                       : "through");
    if (targetless(fam))
      std::printf(" (false targets in %d runs: found in %d frames, a partial view in %d)",
                  false_runs, false_frames, partial_frames);
    else if (mission_of(fam) == Mission::kLanding)
      std::printf("; touchdown lateral error p50 %.2f p95 %.2f max %.2f cm",
                  quantile(touch_cm, 0.5), quantile(touch_cm, 0.95), quantile(touch_cm, 1.0));
    else
      std::printf(
          "; width error |.| p50 %.2f p95 %.2f max %.2f cm (signed p50 %+.2f, %zu runs measured); "
          "centre error p50 %.2f p95 %.2f cm; offset in the wall p50 %.2f max %.2f cm",
          quantile(wabs_cm, 0.5), quantile(wabs_cm, 0.95), quantile(wabs_cm, 1.0),
          quantile(werr_cm, 0.5), werr_cm.size(), quantile(centre_cm, 0.5),
          quantile(centre_cm, 0.95), quantile(offset_cm, 0.5), quantile(offset_cm, 1.0));
    if (moving(fam))
      std::printf(
          "; relative to the platform: heading error p50 %.1f p95 %.1f deg, contact "
          "|relative vz| p50 %.2f p95 %.2f m/s",
          quantile(heading_deg, 0.5), quantile(heading_deg, 0.95), quantile(rel_vz_mps, 0.5),
          quantile(rel_vz_mps, 0.95));
    std::printf(
        "; mission p50 %.1f s; retries %d; looks %d; collided %d; vision CPU per frame p50 %.2f "
        "p99 %.2f max %.2f ms over %zu frames\n",
        quantile(time_s, 0.5), retries, looks, collided, quantile(cpu, 0.5), quantile(cpu, 0.99),
        quantile(cpu, 1.0), cpu.size());
    for (const auto& [why, k] : failures) std::printf("    failed %dx: %s\n", k, why.c_str());
  }
  std::fflush(stdout);
  if (!csv_path.empty() && !write_csv(csv_path, all, no_mocap)) {
    std::fprintf(stderr, "alight_families_bench: cannot write %s\n", csv_path.c_str());
    return 2;
  }
  return 0;
} catch (const alight::ParamError& e) {
  // A bad scenario or vehicle file: the message names the file, the key and the value.
  std::fprintf(stderr, "alight_families_bench: configuration error: %s\n", e.what());
  return 2;
}
