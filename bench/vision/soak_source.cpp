// alight-vision-soak-source: the camera and motion capture of bench/vision/soak ("keep
// up with the camera"): CAMERA at a fixed rate (60 Hz by default) and MOCAP_POSE, for as long as
// asked, paced on the steady clock and stamped on the wall clock like a real camera and room.
//
// The frames are those alight-sim renders (the scenario's textures, noise, motion blur, gain
// flicker; the motion-capture noise and latency), of the vehicle flown by the outer loop's
// position controller along a closed figure-eight in front of the target (over the platform,
// or facing the wall and its opening). One period of that flight is rendered before publishing
// starts, after one period to settle, and then published over and over, re-stamped: rendering a
// blurred 640x480 frame costs up to ~16 ms of one core, which at 60 Hz would compete with the
// vision for the machine's two cores. alight-sim itself is not used for the soak because, with
// no flight stack commanding it, its vehicle rests on the floor; with one, a mission ends within
// a minute. The seam between two periods is where the vehicle's tracking error (cm) jumps.
//
//   alight-vision-soak-source --scenario FILE --vehicle FILE [--rate-hz 60] [--loop-s 8]
//                             [--duration-s 600] [--seed N] [--summary FILE] [--lcm-url URL]
//
// At the end it writes a JSON summary: frames and poses published, and how late publications
// were against their schedule (a loaded machine delays the source too).

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <alight/image_t.hpp>
#include <alight/pose_t.hpp>
#include <chrono>
#include <cmath>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <thread>
#include <vector>

#include "common/image_msg.hpp"
#include "common/msg_convert.hpp"
#include "common/node.hpp"
#include "outer_loop/params.hpp"
#include "outer_loop/position_controller.hpp"
#include "sim/params.hpp"
#include "sim/simulator.hpp"
#include "soak_flight.hpp"

namespace {

using namespace alight;
using bench::record_one_period;
using bench::Recorded;

// The publications of one period, by release time within it (may run past the period's end).
struct Event {
  int64_t release_us;  // from the period's start
  bool frame;
  size_t index;
};

}  // namespace

int main(int argc, char** argv) {
  return alight::run_node_main("alight-vision-soak-source", [&]() -> int {
    CLI::App app("alight-vision-soak-source: rendered camera and motion capture, paced, looped");
    std::string scenario_file, vehicle_file, summary_file, frame_file;
    double rate_hz = 60.0, loop_s = 8.0, duration_s = 600.0;
    uint64_t seed = 1;
    NodeArgs args;
    app.add_option("--scenario", scenario_file, "Scenario (a platform or a wall)")
        ->required()
        ->check(CLI::ExistingFile);
    app.add_option("--vehicle", vehicle_file, "Vehicle file (cameras, outer loop)")
        ->required()
        ->check(CLI::ExistingFile);
    app.add_option("--rate-hz", rate_hz, "Camera rate")->check(CLI::Range(1.0, 240.0));
    app.add_option("--loop-s", loop_s, "Length of the rendered flight, published over and over")
        ->check(CLI::Range(0.5, 60.0));
    app.add_option("--duration-s", duration_s, "How long to publish frames [s]")
        ->check(CLI::Range(0.0, 86400.0));
    app.add_option("--seed", seed, "Scenario seed (textures, noise, wind)");
    app.add_option("--summary", summary_file, "Write the JSON summary here too");
    app.add_option("--save-frame", frame_file, "Write the period's middle frame here (PNG)");
    args.add_to(app, false);
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      return app.exit(e);
    }
    args.finalize();

    sim::Scenario scenario = sim::load_scenario(scenario_file);
    const double exposure_s = scenario.camera.exposure_s;
    scenario.camera.rate_hz = rate_hz;
    const auto t_render = std::chrono::steady_clock::now();
    const Recorded rec = record_one_period(scenario, vehicle_file, seed, loop_s, rate_hz);
    const double render_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t_render).count();
    if (rec.frames.empty()) throw std::runtime_error("no frame was rendered");
    if (!frame_file.empty()) cv::imwrite(frame_file, rec.frames[rec.frames.size() / 2].second);

    std::vector<Event> events;
    for (size_t i = 0; i < rec.frames.size(); ++i)
      events.push_back({rec.frames[i].first + rec.frame_release_us, true, i});
    for (size_t i = 0; i < rec.poses.size(); ++i)
      events.push_back({rec.poses[i].first + rec.pose_release_us, false, i});
    std::stable_sort(events.begin(), events.end(),
                     [](const Event& a, const Event& b) { return a.release_us < b.release_us; });

    Node node(args, "alight-vision-soak-source");
    node.set_status_period(0);
    // Stamps: the wall clock at the schedule's start plus the event's time in the schedule;
    // pacing: the steady clock, so a wall-clock step neither stalls nor bursts the camera.
    const int64_t steady0 = steady_utime() + 200'000, wall0 = wall_utime() + 200'000;
    const int64_t frames_end_us = static_cast<int64_t>(duration_s * 1e6);
    const int64_t poses_end_us = frames_end_us + 500'000;  // the last frames' poses
    int64_t n_frames = 0, n_poses = 0, late_over_5ms = 0, late_max_us = 0;
    std::vector<int64_t> lateness_us;
    // Two cursors: events of period k and of period k + 1 interleave where releases run past
    // the period's end.
    const auto time_of = [&](int64_t k, size_t i) {
      return k * rec.period_us + events[i].release_us;
    };
    int64_t k_a = 0, k_b = 1;
    size_t i_a = 0, i_b = 0;
    while (!node.stopping()) {
      const bool take_a =
          i_a < events.size() && (i_b >= events.size() || time_of(k_a, i_a) <= time_of(k_b, i_b));
      const int64_t k = take_a ? k_a : k_b;
      const size_t i = take_a ? i_a : i_b;
      const Event& e = events[i];
      const int64_t t_us = time_of(k, i);
      if (t_us >= poses_end_us) break;
      (take_a ? i_a : i_b)++;
      if (i_a >= events.size()) {
        k_a = k_b, i_a = i_b;
        k_b = k_a + 1, i_b = 0;
      }
      // A frame's or pose's own time in the schedule (exposure, sample).
      const int64_t own_us =
          k * rec.period_us + (e.frame ? rec.frames[e.index].first : rec.poses[e.index].first);
      if (e.frame && own_us >= frames_end_us) continue;
      const int64_t due = steady0 + t_us;
      const int64_t wait = due - steady_utime();
      if (wait > 0) std::this_thread::sleep_for(std::chrono::microseconds(wait));
      const int64_t late = steady_utime() - due;
      late_max_us = std::max(late_max_us, late);
      if (late > 5'000) ++late_over_5ms;
      if (e.frame) {
        image_t msg = image_to_msg(rec.frames[e.index].second, wall0 + own_us, n_frames);
        set_exposure_metadata(msg, exposure_s);
        node.publish(channels::kCamera, msg);
        ++n_frames;
        lateness_us.push_back(late);
      } else {
        PoseSample p = rec.poses[e.index].second;
        p.utime = wall0 + own_us;
        node.publish(channels::kMocapPose, to_msg(p, n_poses));
        ++n_poses;
      }
    }
    std::sort(lateness_us.begin(), lateness_us.end());
    const auto pct = [&](double q) {
      return lateness_us.empty()
                 ? 0.0
                 : 1e-3 * static_cast<double>(lateness_us[std::min(
                              lateness_us.size() - 1,
                              static_cast<size_t>(std::ceil(q * lateness_us.size())) - 1)]);
    };
    char json[1024];
    std::snprintf(json, sizeof json,
                  "{\"frames_published\": %lld, \"poses_published\": %lld, \"rate_hz\": %.3f, "
                  "\"period_frames\": %zu, \"period_s\": %.6f, \"render_s\": %.1f, "
                  "\"frame_late_p50_ms\": %.3f, \"frame_late_p99_ms\": %.3f, "
                  "\"late_max_ms\": %.3f, \"late_over_5ms\": %lld, \"interrupted\": %s}\n",
                  static_cast<long long>(n_frames), static_cast<long long>(n_poses),
                  1e6 / static_cast<double>(std::llround(1e6 / rate_hz)), rec.frames.size(),
                  1e-6 * static_cast<double>(rec.period_us), render_s, pct(0.5), pct(0.99),
                  1e-3 * static_cast<double>(late_max_us), static_cast<long long>(late_over_5ms),
                  node.stopping() ? "true" : "false");
    std::fputs(json, stdout);
    if (!summary_file.empty()) std::ofstream(summary_file) << json;
    return 0;
  });
}
