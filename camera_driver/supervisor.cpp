#include "camera_driver/supervisor.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace alight::camera {

ReconnectBackoff::ReconnectBackoff(double initial_s, double max_s, double factor)
    : initial_s_(initial_s), max_s_(max_s), factor_(factor), next_s_(initial_s) {
  assert(initial_s > 0.0 && max_s >= initial_s && factor >= 1.0);
}

int64_t ReconnectBackoff::next_delay_us() {
  const double d = next_s_;
  next_s_ = std::min(max_s_, next_s_ * factor_);
  return static_cast<int64_t>(std::llround(d * 1e6));
}

CameraSupervisor::CameraSupervisor(SysIo& io, const CaptureConfig& config,
                                   const SupervisorParams& params)
    : io_(io),
      capture_(io, config),
      params_(params),
      backoff_(params.backoff_initial_s, params.backoff_max_s) {}

Status CameraSupervisor::start(int64_t now_mono_us) {
  Status s = capture_.open();
  if (s.ok()) {
    state_ = State::kStreaming;
    last_frame_mono_us_ = now_mono_us;
  }
  return s;
}

void CameraSupervisor::lose(int64_t now_mono_us, const std::string& why, Step& step) {
  step.events.push_back(why);
  capture_.close();
  state_ = State::kReconnecting;
  backoff_.reset();
  next_attempt_mono_us_ = now_mono_us;  // the first attempt is immediate: a stall may be brief
}

CameraSupervisor::Step CameraSupervisor::step(int64_t now_mono_us) {
  Step out;
  if (state_ == State::kClosed) {
    out.events.push_back("camera not started");
    out.sleep_us = params_.grab_timeout_ms * 1000;
    return out;
  }
  if (state_ == State::kReconnecting) {
    if (now_mono_us < next_attempt_mono_us_) {
      out.sleep_us = next_attempt_mono_us_ - now_mono_us;
      return out;
    }
    if (reset_target_) {
      const std::string err = io_.usb_reset(reset_target_->usb_bus, reset_target_->usb_address);
      ++usb_resets_;
      out.events.push_back(err.empty() ? "USB reset of " + reset_target_->path + " done"
                                       : "USB reset of " + reset_target_->path + " failed: " + err);
      reset_target_.reset();
    }
    const Status s = capture_.open();
    if (!s.ok()) {
      const int64_t wait = backoff_.next_delay_us();
      next_attempt_mono_us_ = now_mono_us + wait;
      out.events.push_back("reconnect failed (" + s.message + "); next attempt in " +
                           std::to_string(wait / 1000) + " ms");
      out.sleep_us = wait;
      return out;
    }
    ++reconnects_;
    state_ = State::kStreaming;
    last_frame_mono_us_ = now_mono_us;
    out.events.push_back("reconnected to " + capture_.format().path);
    return out;
  }

  GrabResult g = capture_.grab(params_.grab_timeout_ms);
  switch (g.status) {
    case GrabStatus::kFrame:
      last_frame_mono_us_ = now_mono_us;
      out.frame = std::move(g.frame);
      if (!g.message.empty()) out.events.push_back(g.message);
      break;
    case GrabStatus::kBadFrame:
      out.events.push_back(g.message);
      break;
    case GrabStatus::kDeviceLost:
      lose(now_mono_us, g.message + "; reconnecting", out);
      break;
    case GrabStatus::kError:
      lose(now_mono_us, g.message + "; reopening", out);
      break;
    case GrabStatus::kTimeout:
      break;
  }
  // No good frame for stall_timeout_s is a stall whatever the device reports: silence, only
  // corrupt buffers (a camera whose every frame is flagged V4L2_BUF_FLAG_ERROR, or fails to
  // convert) or only stale ones all leave the consumer without an image.
  if (state_ == State::kStreaming && !out.frame) {
    const int64_t silent_us = now_mono_us - last_frame_mono_us_;
    if (silent_us > static_cast<int64_t>(params_.stall_timeout_s * 1e6)) {
      const VideoNode node = capture_.node();
      if (params_.usb_reset_on_stall && node.is_usb && node.usb_bus >= 0) reset_target_ = node;
      lose(now_mono_us,
           node.path + ": no good frame for " + std::to_string(silent_us / 1000) +
               " ms (stalled); " + (reset_target_ ? "resetting over USB and " : "") + "reopening",
           out);
    }
  }
  return out;
}

}  // namespace alight::camera
