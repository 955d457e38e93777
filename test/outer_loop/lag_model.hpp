#pragma once
// A small stand-in for the inner loop and the vehicle, for controller tests that must not need the
// simulator: a point mass (double integrator with linear drag and a floor at z = 0) whose roll and
// pitch follow the command through a second-order lag (the autopilot's attitude loop), yaw
// integrates the commanded rate, and the thrust follows through a first-order motor lag.

#include <cmath>

#include "common/geometry.hpp"
#include "common/pose_buffer.hpp"
#include "outer_loop/setpoint.hpp"

namespace alight::outer_loop::test {

struct LagModel {
  double mass_kg = 1.2;
  double g = 9.81;
  double attitude_wn_radps = 2 * M_PI * 4.0;  // inner loop natural frequency
  double attitude_zeta = 0.8;
  double motor_tau_s = 0.03;
  double drag_Nspm = 0.25;
  bool floor = true;

  Vector3d p = Vector3d::Zero(), v = Vector3d::Zero();
  double roll = 0, pitch = 0, yaw = 0, roll_rate = 0, pitch_rate = 0, thrust_N = 0;

  void step(const AttitudeCommand& c, double dt) {
    const double w = attitude_wn_radps, z = attitude_zeta;
    const double roll_acc = w * w * (c.roll_rad - roll) - 2 * z * w * roll_rate;
    const double pitch_acc = w * w * (c.pitch_rad - pitch) - 2 * z * w * pitch_rate;
    roll_rate += roll_acc * dt;
    pitch_rate += pitch_acc * dt;
    roll += roll_rate * dt;
    pitch += pitch_rate * dt;
    yaw = wrap_angle(yaw + c.yaw_rate_radps * dt);
    const double t_cmd = c.armed ? c.thrust_N : 0.0;
    thrust_N += (t_cmd - thrust_N) * std::min(1.0, dt / motor_tau_s);
    const Matrix3d R = rotation_from_rpy(roll, pitch, yaw);
    Vector3d a =
        R * Vector3d(0, 0, thrust_N / mass_kg) - Vector3d(0, 0, g) - drag_Nspm / mass_kg * v;
    v += a * dt;
    p += v * dt;
    if (floor && p.z() < 0) {
      p.z() = 0;
      v.setZero();
    }
  }
  PoseSample pose(int64_t utime) const {
    PoseSample s;
    s.utime = utime;
    s.p_W_B = p;
    s.v_W_B = v;
    s.q_WB = Quaterniond(rotation_from_rpy(roll, pitch, yaw));
    return s;
  }
  /// Starts in hover at p0 with the hover thrust.
  void hover_at(const Vector3d& p0, double yaw0 = 0.0) {
    p = p0;
    v.setZero();
    roll = pitch = roll_rate = pitch_rate = 0;
    yaw = yaw0;
    thrust_N = mass_kg * g;
  }
};

}  // namespace alight::outer_loop::test
