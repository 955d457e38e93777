#pragma once
// Touch-down detection (paper 3.4.1: "During this final phase the onboard accelerometer readings
// are employed to detect touch down and cut off the motor power").
//
// Primary cue: the impact. In flight the accelerometer measures the thrust over the mass, which
// in a descent is at most about g; the gear meeting the platform decelerates the body, a spike
// of the specific force's magnitude well above g. A second cue covers a soft touch-down that
// leaves no spike: the pose shows the body not descending for touchdown_still_s although the
// altitude setpoint lies well below it (the platform holds it up).

#include <cstdint>
#include <optional>

#include "autonomy/params.hpp"
#include "autonomy/types.hpp"

namespace alight::autonomy {

class TouchdownDetector {
 public:
  explicit TouchdownDetector(const LandingParams& params, double gravity_mps2 = 9.81)
      : params_(params), g_(gravity_mps2) {}

  /// Starts watching (at the start of the final descent or a failsafe descent).
  void arm(int64_t now_utime);
  void disarm() { armed_ = false; }
  bool armed() const { return armed_; }

  void add_imu(const ImuSample& imu);
  /// z_setpoint_m: the altitude currently commanded.
  void add_pose(const PoseSample& pose, double z_setpoint_m, int64_t now_utime);

  bool detected() const { return detected_; }
  /// "impact" or "resting", for the status reason.
  const char* cue() const { return cue_; }
  double peak_excess_mps2() const { return peak_excess_mps2_; }

 private:
  LandingParams params_;
  double g_;
  bool armed_ = false;
  bool detected_ = false;
  const char* cue_ = "";
  double peak_excess_mps2_ = 0.0;
  std::optional<int64_t> still_since_;
};

}  // namespace alight::autonomy
