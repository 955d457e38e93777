#include "camera_driver/params.hpp"

#include "camera_driver/convert.hpp"
#include "camera_driver/device_select.hpp"

namespace alight::camera {

const ParamSchema<CameraParams>& CameraParams::schema() {
  using P = CameraParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("device", &P::device, Range::any(), "",
          "a V4L2 node path, or usb:VVVV:PPPP[:SERIAL] (hex ids; alight-camera --list)")
        .check_with([](const P& p) {
          std::string why;
          return parse_device_spec(p.device, &why) ? std::string() : why;
        });
    s.add("pixel_format", &P::pixel_format, Range::any(), "",
          "what the camera sends: GREY (or GRAY), YUYV, MJPEG (or MJPG)")
        .check([](const P& p) { return parse_pixel_format(p.pixel_format).has_value(); },
               "must be GREY, YUYV or MJPEG");
    s.add("output_encoding", &P::output_encoding, Range::any(), "", "what CAMERA carries")
        .one_of({"mono8", "rgb8", "bgr8"});
    s.add("width", &P::width, Range::closed(1, 16384), "px",
          "requested width (the driver may change it; the log says so)")
        .check([](const P& p) { return p.pixel_format != "YUYV" || p.width % 2 == 0; },
               "must be even for YUYV (two pixels share U and V)");
    s.add("height", &P::height, Range::closed(1, 16384), "px", "requested height");
    s.add("fps", &P::fps, Range::open_closed(0, 1000), "Hz",
          "requested frame rate (Firefly MV class: up to 60)");
    s.add("exposure_us", &P::exposure_us, Range::ge(-1), "us", "manual exposure; -1 = auto")
        .check([](const P& p) { return p.exposure_us != 0; },
               "must be -1 (auto) or a positive time in us");
    s.add("gain", &P::gain, Range::ge(-1), "driver units", "manual gain; -1 = auto / unchanged");
    s.add("buffer_count", &P::buffer_count, Range::closed(2, 32), "", "mmap buffers to request");
    s.add("camera_info", &P::camera_info, Range::any(), "",
          "intrinsics (ROS camera_info; alight-calibrate writes one)")
        .path()
        .check([](const P& p) { return !p.camera_info.empty(); }, "must name a camera_info file");
    s.add("channel", &P::channel, Range::any(), "", "LCM channel of the frames")
        .check([](const P& p) { return !p.channel.empty(); }, "must not be empty");
    // Bounded (kMaxTimeoutS): an infinite or huge value would switch the supervision off.
    s.add("backoff_initial_s", &P::backoff_initial_s, Range::open_closed(0, kMaxTimeoutS), "s",
          "first wait before reconnecting after an unplug");
    s.add("backoff_max_s", &P::backoff_max_s, Range::le(kMaxTimeoutS), "s",
          "longest wait between reconnect attempts")
        .check([](const P& p) { return p.backoff_max_s >= p.backoff_initial_s; },
               "must be in [backoff_initial_s, 60] s");
    s.add("stall_timeout_s", &P::stall_timeout_s, Range::open_closed(0, kMaxTimeoutS), "s",
          "no good frame this long while streaming = stalled: reset over USB and reopen");
    s.add("usb_reset_on_stall", &P::usb_reset_on_stall, Range::any(), "",
          "reset a stalled USB camera through libusb");
    return s;
  }();
  return schema;
}

void CameraParams::validate() const { schema().validate(*this); }

CameraParams load_params(const std::string& path) {
  CameraParams p;
  CameraParams::schema().read(ParamNode::load_file(path), p);
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
