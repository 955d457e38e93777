// alight-score LOG [--json] [--vehicle FILE]: the mission's figures from a session log, as
// `key: value` lines (or one JSON object), for people and scripts. Exit status: 0 when the
// mission succeeded, 1 when it did not, 2 when the log cannot be read or holds no SIM_TRUTH, or
// the vehicle file is refused. With --vision-only (a log without a simulator, e.g.
// bench/vision/soak's): no SIM_TRUTH needed, exit 0 when the log holds VISION_TIMING, 2 when not.
// A touch-down sinking faster than the vehicle's gear takes (vehicle.gear_max_impact_mps of
// --vehicle; the log does not say which vehicle flew, so without it the default vehicle's) is a
// crash: outcome `crashed`, whatever the attitude; `max_touchdown_speed_mps` is the fastest one.
// The vision's latency and rates use each event's receipt time as lcm-logger stamped it (wall
// clock): a VISION_TARGET's receipt minus that of the CAMERA frame with the same utime; its
// processing and waiting times come from VISION_TIMING.
#include <CLI/CLI.hpp>
#include <alight/image_t.hpp>
#include <cstdio>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <optional>
#include <string>

#include "common/channels.hpp"
#include "common/decode.hpp"
#include "common/params.hpp"
#include "sim/params.hpp"
#include "tools/score.hpp"

namespace {
template <class T>
bool decode(const lcm::LogEvent& ev, T& msg) {
  return ev.datalen >= 0 && alight::decode_message(msg, ev.data, static_cast<size_t>(ev.datalen));
}
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"alight-score: score a mission from its session log against the simulator's truth"};
  std::string log_path,
      truth_ch = alight::channels::kSimTruth, status_ch = alight::channels::kAutonomyStatus,
      target_ch = alight::channels::kVisionTarget, camera_ch = alight::channels::kCamera,
      timing_ch = alight::channels::kVisionTiming, platform_ch = alight::channels::kSimPlatform;
  std::string vehicle_file;
  bool json = false, vision_only = false;
  app.add_option("log", log_path, "Session log (.lcmlog)")->required()->check(CLI::ExistingFile);
  char default_impact[32];
  std::snprintf(default_impact, sizeof default_impact, "%g",
                alight::sim::VehicleParams{}.gear_max_impact_mps);
  app.add_option("--vehicle", vehicle_file,
                 std::string("Vehicle file of the flight: a touch-down sinking faster than its "
                             "vehicle.gear_max_impact_mps is a crash (without it: ") +
                     default_impact + " m/s, the default vehicle's)");
  app.add_flag("--json", json, "Print one JSON object instead of key: value lines");
  app.add_option("--truth-channel", truth_ch, "Channel of sim_truth_t");
  app.add_option("--status-channel", status_ch, "Channel of autonomy_status_t");
  app.add_option("--target-channel", target_ch, "Channel of target_t");
  app.add_option("--camera-channel", camera_ch, "Channel of image_t (raw frames)");
  app.add_option("--timing-channel", timing_ch, "Channel of vision_timing_t");
  app.add_option("--platform-channel", platform_ch,
                 "Channel of platform_truth_t (a moving platform's truth)");
  app.add_flag("--vision-only", vision_only,
               "Only the vision's figures: no SIM_TRUTH needed; exit 0 when the log holds "
               "VISION_TIMING");
  CLI11_PARSE(app, argc, argv);

  std::optional<alight::tools::Scorer> scorer_or;
  try {
    scorer_or = vehicle_file.empty()
                    ? alight::tools::Scorer()
                    : alight::tools::Scorer(
                          alight::sim::load_vehicle_params(vehicle_file).gear_max_impact_mps);
  } catch (const alight::ParamError& e) {
    std::fprintf(stderr, "alight-score: configuration error: %s\n", e.what());
    return 2;
  }
  alight::tools::Scorer& scorer = *scorer_or;

  lcm::LogFile log(log_path, "r");
  if (!log.good()) {
    std::fprintf(stderr, "alight-score: cannot read %s\n", log_path.c_str());
    return 2;
  }
  int truths = 0, timings = 0, bad = 0;
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev; ev = log.readNextEvent()) {
    if (ev->channel == truth_ch) {
      alight::sim_truth_t m;
      if (decode(*ev, m)) {
        scorer.add(m);
        ++truths;
      } else {
        ++bad;
      }
    } else if (ev->channel == platform_ch) {
      alight::platform_truth_t m;
      decode(*ev, m) ? scorer.add(m) : void(++bad);
    } else if (ev->channel == status_ch) {
      alight::autonomy_status_t m;
      decode(*ev, m) ? scorer.add(m) : void(++bad);
    } else if (ev->channel == target_ch) {
      alight::target_t m;
      decode(*ev, m) ? scorer.add(m, ev->timestamp) : void(++bad);
    } else if (ev->channel == timing_ch) {
      alight::vision_timing_t m;
      if (decode(*ev, m)) {
        scorer.add(m);
        ++timings;
      } else {
        ++bad;
      }
    } else if (ev->channel == camera_ch) {
      alight::image_t m;
      decode(*ev, m) ? scorer.add_camera_frame(m.utime, ev->timestamp) : void(++bad);
    }
  }
  if (bad > 0)
    std::fprintf(stderr, "alight-score: %d message(s) failed to decode (skipped)\n", bad);
  if (vision_only) {
    std::cout << (json ? scorer.result().to_json() : scorer.result().to_text());
    if (timings > 0) return 0;
    std::fprintf(stderr, "alight-score: %s holds no %s messages\n", log_path.c_str(),
                 timing_ch.c_str());
    return 2;
  }
  if (truths == 0) {
    std::fprintf(stderr, "alight-score: %s holds no %s messages (not a simulated session?)\n",
                 log_path.c_str(), truth_ch.c_str());
    return 2;
  }
  const auto score = scorer.result();
  std::cout << (json ? score.to_json() : score.to_text());
  return score.success ? 0 : 1;
}
