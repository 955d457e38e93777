#pragma once
// The rendered flight of bench/vision/soak: the vehicle flown by the outer loop's
// position controller along a closed figure-eight in front of the target (over the platform, or
// facing the wall and its opening), one period of its frames and motion-capture poses kept.
// Shared by alight-vision-soak-source (publishes them over LCM) and alight_vision_cpu_bench
// (runs the pipeline on them in process).

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "outer_loop/params.hpp"
#include "outer_loop/position_controller.hpp"
#include "sim/params.hpp"
#include "sim/simulator.hpp"

namespace alight::bench {

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
inline Trajectory trajectory(const sim::Truth& truth, const sim::Scenario& scenario,
                             double period_s, double standoff_m = 2.0) {
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
    // standoff_m (2 m) in front of the opening, facing the wall: 0.3 m sideways, 0.12 m up and
    // down, and 0.3 m nearer and farther, so the wall's features change scale.
    const Vector3d n = opening->wall_normal_W;
    const Vector3d side = Vector3d::UnitZ().cross(n).normalized();
    tr.center_W = opening->center_W + standoff_m * n;
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
  std::optional<sim::OpeningTruth> opening;  // the wall's opening, if any (truth)
  double line_delay_s = 0.0;  // the frames' rolling-shutter row delay; 0: a global shutter [s]
};

// Flies two periods and keeps the second: frames exposed and poses sampled in it.
inline Recorded record_one_period(const sim::Scenario& scenario, const std::string& vehicle_file,
                                  uint64_t seed, double loop_s, double rate_hz,
                                  double standoff_m = 2.0) {
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
  const Trajectory tr = trajectory(simulator.truth(), scenario,
                                   1e-6 * static_cast<double>(rec.period_us), standoff_m);

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
      if (auto f = simulator.take_camera(); f && f->utime >= rec0 && f->utime < rec1) {
        rec.frames.emplace_back(f->utime - rec0, f->pixels);
        rec.line_delay_s = f->line_delay_s;
      }
    }
  }
  const sim::Truth truth = simulator.truth();
  rec.opening = truth.opening;
  const Vector3d err = truth.state.p_W_B - tr.p_W(1e-6 * static_cast<double>(rec1 - t0));
  spdlog::info(
      "soak source: {} frames and {} poses in a {:.3f} s period; tracking error at its end "
      "{:.1f} cm{}",
      rec.frames.size(), rec.poses.size(), 1e-6 * static_cast<double>(rec.period_us),
      100 * err.norm(), truth.collided || truth.tipped ? " (the vehicle hit something)" : "");
  return rec;
}

}  // namespace alight::bench
