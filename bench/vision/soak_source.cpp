// alight-vision-soak-source: the camera and motion capture of bench/vision/soak (issue 15, "keep
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

#include "common/msg_convert.hpp"
#include "common/node.hpp"
#include "outer_loop/params.hpp"
#include "outer_loop/position_controller.hpp"
#include "sim/params.hpp"
#include "sim/simulator.hpp"

namespace {

using namespace alight;

// A closed figure-eight of period T in front of the target: position and velocity at time t.
struct Trajectory {
  Vector3d center_W;
  Vector3d axis_a_W, axis_b_W, axis_c_W;  // amplitudes along three directions [m]
  double period_s;
  double yaw_rad;

  Vector3d p_W(double t) const {
    const double w = 2 * M_PI / period_s;
    return center_W + std::sin(w * t) * axis_a_W + std::sin(2 * w * t) * axis_b_W +
           std::sin(w * t + M_PI / 3) * axis_c_W;
  }
  Vector3d v_W(double t) const {
    const double w = 2 * M_PI / period_s;
    return w * std::cos(w * t) * axis_a_W + 2 * w * std::cos(2 * w * t) * axis_b_W +
           w * std::cos(w * t + M_PI / 3) * axis_c_W;
  }
};

// Over the platform, or in front of the opening; over the area's centre when there is no
// platform, in front of the wall's middle when it has no opening (the families that must find
// nothing).
Trajectory trajectory(const sim::Truth& truth, const sim::Scenario& scenario, double period_s) {
  Trajectory tr;
  tr.period_s = period_s;
  std::optional<sim::OpeningTruth> opening = truth.opening;
  if (!opening && scenario.wall) {
    opening.emplace();
    opening->center_W =
        Vector3d(scenario.wall->x_m, scenario.wall->center_y_m, 0.5 * scenario.wall->height_m);
  }
  if (!scenario.wall) {
    // 1.2 m over the platform top (the downward camera sees +-0.55 m around it), 0.3 m either
    // way along x, 0.15 m along y, 0.15 m up and down: 0.25 m/s at most with an 8 s period.
    const Vector3d top =
        truth.platform ? truth.platform->top_center_W
                       : Vector3d(scenario.area_center_xy_m.x(), scenario.area_center_xy_m.y(), 0);
    tr.center_W = top + Vector3d(0, 0, 1.2);
    tr.axis_a_W = Vector3d(0.3, 0, 0);
    tr.axis_b_W = Vector3d(0, 0.15, 0);
    tr.axis_c_W = Vector3d(0, 0, 0.15);
    tr.yaw_rad = 0.0;
  } else {
    // 2 m in front of the opening, facing the wall: 0.3 m sideways, 0.12 m up and down, and
    // 0.3 m nearer and farther, so the wall's features change scale.
    const Vector3d n = opening->wall_normal_W;
    const Vector3d side = Vector3d::UnitZ().cross(n).normalized();
    tr.center_W = opening->center_W + 2.0 * n;
    tr.axis_a_W = 0.3 * side;
    tr.axis_b_W = Vector3d(0, 0, 0.12);
    tr.axis_c_W = 0.3 * n;
    tr.yaw_rad = std::atan2(-n.y(), -n.x());
  }
  return tr;
}

struct Recorded {
  std::vector<std::pair<int64_t, cv::Mat>> frames;    // (exposure offset in the period, pixels)
  std::vector<std::pair<int64_t, PoseSample>> poses;  // (sample offset in the period, pose)
  int64_t period_us = 0;
  int64_t frame_release_us = 0;  // exposure -> available (half the exposure + camera latency)
  int64_t pose_release_us = 0;   // sample -> published (motion-capture latency)
};

// Flies two periods and keeps the second: frames exposed and poses sampled in it.
Recorded record_one_period(const sim::Scenario& scenario, const std::string& vehicle_file,
                           uint64_t seed, double loop_s, double rate_hz) {
  const sim::VehicleParams vehicle = sim::load_vehicle_params(vehicle_file);
  const auto rig = sim::load_camera_rig(vehicle_file, scenario.camera.mount);
  sim::Simulator simulator(scenario, vehicle, seed, rig);
  outer_loop::PositionController controller(outer_loop::load_params(vehicle_file));

  Recorded rec;
  const int64_t frame_period_us = std::llround(1e6 / rate_hz);
  const int64_t n_frames = std::max<int64_t>(1, std::llround(loop_s * rate_hz));
  rec.period_us = n_frames * frame_period_us;
  rec.frame_release_us = std::llround(0.5 * scenario.camera.exposure_s * 1e6) +
                         std::llround(scenario.camera.latency_s * 1e6);
  rec.pose_release_us = std::llround(scenario.mocap.latency_s * 1e6);
  const Trajectory tr =
      trajectory(simulator.truth(), scenario, 1e-6 * static_cast<double>(rec.period_us));

  const int64_t t0 = simulator.now_utime();
  sim::VehicleState start;
  start.p_W_B = tr.p_W(0);
  start.v_W_B = tr.v_W(0);
  start.q_WB = Quaterniond(Eigen::AngleAxisd(tr.yaw_rad, Vector3d::UnitZ()));
  start.yaw_des_rad = tr.yaw_rad;
  start.thrust_N = vehicle.hover_thrust_N();
  start.armed = true;
  simulator.set_state(start);

  const int64_t rec0 = t0 + rec.period_us, rec1 = rec0 + rec.period_us;
  std::optional<PoseSample> pose;
  outer_loop::AttitudeCommand att;
  const auto setpoint = [&](int64_t now) {
    const double t = 1e-6 * static_cast<double>(now - t0);
    outer_loop::PositionSetpoint sp;
    sp.utime = now;
    sp.p_W = tr.p_W(t);
    sp.v_W = tr.v_W(t);
    sp.yaw_rad = tr.yaw_rad;
    sp.motors_on = true;
    return sp;
  };
  for (int64_t now = t0; now < rec1 + 100'000;) {
    const sim::AttitudeCommand cmd{att.utime,          att.roll_rad, att.pitch_rad,
                                   att.yaw_rate_radps, att.thrust_N, att.armed};
    now += 5'000;
    simulator.step(cmd, now);
    for (const auto& m : simulator.take_mocap()) {
      pose = m.pose;
      att = controller.update(setpoint(m.pose.utime), pose, m.pose.utime);
      if (m.pose.utime >= rec0 && m.pose.utime < rec1)
        rec.poses.emplace_back(m.pose.utime - rec0, m.pose);
    }
    att = controller.update(setpoint(now), pose, now);
    simulator.take_imu();
    // Frames are rendered only when taken: the first period is flown without rendering.
    if (now + 50'000 >= rec0) {
      if (auto f = simulator.take_camera(); f && f->utime >= rec0 && f->utime < rec1)
        rec.frames.emplace_back(f->utime - rec0, f->pixels);
    }
  }
  const sim::Truth truth = simulator.truth();
  const Vector3d err = truth.state.p_W_B - tr.p_W(1e-6 * static_cast<double>(rec1 - t0));
  spdlog::info(
      "soak source: {} frames and {} poses in a {:.3f} s period; tracking error at its end "
      "{:.1f} cm{}",
      rec.frames.size(), rec.poses.size(), 1e-6 * static_cast<double>(rec.period_us),
      100 * err.norm(), truth.collided || truth.tipped ? " (the vehicle hit something)" : "");
  return rec;
}

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
        node.publish(channels::kCamera,
                     image_to_msg(rec.frames[e.index].second, wall0 + own_us, n_frames));
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
