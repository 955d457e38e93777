// alight-camera: a V4L2 camera (or a video file / image folder) into CAMERA image_t messages.
//
//   alight-camera --config config/cameras/usb_mono_640x480.yaml     # capture and publish
//   alight-camera --list                                             # USB cameras and modes
//   alight-camera --config ... --source file:flight.avi [--as-fast-as-possible] [--loop]
//   alight-camera --config ... --source folder:images/ --rate 10
//   alight-camera --config ... --reset                               # libusb reset, then exit
//
// Each frame: utime = the V4L2 buffer timestamp (CLOCK_MONOTONIC) moved to the middle of the
// exposure when the exposure is known, plus one CLOCK_REALTIME - CLOCK_MONOTONIC offset
// measured at start and kept; metadata "seq" (capture sequence, monotonic across reconnects,
// so gaps show every lost frame), "dropped" (frames the kernel dropped since start) and
// "skipped" (frames this process skipped to publish the newest one when it fell behind), and
// "exposure_us" when the camera took the configured manual exposure (the vision's motion blur
// guard uses it).
//
// Exit codes (the launcher and the user act on them):
//   0  stopped by SIGINT / SIGTERM, or the stored source ended (or --max-frames reached)
//   1  any other failure
//   2  bad configuration or command line
//   3  device missing (no such node, USB camera not plugged in, source file / folder absent)
//   4  device busy (another process streams from it)
//   5  permission denied (user not in group video / no udev rule)
//   6  unusable device: not a capture device, pixel format not offered, or the USB spec
//      matches several cameras
// Once streaming, an unplugged or stalled camera does not end the process: it reconnects with
// backoff (and a libusb reset of a stalled camera).

#include <spdlog/spdlog.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iostream>
#include <thread>

#include "camera_driver/device_list.hpp"
#include "camera_driver/frame_label.hpp"
#include "camera_driver/params.hpp"
#include "camera_driver/stored_source.hpp"
#include "camera_driver/supervisor.hpp"
#include "camera_driver/timestamp.hpp"
#include "common/build_paths.hpp"
#include "common/camera_model.hpp"
#include "common/image_msg.hpp"
#include "common/node.hpp"
#include "common/params.hpp"

namespace {

using namespace alight;
using namespace alight::camera;

enum ExitCode {
  kExitOk = 0,
  kExitConfig = 2,
  kExitMissing = 3,
  kExitBusy = 4,
  kExitPermission = 5,
  kExitUnusable = 6,
};

int exit_code(CaptureError e) {
  switch (e) {
    case CaptureError::kNone:
      return kExitOk;
    case CaptureError::kNotFound:
    case CaptureError::kDeviceLost:
      return kExitMissing;
    case CaptureError::kBusy:
      return kExitBusy;
    case CaptureError::kPermissionDenied:
      return kExitPermission;
    case CaptureError::kAmbiguous:
    case CaptureError::kNotCapture:
    case CaptureError::kFormatRejected:
      return kExitUnusable;
    case CaptureError::kIo:
      return 1;
  }
  return 1;
}

int64_t clock_us(clockid_t id) {
  timespec ts{};
  clock_gettime(id, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000;
}
int64_t mono_now_us() { return clock_us(CLOCK_MONOTONIC); }

int64_t measure_clock_offset_us() {
  std::vector<ClockSample> samples(16);
  for (auto& s : samples) {
    s.mono_before_us = clock_us(CLOCK_MONOTONIC);
    s.unix_us = clock_us(CLOCK_REALTIME);
    s.mono_after_us = clock_us(CLOCK_MONOTONIC);
  }
  return clock_offset_us(samples);
}

void sleep_us(int64_t us) {
  if (us > 0) std::this_thread::sleep_for(std::chrono::microseconds(us));
}

/// Counts publications and logs a summary every few seconds.
struct Publisher {
  Node& node;
  std::string channel;
  OutputEncoding encoding;
  uint64_t published = 0;
  int64_t last_report_us = 0;
  uint64_t last_report_count = 0;

  /// exposure_us: the exposure the camera was set to, published as metadata when known.
  void publish(const cv::Mat& pixels, int64_t utime, int64_t seq, uint64_t dropped,
               uint64_t skipped, std::optional<int64_t> exposure_us = std::nullopt) {
    image_t msg = image_to_msg(pixels, utime, seq);
    // image_to_msg copies bytes as they are and labels 3 channels BGR; rgb8 holds RGB bytes.
    if (encoding == OutputEncoding::kRgb8) msg.pixelformat = image_t::PIXEL_FORMAT_RGB;
    set_metadata_int(msg, "dropped", static_cast<int64_t>(dropped));
    set_metadata_int(msg, "skipped", static_cast<int64_t>(skipped));
    if (exposure_us) set_exposure_metadata(msg, double(*exposure_us) * 1e-6);
    node.publish(channel, msg);
    ++published;
  }
  void report(int64_t now_us, uint64_t dropped, uint64_t skipped) {
    if (last_report_us == 0) last_report_us = now_us;
    if (now_us - last_report_us < 10'000'000) return;
    const double rate = (published - last_report_count) * 1e6 / (now_us - last_report_us);
    spdlog::info(
        "alight-camera: {} frames on {} ({:.1f} fps), {} dropped by the kernel, {} "
        "skipped (behind)",
        published, channel, rate, dropped, skipped);
    last_report_us = now_us;
    last_report_count = published;
  }
};

/// Logs at most one message per second per kind, with the number it held back.
struct RateLimitedLog {
  int64_t last_us = -1'000'000'000;
  uint64_t held = 0;
  void warn(int64_t now_us, const std::string& text) {
    if (now_us - last_us < 1'000'000) {
      ++held;
      return;
    }
    if (held > 0) {
      spdlog::warn("alight-camera: {} ({} similar messages held back)", text, held);
    } else {
      spdlog::warn("alight-camera: {}", text);
    }
    held = 0;
    last_us = now_us;
  }
};

void check_camera_info(const CameraParams& p, int width, int height) {
  const CameraModel cam = load_camera_info(p.camera_info);
  if (cam.width != width || cam.height != height)
    spdlog::warn(
        "alight-camera: {} is calibrated for {}x{} but frames are {}x{}: consumers "
        "using these intrinsics will be wrong (run alight-calibrate)",
        p.camera_info, cam.width, cam.height, width, height);
}

struct Options {
  NodeArgs args;
  bool list = false;
  bool reset = false;
  std::string source = "camera";
  std::string device;
  bool as_fast_as_possible = false;
  bool loop = false;
  double rate_hz = 0.0;
  int64_t max_frames = 0;
};

int run_stored(const Options& o, const CameraParams& p, const SourceSpec& spec) {
  const OutputEncoding enc = *parse_output_encoding(p.output_encoding);
  std::string err;
  auto src = StoredSource::open(spec, enc, &err);
  if (!src) {
    spdlog::error("alight-camera: {}", err);
    return kExitMissing;
  }
  const double fps = o.rate_hz > 0 ? o.rate_hz : (src->fps() > 0 ? src->fps() : p.fps);
  spdlog::info("alight-camera: {} ({} frames) at {}, publishing {} on {}", spec.path,
               src->frame_count(),
               o.as_fast_as_possible ? std::string("full speed") : std::to_string(fps) + " fps",
               p.output_encoding, p.channel);
  const int64_t offset_us = measure_clock_offset_us();
  Node node(o.args, "alight-camera");
  Publisher pub{node, p.channel, enc};
  FramePacer pacer(fps, mono_now_us());
  int64_t seq = 0;
  uint64_t skipped = 0;
  bool first_check = true;
  while (!node.stopping() &&
         (o.max_frames <= 0 || static_cast<int64_t>(pub.published) < o.max_frames)) {
    if (!o.as_fast_as_possible) {
      const FramePacer::Plan plan = pacer.plan(mono_now_us());
      for (int64_t i = 0; i < plan.skip && src->skip(); ++i) ++skipped, ++seq;
      sleep_us(plan.wait_us);
    }
    // The stored frame's "buffer timestamp" is taken before it is decoded, as a kernel buffer
    // is stamped before the driver's frame is converted: latency measured from it includes
    // the decoding, as it would for an MJPEG camera.
    const int64_t mono = mono_now_us();
    std::optional<cv::Mat> frame = src->next(&err);
    if (!frame) {
      if (!err.empty()) {
        spdlog::error("alight-camera: {}", err);
        return 1;
      }
      if (o.loop && src->rewind()) {
        pacer.restart(mono_now_us());
        continue;
      }
      spdlog::info("alight-camera: end of {} after {} frames", spec.path, pub.published);
      return kExitOk;
    }
    if (first_check) {
      check_camera_info(p, frame->cols, frame->rows);
      first_check = false;
    }
    pub.publish(*frame, mono + offset_us, seq++, 0, skipped);
    pub.report(mono, 0, skipped);
  }
  return kExitOk;
}

int run_camera(const Options& o, const CameraParams& p) {
  auto io = make_linux_sys_io();
  const CaptureConfig config = capture_config(p);
  if (o.reset) {
    const Candidates c = candidate_nodes(config.device, io->video_nodes());
    if (c.nodes.empty() || !c.nodes.front().is_usb) {
      spdlog::error("alight-camera: {}: {}", p.device,
                    c.error.empty() ? "not a USB camera: nothing to reset" : c.error);
      return kExitMissing;
    }
    const std::string e = io->usb_reset(c.nodes.front().usb_bus, c.nodes.front().usb_address);
    if (!e.empty()) {
      spdlog::error("alight-camera: USB reset of {} failed: {}", p.device, e);
      return e.find("ccess") != std::string::npos ? kExitPermission : 1;
    }
    spdlog::info("alight-camera: USB reset of {} done", p.device);
    return kExitOk;
  }

  CameraSupervisor sup(*io, config, supervisor_params(p));
  const Status s = sup.start(mono_now_us());
  if (!s.ok()) {
    spdlog::error("alight-camera: cannot start {}: {}", p.device, s.message);
    return exit_code(s.error);
  }
  const NegotiatedFormat& f = sup.capture().format();
  spdlog::info(
      "alight-camera: {} streaming {} {}x{} at {} fps with {} buffers, publishing {} on {}", f.path,
      to_string(f.format), f.width, f.height, f.fps, f.buffers, p.output_encoding, p.channel);
  for (const auto& w : sup.capture().warnings()) spdlog::warn("alight-camera: {}", w);
  check_camera_info(p, f.width, f.height);

  const int64_t offset_us = measure_clock_offset_us();
  Node node(o.args, "alight-camera");
  Publisher pub{node, p.channel, *parse_output_encoding(p.output_encoding)};
  RateLimitedLog log;
  FrameLabeler labeler(offset_us, p.exposure_us);
  uint64_t reconnects = 0;
  bool warned_clock = false;
  while (!node.stopping() &&
         (o.max_frames <= 0 || static_cast<int64_t>(pub.published) < o.max_frames)) {
    const int64_t now = mono_now_us();
    CameraSupervisor::Step step = sup.step(now);
    for (const auto& e : step.events) log.warn(now, e);
    if (sup.reconnects() != reconnects) {
      reconnects = sup.reconnects();
      for (const auto& w : sup.capture().warnings()) spdlog::warn("alight-camera: {}", w);
    }
    if (step.frame) {
      const FrameLabel label = labeler.label(*step.frame, sup.reconnects(), mono_now_us());
      if (labeler.used_dequeue_time() && !warned_clock) {
        spdlog::warn(
            "alight-camera: {} does not stamp buffers with CLOCK_MONOTONIC; frames are "
            "stamped when dequeued (later than the exposure)",
            f.path);
        warned_clock = true;
      }
      const CaptureCounters& c = sup.capture().counters();
      pub.publish(step.frame->pixels, label.utime, label.seq, c.dropped, c.skipped,
                  sup.capture().exposure_us());
      pub.report(now, c.dropped, c.skipped);
    }
    sleep_us(std::min<int64_t>(step.sleep_us, 100'000));
  }
  return kExitOk;
}

int run(int argc, char** argv) {
  Options o;
  CLI::App app{"alight-camera: V4L2 camera, video file or image folder -> CAMERA (image_t)"};
  o.args.add_to(app, false);
  app.add_flag("--list", o.list, "List USB cameras (vendor:product:serial, V4L2 node, modes)");
  app.add_flag("--reset", o.reset, "Reset the configured USB camera through libusb and exit");
  app.add_option("--source", o.source, "camera (default), file:VIDEO.avi|mp4 or folder:DIR");
  app.add_option("--device", o.device,
                 "Override the config's device (path or usb:VVVV:PPPP[:SERIAL])");
  app.add_flag("--as-fast-as-possible", o.as_fast_as_possible,
               "Stored sources: publish without pacing");
  app.add_flag("--loop", o.loop, "Stored sources: start again at the end");
  app.add_option("--rate", o.rate_hz,
                 "Stored sources: frame rate [Hz] (default: the file's, "
                 "else the config's fps)")
      ->check(CLI::PositiveNumber);
  app.add_option("--max-frames", o.max_frames, "Stop after publishing this many frames");
  app.footer(
      "Exit codes: 0 stopped / source ended, 1 other failure, 2 bad configuration, 3 device "
      "missing, 4 device busy, 5 permission denied, 6 unusable device (not a capture device, "
      "format not offered, ambiguous USB spec).");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int r = app.exit(e);
    return r == 0 ? 0 : kExitConfig;
  }
  o.args.finalize();

  if (o.list) {
    auto io = make_linux_sys_io();
    std::cout << list_cameras(*io) << std::flush;
    return kExitOk;
  }
  CameraParams p;
  if (!o.args.config.empty()) {
    p = load_params(o.args.config);
  } else {
    // Defaults; the camera_info default is the paper's camera in the source tree's config.
    p.camera_info =
        (std::filesystem::path(alight::build::source_dir()) / "config" / "cameras" / p.camera_info)
            .string();
  }
  if (!o.device.empty()) {
    p.device = o.device;
    try {
      p.validate();
    } catch (const ParamError& e) {
      throw ParamError("--device", e.key(), e.value(), e.problem());
    }
  }
  std::string err;
  const auto spec = parse_source(o.source, &err);
  if (!spec) throw ParamError("--source", "", o.source, err);
  if (spec->kind != SourceSpec::Kind::kCamera) return run_stored(o, p, *spec);
  return run_camera(o, p);
}

}  // namespace

int main(int argc, char** argv) {
  return alight::run_node_main("alight-camera", [&] { return run(argc, argv); });
}
