#pragma once
// V4L2 buffer timestamps to Unix utime. UVC and most V4L2 drivers stamp buffers with
// CLOCK_MONOTONIC (V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC); every alight message carries Unix time
// (docs/ARCHITECTURE.md "Time"). The offset between the two clocks is measured once at
// start and then kept: re-measuring it per frame would let NTP slews of CLOCK_REALTIME jitter
// the frame times, whereas a fixed offset keeps frame-to-frame intervals exactly the camera's.

#include <cstdint>
#include <vector>

struct timeval;

namespace alight::camera {

/// One reading of both clocks: CLOCK_MONOTONIC before and after a CLOCK_REALTIME read [us].
struct ClockSample {
  int64_t mono_before_us = 0;
  int64_t unix_us = 0;
  int64_t mono_after_us = 0;
};

/// unix - monotonic [us] from the sample whose monotonic bracket is narrowest (least chance a
/// preemption fell between the reads), with the Unix read taken at the bracket's midpoint.
int64_t clock_offset_us(const std::vector<ClockSample>& samples);

/// A V4L2 buffer's struct timeval [us].
int64_t timeval_us(const timeval& tv);

/// Where in the exposure the driver took its timestamp (V4L2_BUF_FLAG_TSTAMP_SRC_*).
enum class StampSource { kStartOfExposure, kEndOfFrame };
StampSource stamp_source_from_flags(uint32_t buffer_flags);

/// image_t.utime: the middle of the exposure on the Unix clock. With a known exposure time the
/// stamp is moved by half of it towards the middle (readout time after an end-of-frame stamp is
/// unknown to V4L2 and is not corrected); exposure_us <= 0 (auto exposure) leaves it as stamped.
int64_t exposure_utime(int64_t buffer_mono_us, int64_t offset_us, StampSource source,
                       int64_t exposure_us);

}  // namespace alight::camera
