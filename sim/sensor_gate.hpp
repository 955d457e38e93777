#pragma once
// The simulator's test hook (SIM_CONTROL, lcmtypes/sim_control_t.lcm): silences MOCAP_POSE,
// CAMERA or IMU for a stretch of sim time, so the fault campaign (scripts/faults) can drop
// motion capture for 0.5 s, 2 s or for good, and stall the camera, while the vehicle flies on.
// Pure: the node passes the sim time in.

#include <alight/sim_control_t.hpp>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>

namespace alight::sim {

class SensorGate {
 public:
  /// Silent for `off_s` of sim time from `now_utime` (0: on again at once; negative: unchanged).
  void command(double off_s, int64_t now_utime) {
    if (off_s < 0) return;
    off_until_utime_ = now_utime + static_cast<int64_t>(std::llround(off_s * 1e6));
  }
  bool on(int64_t now_utime) const { return now_utime >= off_until_utime_; }

 private:
  int64_t off_until_utime_ = 0;
};

struct SensorGates {
  SensorGate mocap, camera, imu;

  /// Applies a request, or refuses all of it (non-finite, or above MAX_OFF_S) with the reason.
  std::optional<std::string> apply(const sim_control_t& m, int64_t now_utime) {
    for (double v : {m.mocap_off_s, m.camera_off_s, m.imu_off_s})
      if (!std::isfinite(v) || v > sim_control_t::MAX_OFF_S)
        return "SIM_CONTROL duration " + std::to_string(v) + " s: not finite or above MAX_OFF_S";
    mocap.command(m.mocap_off_s, now_utime);
    camera.command(m.camera_off_s, now_utime);
    imu.command(m.imu_off_s, now_utime);
    return std::nullopt;
  }
};

}  // namespace alight::sim
