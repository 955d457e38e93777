#include "camera_driver/params.hpp"

#include "common/camera_mount.hpp"
#include "common/params.hpp"

namespace alight::camera {

void CameraParams::validate() const {
  std::string why;
  param_check(parse_device_spec(device, &why).has_value(), "device", device, why);
  param_check(parse_pixel_format(pixel_format).has_value(), "pixel_format", pixel_format,
              "must be GREY, YUYV or MJPEG");
  param_check(parse_output_encoding(output_encoding).has_value(), "output_encoding",
              output_encoding, "must be mono8, rgb8 or bgr8");
  param_check(width > 0 && width <= 16384, "width", width, "must be in 1..16384 px");
  param_check(height > 0 && height <= 16384, "height", height, "must be in 1..16384 px");
  param_check(pixel_format != "YUYV" || width % 2 == 0, "width", width,
              "must be even for YUYV (two pixels share U and V)");
  param_check(fps > 0.0 && fps <= 1000.0, "fps", fps, "must be in (0, 1000] Hz");
  param_check(exposure_us == -1 || exposure_us > 0, "exposure_us", exposure_us,
              "must be -1 (auto) or a positive time in us");
  param_check(gain >= -1, "gain", gain, "must be -1 (auto) or >= 0");
  param_check(buffer_count >= 2 && buffer_count <= 32, "buffer_count", buffer_count,
              "must be in 2..32");
  param_check(!camera_info.empty(), "camera_info", camera_info, "must name a camera_info file");
  param_check(!channel.empty(), "channel", channel, "must not be empty");
  // Written so that NaN fails every check; the upper bounds refuse .inf.
  param_check(backoff_initial_s > 0.0 && backoff_initial_s <= kMaxTimeoutS, "backoff_initial_s",
              backoff_initial_s, "must be in (0, 60] s");
  param_check(backoff_max_s >= backoff_initial_s && backoff_max_s <= kMaxTimeoutS, "backoff_max_s",
              backoff_max_s, "must be in [backoff_initial_s, 60] s");
  param_check(stall_timeout_s > 0.0 && stall_timeout_s <= kMaxTimeoutS, "stall_timeout_s",
              stall_timeout_s, "must be in (0, 60] s");
}

CameraParams load_params(const std::string& path) {
  const ParamNode root = ParamNode::load_file(path);
  CameraParams p;
  root.read("device", p.device);
  root.read("pixel_format", p.pixel_format);
  root.read("output_encoding", p.output_encoding);
  root.read("width", p.width);
  root.read("height", p.height);
  root.read("fps", p.fps);
  root.read("exposure_us", p.exposure_us);
  root.read("gain", p.gain);
  root.read("buffer_count", p.buffer_count);
  root.read("camera_info", p.camera_info);
  root.read("channel", p.channel);
  root.read("backoff_initial_s", p.backoff_initial_s);
  root.read("backoff_max_s", p.backoff_max_s);
  root.read("stall_timeout_s", p.stall_timeout_s);
  root.read("usb_reset_on_stall", p.usb_reset_on_stall);
  root.finish();
  root.validate(p);
  p.camera_info = resolve_relative(path, p.camera_info);
  return p;
}

CaptureConfig capture_config(const CameraParams& p) {
  CaptureConfig c;
  c.device = *parse_device_spec(p.device, nullptr);
  c.format = *parse_pixel_format(p.pixel_format);
  c.encoding = *parse_output_encoding(p.output_encoding);
  c.width = p.width;
  c.height = p.height;
  c.fps = p.fps;
  c.exposure_us = p.exposure_us;
  c.gain = p.gain;
  c.buffer_count = p.buffer_count;
  return c;
}

SupervisorParams supervisor_params(const CameraParams& p) {
  SupervisorParams s;
  s.backoff_initial_s = p.backoff_initial_s;
  s.backoff_max_s = p.backoff_max_s;
  s.stall_timeout_s = p.stall_timeout_s;
  s.usb_reset_on_stall = p.usb_reset_on_stall;
  return s;
}

}  // namespace alight::camera
