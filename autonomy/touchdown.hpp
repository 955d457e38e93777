#pragma once
// Touch-down detection (paper 3.4.1: "During this final phase the onboard accelerometer readings
// are employed to detect touch down and cut off the motor power").
//
// Primary cue: the impact. In flight the accelerometer measures the thrust over the mass, which
// in a descent is at most about g; the gear meeting the platform decelerates the body, a spike
// of the specific force's magnitude well above g. A second cue covers a soft touch-down that
// leaves no spike: the pose shows the body not descending for touchdown_still_s although the
// altitude setpoint lies well below it (the platform holds it up).
//
// Where the body's height at contact is known (the platform's top, or the floor, under the
// gear: set_contact_z), an impact counts only with the pose within kImpactReachM of it: an
// autopilot that brakes a descent hard on top of a noisy IMU puts a spike of the same size into
// the specific force with the gear still well above the top, and cutting the motors there drops
// the vehicle onto the top's edge (PX4 SIH in SITL: 4-5 m/s^2 over g with the gear 12-15 cm
// up).
//
// Where it is not known (a failsafe descent onto whatever lies below), an impact must be
// confirmed (confirm_impacts): a pose within kImpactConfirmS of it shows the body stopped, as
// PX4's and ArduPilot's land detectors want no vertical movement before they call the vehicle
// down. A spike while the vehicle is thrown about (an autopilot's own failsafe, a stalled
// machine's burst of samples) leaves it moving and is dropped; cutting the motors there drops
// the vehicle from the height it flies at. Only a blind descent, with no pose in that time,
// takes the impact alone: there is nothing else to go by.

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

  /// The body's height when the gear meets the surface below [m, world z]; from then on an
  /// impact counts only with the last pose within kImpactReachM above it.
  void set_contact_z(double z_m) { contact_z_m_ = z_m; }
  /// Without a contact height, an impact counts only once a pose confirms it (see above).
  void confirm_impacts() { confirm_ = true; }
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
  std::optional<double> contact_z_m_, last_z_m_;
  bool confirm_ = false;
  std::optional<int64_t> impact_utime_;  ///< an impact waiting for its confirmation (IMU time)
  int poses_since_impact_ = 0;
};

/// How far above the contact height an impact still counts [m]: the estimate's height error
/// (1-2 cm), a pose's latency times the descent's speed (about 1 cm) and a deck's heave
/// between predictions, with room to spare; a braking spike comes a gear's length and more up.
constexpr double kImpactReachM = 0.08;

/// An unconfirmed impact waits this long for a pose that shows the body stopped [s]: a few
/// poses at any motion-capture or estimator rate, and the time a descent at up to 1 m/s takes
/// to come to rest on its gear.
constexpr double kImpactConfirmS = 0.5;
/// Stopped: the vertical speed within this [m/s]; a failsafe descent flies at 0.3-0.4 m/s.
constexpr double kImpactStoppedMps = 0.1;

}  // namespace alight::autonomy
