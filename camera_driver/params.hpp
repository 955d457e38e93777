#pragma once
// alight-camera's configuration: one YAML file per camera under config/cameras/ (flat keys,
// e.g. config/cameras/usb_mono_640x480.yaml). Every key is optional; unknown keys are errors.

#include <string>

#include "camera_driver/supervisor.hpp"
#include "camera_driver/v4l2_capture.hpp"

namespace alight::camera {

/// Upper bound of every camera timeout [s]: a camera that stays stuck or away for longer than
/// this is not worth waiting for any longer between attempts, and an infinite (".inf") or huge
/// value would switch the supervision off.
inline constexpr double kMaxTimeoutS = 60.0;

struct CameraParams {
  std::string device = "/dev/video0";     ///< a V4L2 node path, or usb:VVVV:PPPP[:SERIAL] (hex ids)
  std::string pixel_format = "GREY";      ///< GREY | YUYV | MJPEG: what the camera sends
  std::string output_encoding = "mono8";  ///< mono8 | rgb8 | bgr8: what CAMERA carries
  int width = 640;                        ///< requested width [px] (the driver may change it)
  int height = 480;                       ///< requested height [px]
  double fps = 60.0;     ///< requested frame rate [Hz] (Firefly MV class: up to 60)
  int exposure_us = -1;  ///< manual exposure [us]; -1 = auto exposure
  int gain = -1;         ///< manual gain [driver units]; -1 = auto / unchanged
  int buffer_count = 4;  ///< mmap buffers to request (>= 2)
  std::string camera_info = "firefly_mv_4mm.yaml";  ///< intrinsics; relative to this file
  std::string channel = "CAMERA";                   ///< LCM channel of the frames
  double backoff_initial_s = 0.1;  ///< first wait before reconnecting, in (0, kMaxTimeoutS] [s]
  double backoff_max_s = 5.0;      ///< longest wait between reconnect attempts, <= kMaxTimeoutS [s]
  double stall_timeout_s = 2.0;    ///< no good frame this long while streaming = stalled,
                                   ///< in (0, kMaxTimeoutS] [s]
  bool usb_reset_on_stall = true;  ///< reset a stalled USB camera through libusb

  void validate() const;  ///< throws ParamError naming the field and its value
};

/// Reads and validates a camera file; camera_info comes back resolved against the file's folder.
CameraParams load_params(const std::string& path);

/// The capture and supervision settings of validated params.
CaptureConfig capture_config(const CameraParams& params);
SupervisorParams supervisor_params(const CameraParams& params);

}  // namespace alight::camera
