#pragma once
// A real small-drone camera's imperfections for the simulated camera, each switched
// on by the scenario (CameraEffects, VibrationParams in params.hpp) and seeded from the
// simulator's seed. The simulator (simulator.cpp) applies them:
// - Rolling shutter: row v is exposed line_delay x v after row 0, each band of rows rendered
//   from the camera pose at its own time along the simulated trajectory (the model of Meingast,
//   Geyer and Sastry, "Geometric models of rolling-shutter cameras", OMNIVIS 2005; the per-row
//   pose of Hedborg, Forssen, Felsberg and Ringaby, "Rolling shutter bundle adjustment", CVPR
//   2012).
// - Motor vibration: a sum of sinusoids at the motors' rotation rate and its harmonics, as
//   angular and linear jitter of the airframe (so of every camera mount) and of the IMU, which
//   sees its rate and acceleration averaged over each sample exactly as it averages the flight
//   (ImuEmulator). Airframe vibration spectra are lines at the rotor rate and its multiples
//   (e.g. PX4's "Vibration isolation" guide; ArduPilot's harmonic notch filter is built on it).
// - Automatic-exposure steps: a step of the brightness by 2^EV that the exposure control brings
//   back over a number of frames.
// - Vignetting: natural vignetting, the cos^4 law of a thin lens (e.g. Goldman, "Vignette and
//   exposure calibration and compensation", PAMI 2010), as 1 / (1 + k rho^2)^2 over the image
//   radius rho normalised to the farthest corner, k set by the corner's ratio.
// - The driver's delivery: lost frames (a V4L2 sequence gap), frames delivered twice (the same
//   pixels under a new sequence number and stamp) and jittered stamps.

#include <cstdint>
#include <opencv2/core.hpp>
#include <random>

#include "common/camera_model.hpp"
#include "common/geometry.hpp"
#include "sim/params.hpp"

namespace alight::sim {

/// The airframe's vibration as a function of time since the simulation's start [s].
class Vibration {
 public:
  Vibration() = default;
  /// Phases drawn from `seed`, one per axis and harmonic, angular and linear apart.
  Vibration(const VibrationParams& params, uint64_t seed);
  bool enabled() const { return params_.enabled; }
  const VibrationParams& params() const { return params_; }
  /// Highest harmonic [Hz].
  double max_hz() const { return params_.base_hz * params_.harmonics; }
  /// Rotation vector of the shaken body in the body (small angles) [rad].
  Vector3d angle(double t_s) const;
  /// Offset of the shaken body's origin in the body [m].
  Vector3d offset(double t_s) const;
  /// The offset's velocity [m/s].
  Vector3d velocity(double t_s) const;
  /// X_BB': the shaken body in the body at t_s.
  Isometry3d jitter(double t_s) const;
  /// Mean angular rate over [t0_s, t1_s] (the angle's change over the interval) [rad/s].
  Vector3d mean_rate(double t0_s, double t1_s) const;
  /// Mean linear acceleration over [t0_s, t1_s] [m/s^2].
  Vector3d mean_accel(double t0_s, double t1_s) const;

 private:
  VibrationParams params_;
  // [harmonic][axis] phases [rad].
  double angle_phase_[3][3] = {}, linear_phase_[3][3] = {};
};

/// The automatic exposure's steps: per frame, the EV offset of its brightness.
class ExposureSteps {
 public:
  ExposureSteps() = default;
  /// `frame_rate_hz`: the camera's (a step starts on a frame with probability rate / frame rate).
  ExposureSteps(const CameraEffects& effects, double frame_rate_hz);
  /// The next frame's EV offset: a new step of U(-max_ev, max_ev) with the step probability,
  /// else the current one brought back linearly, 0 from lag_frames frames after it.
  double next_ev(std::mt19937_64& rng);
  /// Starts a step of `ev` on the next frame (tests).
  void start(double ev);

 private:
  double max_ev_ = 0, p_step_ = 0;
  int lag_ = 1;
  double step_ev_ = 0;
  int since_ = 1 << 30;  // frames since the step began
  bool forced_ = false;
};

/// Per-pixel brightness factor of natural vignetting: 1 at the principal point, corner_ratio at
/// the farthest image corner (CV_32F, the model's size).
cv::Mat vignetting_map(const CameraModel& model, double corner_ratio);

/// What the driver does with one frame.
struct DriverDraw {
  bool dropped = false;
  bool duplicated = false;  ///< the previous frame's pixels again
  double stamp_error_s = 0;
};
DriverDraw draw_driver(const CameraEffects& effects, std::mt19937_64& rng);

}  // namespace alight::sim
