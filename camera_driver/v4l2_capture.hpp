#pragma once
// V4L2 streaming capture with mmap buffers and poll (the Video4Linux2 API, "Streaming I/O
// (Memory Mapping)"), driven entirely through SysIo so the tests run it against a scripted
// device. What it guarantees to its caller:
//  - the format actually in force is the one VIDIOC_S_FMT returned (drivers may change the
//    requested size; they may not change the pixel format without it being an error here);
//  - each grab() returns the NEWEST completed frame: older completed buffers are requeued
//    unpublished and counted as skipped, and a frame never older than one already returned
//    (stale queued frames are never delivered as new);
//  - gaps in the kernel's buffer sequence numbers are counted as frames the kernel dropped;
//  - ENODEV (unplug) is reported as kDeviceLost, never thrown, so the caller can reconnect;
//  - open() failures name the device and are classified (missing, busy, permission denied).

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "camera_driver/convert.hpp"
#include "camera_driver/device_select.hpp"
#include "camera_driver/sys_io.hpp"
#include "camera_driver/timestamp.hpp"

namespace alight::camera {

struct CaptureConfig {
  DeviceSpec device;                        ///< path or USB identity
  PixelFormat format = PixelFormat::kGrey;  ///< requested V4L2 pixel format
  int width = 640;                          ///< requested [px]
  int height = 480;                         ///< requested [px]
  double fps = 30.0;                        ///< requested frame rate [Hz]
  int exposure_us = -1;                     ///< manual exposure [us]; -1: auto
  int gain = -1;                            ///< manual gain [driver units]; -1: auto
  OutputEncoding encoding = OutputEncoding::kMono8;
  int buffer_count = 4;  ///< mmap buffers requested (driver may change)
};

enum class CaptureError {
  kNone,
  kNotFound,          ///< no such device node / USB camera (ENOENT, ENODEV, ENXIO at open)
  kBusy,              ///< another process streams from it (EBUSY)
  kPermissionDenied,  ///< EACCES / EPERM: not in group video, or udev rule missing
  kAmbiguous,         ///< a USB spec matches several cameras
  kNotCapture,        ///< not a video capture device with streaming I/O
  kFormatRejected,    ///< the requested pixel format is not offered
  kDeviceLost,        ///< ENODEV while streaming (unplugged)
  kIo,                ///< any other failed call
};
const char* to_string(CaptureError error);

struct Status {
  CaptureError error = CaptureError::kNone;
  std::string message;
  bool ok() const { return error == CaptureError::kNone; }
};

/// What the driver agreed to (VIDIOC_S_FMT / VIDIOC_S_PARM answers).
struct NegotiatedFormat {
  std::string path;  ///< the node opened
  PixelFormat format = PixelFormat::kGrey;
  int width = 0, height = 0, stride = 0;  ///< [px], [px], [bytes per row]
  double fps = 0.0;                       ///< 0 when the driver does not report it
  int buffers = 0;                        ///< mmap buffers granted
};

struct Frame {
  cv::Mat pixels;              ///< converted, owned (the kernel buffer is already requeued)
  int64_t buffer_mono_us = 0;  ///< the V4L2 buffer timestamp (CLOCK_MONOTONIC) [us]
  StampSource stamp_source = StampSource::kEndOfFrame;
  bool monotonic_clock = true;  ///< false: the driver's timestamps are not CLOCK_MONOTONIC
  uint32_t sequence = 0;        ///< the kernel's buffer sequence number
  uint32_t dropped = 0;         ///< kernel-dropped frames just before this one (sequence gap)
  uint32_t skipped = 0;         ///< newer-frame-wins: completed frames not returned before it
};

enum class GrabStatus {
  kFrame,       ///< `frame` holds the newest frame
  kTimeout,     ///< nothing completed within the timeout (or a wake-up with no buffer: EAGAIN)
  kBadFrame,    ///< a frame completed but was corrupt or did not convert (message says why)
  kDeviceLost,  ///< ENODEV: the device is gone; close() and reopen later
  kError,       ///< another failure; close() and reopen
};

struct GrabResult {
  GrabStatus status = GrabStatus::kTimeout;
  std::optional<Frame> frame;
  std::string message;
};

struct CaptureCounters {
  uint64_t frames = 0;         ///< frames returned
  uint64_t dropped = 0;        ///< kernel drops (sequence gaps)
  uint64_t skipped = 0;        ///< completed but superseded by a newer frame
  uint64_t stale = 0;          ///< completed with a timestamp not after the last returned
  uint64_t empty_wakeups = 0;  ///< poll said readable, DQBUF said EAGAIN
  uint64_t bad_frames = 0;     ///< error-flagged or unconvertible
};

/// One V4L2 mode, for --list.
struct Mode {
  uint32_t fourcc = 0;
  std::string description;
  int width = 0, height = 0;  ///< 0 for stepwise / continuous sizes (see `size_range`)
  std::string size_range;     ///< "min..max step" for non-discrete sizes
  std::vector<double> fps;    ///< discrete frame rates [Hz]
};

/// Every format, size and discrete frame rate an open device offers.
std::vector<Mode> enumerate_modes(SysIo& io, int fd);

class V4l2Capture {
 public:
  V4l2Capture(SysIo& io, CaptureConfig config);
  ~V4l2Capture();
  V4l2Capture(const V4l2Capture&) = delete;
  V4l2Capture& operator=(const V4l2Capture&) = delete;

  /// Selects the node, opens it non-blocking, negotiates format, rate and controls, maps the
  /// buffers and starts streaming. On failure everything is released again.
  Status open();
  /// Stops streaming and releases buffers and the descriptor (tolerates a vanished device).
  void close();
  bool is_open() const { return fd_ >= 0; }

  /// Waits up to timeout_ms for completed buffers and returns the newest (see the header).
  GrabResult grab(int timeout_ms);

  const NegotiatedFormat& format() const { return format_; }
  const CaptureCounters& counters() const { return counters_; }
  /// The node in use (with its USB identity, for a libusb reset); valid after open().
  const VideoNode& node() const { return node_; }
  /// Non-fatal findings of the last open(): size changed by the driver, missing controls.
  const std::vector<std::string>& warnings() const { return warnings_; }
  /// The exposure time the camera was set to [us] when open() set a manual exposure (after any
  /// clamping to the control's range); nullopt on automatic exposure or when a control failed.
  /// Published with each frame as "exposure_us" metadata (the vision's motion blur guard).
  std::optional<int64_t> exposure_us() const { return exposure_us_; }

 private:
  struct Buffer {
    void* start = nullptr;
    size_t length = 0;
  };
  Status open_node(const VideoNode& node);
  Status negotiate();
  void set_controls();
  Status start_streaming();
  Status fail(CaptureError error, const std::string& message);
  bool requeue(uint32_t index);

  SysIo& io_;
  CaptureConfig config_;
  int fd_ = -1;
  VideoNode node_;
  NegotiatedFormat format_;
  std::vector<Buffer> buffers_;
  bool streaming_ = false;
  int64_t last_sequence_ = -1;     ///< of the last dequeued buffer (any), -1 before the first
  int64_t last_returned_us_ = -1;  ///< timestamp of the last frame returned
  CaptureCounters counters_;
  std::vector<std::string> warnings_;
  std::optional<int64_t> exposure_us_;
};

}  // namespace alight::camera
