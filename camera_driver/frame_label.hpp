#pragma once
// What a published frame says about itself: its exposure time on the Unix clock and a
// capture sequence number that keeps increasing across reconnects (the kernel restarts its
// numbering at every STREAMON), so a gap in "seq" always means frames were lost.

#include <cstdint>

#include "camera_driver/v4l2_capture.hpp"

namespace alight::camera {

struct FrameLabel {
  int64_t utime = 0;  ///< middle of the exposure [us since Unix epoch]
  int64_t seq = 0;    ///< capture sequence across the whole run
};

class FrameLabeler {
 public:
  /// clock_offset_us: CLOCK_REALTIME - CLOCK_MONOTONIC measured once at start (timestamp.hpp);
  /// exposure_us: the manual exposure, -1 when automatic (no mid-exposure correction).
  FrameLabeler(int64_t clock_offset_us, int64_t exposure_us);

  /// `stream` counts the streams so far (the supervisor's reconnects): a new value means the
  /// kernel's numbering started again. now_mono_us stamps frames whose driver clock is not
  /// monotonic (later than the exposure, but on the right clock).
  FrameLabel label(const Frame& frame, uint64_t stream, int64_t now_mono_us);
  /// True once a frame had to be stamped with now_mono_us.
  bool used_dequeue_time() const { return used_dequeue_time_; }

 private:
  int64_t offset_us_;
  int64_t exposure_us_;
  uint64_t stream_ = 0;
  int64_t seq_base_ = 0;
  int64_t last_seq_ = -1;
  bool used_dequeue_time_ = false;
};

}  // namespace alight::camera
