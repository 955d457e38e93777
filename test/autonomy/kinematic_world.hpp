#pragma once
// A kinematic stand-in for outer loop + vehicle for the autonomy state-machine tests (no
// simulator needed): the position follows the setpoint with a 0.3 s lag and at most 1 m/s; with
// motors off the vehicle drops to whatever is below it; landing on something faster than 0.1 m/s
// gives an accelerometer impact spike. Time is injected: 10 ms per step.

#include <cmath>
#include <functional>
#include <optional>

#include "autonomy/autonomy.hpp"
#include "oracle_vision.hpp"

namespace alight::autonomy::test {

inline constexpr int64_t kT0 = 1'700'000'000'000'000;

inline AutonomyParams test_params() {
  AutonomyParams p;
  p.accept_unsigned_commands = true;
  p.landing.gear_height_m = 0.1;
  p.detection.landing_area_min_W_m = Vector2d(-0.5, -0.5);
  p.detection.landing_area_max_W_m = Vector2d(2.0, 1.5);
  p.geofence.max_W_m = Vector3d(4.5, 3, 2.5);
  return p;
}

inline OperatorCommand command(Command c, int64_t seq, Mission m = Mission::kNone) {
  OperatorCommand cmd;
  cmd.command = c;
  cmd.seq = seq;
  cmd.sender = "gs";
  cmd.mission = m;
  cmd.auth = CommandAuth::kNone;
  return cmd;
}

struct KinematicWorld {
  explicit KinematicWorld(const AutonomyParams& params = test_params(),
                          const OracleVisionParams& vp = {}, const RestartState& restored = {})
      : autonomy(params, restored), vision(vp), gear_height_m(params.landing.gear_height_m) {
    truth.has_platform = true;
    truth.platform_center_W = Vector3d(1.0, 0.5, 0.2);
    truth.platform_size_m = Vector3d(0.432, 0.279, 0.2);
    truth.has_opening = true;
    truth.opening_center_W = Vector3d(3.0, 0.0, 1.2);
    truth.opening_size_m = Vector2d(1.0, 0.8);
    truth.wall_normal_W = Vector3d(-1, 0, 0);
    p = Vector3d(0, 0, gear_height_m);
  }

  Autonomy autonomy;
  OracleVision vision;
  OracleTruth truth;
  double gear_height_m;
  Vector3d p, v = Vector3d::Zero();
  double yaw = 0.0;
  int64_t t = kT0;
  Output out;
  bool mocap = true;      ///< false: no pose reaches autonomy (dropout)
  bool vision_on = true;  ///< false: no VISION_TARGET at all
  bool impact = false;    ///< an impact spike happened in the last step
  int64_t seq = 0;
  int64_t last_mocap_t = kT0;
  /// Applied to every measurement of the oracle vision (a corrupt VISION_TARGET).
  std::function<void(TargetMeasurement&)> corrupt_target;
  /// The onboard estimate's health (STATE_ESTIMATE, issue 17), sent every step stamped with its
  /// time; none: no STATE_ESTIMATE at all (flying on motion capture).
  std::optional<EstimateHealth> estimate;
  /// A platform moving round a circle (its top level, its axes still): its centre at
  /// circle_centre_W + circle_r_m (cos, sin)(circle_speed_mps t / r), and vision's moving-top
  /// measurement (VISION_PLATFORM, exact) every third step. Zero speed: a still platform.
  double circle_speed_mps = 0.0, circle_r_m = 0.5;
  Vector2d circle_centre_W = Vector2d(1.0, 0.5);
  /// The moving top measured only while the vehicle is this near its centre, horizontally [m]
  /// (the top seen whole near the nadir); infinite: always.
  double platform_seen_within_m = INFINITY;
  /// The vehicle follows the setpoint's velocity too (the outer loop's feed-forward): a moving
  /// platform is followed without the position lag's trail.
  bool feed_forward = false;

  double ground_z(const Vector3d& q) const {
    if (truth.has_platform) {
      const Vector3d d = q - truth.platform_center_W;
      if (std::abs(d.x()) <= truth.platform_size_m.x() / 2 &&
          std::abs(d.y()) <= truth.platform_size_m.y() / 2) {
        return truth.platform_center_W.z() + gear_height_m;
      }
    }
    return gear_height_m;
  }

  PoseSample pose() const {
    PoseSample s;
    s.utime = t;
    s.p_W_B = p;
    s.v_W_B = v;
    s.q_WB = Quaterniond(rotation_from_rpy(0, 0, yaw));
    return s;
  }

  void step(std::optional<OperatorCommand> cmd = std::nullopt,
            std::optional<TargetMeasurement> target = std::nullopt) {
    const double dt = 0.01;
    t += 10'000;
    impact = false;
    const Vector3d before = p;
    if (mocap) last_mocap_t = t;
    const double mocap_age_s = (t - last_mocap_t) * 1e-6;
    if (out.setpoint.motors_on && mocap_age_s > 1.0) {
      p.z() -= 0.4 * dt;  // the outer loop's open-loop failsafe descent
    } else if (out.setpoint.motors_on && mocap_age_s > 0.3) {
      // the outer loop holds level: drifts nowhere in this model
    } else if (out.setpoint.motors_on) {
      Vector3d vel =
          (out.setpoint.p_W - p) / 0.3 + (feed_forward ? out.setpoint.v_W : Vector3d::Zero());
      if (vel.norm() > 1.0) vel *= 1.0 / vel.norm();
      p += vel * dt;
      yaw = out.setpoint.yaw_rad;
    } else {
      p.z() -= 1.0 * dt;
    }
    const double g = ground_z(p);
    double vz = (p.z() - before.z()) / dt;
    if (p.z() < g) {
      impact = vz < -0.1;
      p.z() = g;
    }
    v = (p - before) / dt;
    Inputs in;
    if (mocap) in.pose = pose();
    ImuSample imu;
    imu.utime = t;
    if (impact) imu.accel_B.z() += 50.0 * -vz;
    in.imu = imu;
    if (cmd) {
      cmd->utime = t;
      in.command = cmd;
    }
    if (estimate) {
      in.estimate = estimate;
      in.estimate->utime = t;
    }
    truth.vehicle = pose();
    if (circle_speed_mps > 0) {
      move_platform();
      const double off_m = (p - truth.platform_center_W).head<2>().norm();
      if ((t - kT0) % 30'000 == 0 && off_m <= platform_seen_within_m)
        in.platform = platform_measurement();
    }
    if (target) {
      in.target = target;
    } else if (vision_on) {
      in.target = vision.update(truth, t);
      if (in.target && corrupt_target) corrupt_target(*in.target);
    }
    out = autonomy.update(in, t);
  }

  Vector2d circle_p(int64_t at) const {
    const double a = circle_speed_mps * double(at - kT0) * 1e-6 / circle_r_m;
    return circle_centre_W + circle_r_m * Vector2d(std::cos(a), std::sin(a));
  }
  void move_platform() { truth.platform_center_W.head<2>() = circle_p(t); }
  PlatformMeasurement platform_measurement() const {
    PlatformMeasurement m;
    m.utime = t;
    m.ref_utime = t - 250'000;
    m.p_W = truth.platform_center_W;
    m.v_W.head<2>() = (circle_p(t) - circle_p(m.ref_utime)) / 0.25;
    m.cov_p_W = 1e-4 * Matrix3d::Identity();
    m.cov_v_W = 2.5e-3 * Matrix3d::Identity();
    m.var_yaw = 1e-4;
    m.var_yaw_rate = 1e-4;
    m.size_m = truth.platform_size_m.head<2>();
    return m;
  }

  void send(Command c, Mission m = Mission::kNone) { step(command(c, ++seq, m)); }

  /// Steps until pred() or the time limit; returns whether pred() held.
  template <class Pred>
  bool run_until(Pred pred, double limit_s) {
    const int64_t end = t + static_cast<int64_t>(limit_s * 1e6);
    while (t < end) {
      step();
      if (pred()) return true;
    }
    return false;
  }
  bool run_until_phase(Phase ph, double limit_s) {
    return run_until([&] { return autonomy.phase() == ph; }, limit_s);
  }
  void takeoff_and_hover() {
    step();
    send(Command::kTakeoff);
    run_until_phase(Phase::kHover, 10.0);
  }
  /// Takes off, sends GO for `mission` and steps until APPROACH; whether it got there.
  bool go_to_approach(Mission mission, double limit_s = 120) {
    takeoff_and_hover();
    send(Command::kGo, mission);
    return run_until_phase(Phase::kApproach, limit_s);
  }
};

}  // namespace alight::autonomy::test
