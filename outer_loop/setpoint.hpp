#pragma once
// The interface between the autonomy loop and the outer loop (paper 3.4): a world-frame position
// and yaw setpoint, and the attitude / thrust command the outer loop sends to the inner loop.
// Domain forms of position_setpoint_t and attitude_cmd_t (conversions in outer_loop/convert.hpp).

#include <cstdint>

#include "common/geometry.hpp"

namespace alight::outer_loop {

struct PositionSetpoint {
  int64_t utime = 0;                ///< time of the autonomy input that produced it [us]
  Vector3d p_W = Vector3d::Zero();  ///< position setpoint, world [m]
  Vector3d v_W = Vector3d::Zero();  ///< feed-forward velocity, world [m/s]
  Vector3d a_W = Vector3d::Zero();  ///< feed-forward acceleration, world [m/s^2]
  double yaw_rad = 0.0;             ///< heading setpoint about world z [rad]
  double yaw_rate_radps = 0.0;      ///< feed-forward yaw rate about world z [rad/s]
  bool motors_on = false;           ///< false: motors off (landed, not yet taken off); honoured
                                    ///< in the air only with kill
  bool kill = false;                ///< operator KILL: disarm at once, even in the air
  bool idle = false;                ///< on the ground with motors at idle (no position control)
  bool precise = false;  ///< track with the precise lateral gains (landing's final hold and
                         ///< descent: a gust's offset there is the touch-down's error)
};

/// What the outer loop is doing, and why (maps onto attitude_cmd_t.MODE_*).
enum class Mode {
  kNormal,               ///< tracking a fresh setpoint with a fresh pose
  kHoldLevel,            ///< pose stale: level attitude, hover thrust, no lateral command
  kFailsafeDescent,      ///< pose lost: level attitude, open-loop slow descent, then disarm
  kHoldPosition,         ///< setpoint stale: hold the position where it went stale
  kSetpointLostDescent,  ///< setpoint lost: slow descent on the pose, disarm when on the ground
  kDisarmed,             ///< motors off
  kFailsafeLand,         ///< geofence left: hold, then land, then disarm
};

const char* mode_name(Mode mode);

struct AttitudeCommand {
  int64_t utime = 0;            ///< time of the newest input it was computed from [us]
  double roll_rad = 0.0;        ///< Z-Y-X Euler roll of the desired attitude [rad]
  double pitch_rad = 0.0;       ///< positive pitches the nose down: +x_B acceleration [rad]
  double yaw_rate_radps = 0.0;  ///< [rad/s]
  double thrust_N = 0.0;        ///< collective thrust along body z [N]
  bool armed = false;
  Mode mode = Mode::kDisarmed;
  const char* reason = "";  ///< static text: why this mode
};

}  // namespace alight::outer_loop
