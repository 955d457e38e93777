#pragma once
// alight-camera's configuration: one YAML file per camera under config/cameras/ (flat keys,
// e.g. config/cameras/usb_mono_640x480.yaml). Every key is optional; unknown keys are errors.
// The defaults are the initialisers below; `alight-params --defaults camera` prints every key
// with its unit, constraint and meaning.

#include <string>

#include "camera_driver/supervisor.hpp"
#include "camera_driver/v4l2_capture.hpp"
#include "common/channels.hpp"
#include "common/param_schema.hpp"

namespace alight::camera {

/// Upper bound of every camera timeout [s]: a camera that stays stuck or away for longer than
/// this is not worth waiting for any longer between attempts, and an infinite (".inf") or huge
/// value would switch the supervision off.
inline constexpr double kMaxTimeoutS = 60.0;

struct CameraParams {
  std::string device = "/dev/video0";
  std::string pixel_format = "GREY";
  std::string output_encoding = "mono8";
  int width = 640;
  int height = 480;
  double fps = 60.0;
  int exposure_us = -1;
  int gain = -1;
  int buffer_count = 4;
  std::string camera_info = "firefly_mv_4mm.yaml";  ///< resolved against the file's folder
  std::string channel = channels::kCamera;
  double backoff_initial_s = 0.1;
  double backoff_max_s = 5.0;
  double stall_timeout_s = 2.0;
  bool usb_reset_on_stall = true;

  /// Key, constraint, unit and meaning of each field (common/param_schema.hpp).
  static const ParamSchema<CameraParams>& schema();
  void validate() const;  ///< throws ParamError naming the field and its value
};

/// Reads and validates a camera file; camera_info comes back resolved against the file's folder.
CameraParams load_params(const std::string& path);

/// The capture and supervision settings of validated params.
CaptureConfig capture_config(const CameraParams& params);
SupervisorParams supervisor_params(const CameraParams& params);

}  // namespace alight::camera
