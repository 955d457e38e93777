#pragma once
// A moving platform's pose and velocity as a function of time: a cart, a vehicle's
// roof, a boat's deck. Closed form, so the simulator's step, its renderer and the tests all see
// the same platform at the same time: the path is travelled along straights and circular arcs
// (line: a stadium; circle; figure_eight: two circles touching where it starts) at a constant
// speed, or slowing at a constant rate for turns whose course rate is bounded (a cart keeps its
// grip), with a constant drift and turn added, and the deck heaves, rolls and pitches as sines
// and as a seeded sum of sines over a band (a random sea state, as ship-motion simulators draw
// one from a wave spectrum, here flat over the band).

#include <cstdint>
#include <vector>

#include "common/geometry.hpp"
#include "sim/params.hpp"

namespace alight::sim {

/// Where a platform is at one time, and how fast it moves there.
struct PlatformPose {
  Vector3d top_center_W = Vector3d::Zero();               ///< centre of the top face [m]
  double roll_rad = 0.0, pitch_rad = 0.0, yaw_rad = 0.0;  ///< Z-Y-X, R = Rz Ry Rx
  Matrix3d R_WO = Matrix3d::Identity();                   ///< its axes in world
  Vector3d v_W = Vector3d::Zero();                        ///< velocity of the top centre [m/s]
  Vector3d omega_W = Vector3d::Zero();                    ///< angular velocity, world axes [rad/s]
  /// Velocity of a point fixed to the platform that is at p_W now [m/s].
  Vector3d velocity_at(const Vector3d& p_W) const {
    return v_W + omega_W.cross(p_W - top_center_W);
  }
};

class PlatformMotion {
 public:
  /// `top0_W`, `yaw0_rad`: the platform's place at t = 0 (the scene's drawn placement);
  /// `seed`: the sea state's draws (a stream of their own).
  PlatformMotion(const PlatformMotionParams& params, const Vector3d& top0_W, double yaw0_rad,
                 uint64_t seed);

  /// The pose at `t_s` seconds after the start.
  PlatformPose at(double t_s) const;

  /// One sine: amplitude sin(2 pi frequency t + phase).
  struct Sine {
    double amplitude = 0.0, frequency_hz = 0.0, phase_rad = 0.0;
    double value(double t) const;
    double rate(double t) const;
  };
  /// The sea state's components of heave [m], roll and pitch [rad] (tests).
  const std::vector<Sine>& sea_heave() const { return sea_[0]; }
  const std::vector<Sine>& sea_roll() const { return sea_[1]; }
  const std::vector<Sine>& sea_pitch() const { return sea_[2]; }

  /// The path alone, in its own frame (x along path_heading_deg, origin at the start): offset
  /// at arc length s [m], the direction of travel relative to the start [rad] and the signed
  /// curvature [1/m] (left turns positive).
  struct PathPoint {
    Vector2d offset = Vector2d::Zero();
    double heading_rad = 0.0;
    double curvature = 0.0;
  };
  static PathPoint path_point(const PlatformMotionParams& params, double s_m);

  /// How far along the path the platform is `t_s` seconds after the start, and how fast it goes
  /// there [m, m/s]: speed_mps throughout, or turn_speed_mps() in the turns with the straights
  /// between entered and left at it, speeding up and slowing at kTurnAccelMps2.
  struct Travel {
    double s_m = 0.0, speed_mps = 0.0;
  };
  static Travel travel(const PlatformMotionParams& params, double t_s);

 private:
  PlatformMotionParams params_;
  Vector3d top0_W_;
  double yaw0_rad_;
  Sine heave_, roll_, pitch_;
  std::vector<Sine> sea_[3];
};

}  // namespace alight::sim
