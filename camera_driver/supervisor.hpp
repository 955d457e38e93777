#pragma once
// Keeps a camera streaming through what field cameras do: unplugged cables (ENODEV), devices
// that stop delivering frames (stalls), and re-enumeration after a USB reset. The first open
// is the caller's to judge (a wrong device in the config must stop the node with a clear exit
// code); after that every loss is retried with exponential backoff instead of exiting, because
// a vehicle in flight is better served by a camera that comes back than by a dead process.
// Time is passed in (monotonic microseconds), so tests step through minutes of reconnecting
// in no time.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "camera_driver/v4l2_capture.hpp"

namespace alight::camera {

/// Exponential backoff: initial, initial*factor, ... capped at max.
class ReconnectBackoff {
 public:
  ReconnectBackoff(double initial_s, double max_s, double factor = 2.0);
  /// The wait before the next attempt [us]; each call lengthens the following one.
  int64_t next_delay_us();
  void reset() { next_s_ = initial_s_; }

 private:
  double initial_s_, max_s_, factor_, next_s_;
};

struct SupervisorParams {
  double backoff_initial_s = 0.1;  ///< first wait after a loss [s]
  double backoff_max_s = 5.0;      ///< longest wait between attempts [s]
  double stall_timeout_s = 2.0;    ///< no good frame for this long while streaming = stuck,
                                 ///< whether the device is silent or sends only corrupt frames [s]
  bool usb_reset_on_stall = true;  ///< reset a stuck USB camera through libusb before reopening
  int grab_timeout_ms = 100;       ///< longest block inside one step [ms]
};

class CameraSupervisor {
 public:
  enum class State { kClosed, kStreaming, kReconnecting };

  struct Step {
    std::optional<Frame> frame;       ///< a new frame to publish
    int64_t sleep_us = 0;             ///< nothing to do before this much time has passed
    std::vector<std::string> events;  ///< state changes and problems, for the log
  };

  CameraSupervisor(SysIo& io, const CaptureConfig& config, const SupervisorParams& params);

  /// The first open: the caller exits with a code chosen from the status when it fails.
  Status start(int64_t now_mono_us);
  /// One unit of work at time now: a grab while streaming, or a reconnect attempt when due.
  Step step(int64_t now_mono_us);

  State state() const { return state_; }
  const V4l2Capture& capture() const { return capture_; }
  uint64_t reconnects() const { return reconnects_; }
  uint64_t usb_resets() const { return usb_resets_; }

 private:
  void lose(int64_t now_mono_us, const std::string& why, Step& step);

  SysIo& io_;
  V4l2Capture capture_;
  SupervisorParams params_;
  ReconnectBackoff backoff_;
  State state_ = State::kClosed;
  int64_t last_frame_mono_us_ = 0;
  int64_t next_attempt_mono_us_ = 0;
  std::optional<VideoNode> reset_target_;  ///< USB device to reset before the next attempt
  uint64_t reconnects_ = 0;
  uint64_t usb_resets_ = 0;
};

}  // namespace alight::camera
