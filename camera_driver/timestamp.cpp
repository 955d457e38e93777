#include "camera_driver/timestamp.hpp"

#include <linux/videodev2.h>
#include <sys/time.h>

#include <cassert>

namespace alight::camera {

int64_t clock_offset_us(const std::vector<ClockSample>& samples) {
  assert(!samples.empty());
  const ClockSample* best = &samples.front();
  for (const auto& s : samples)
    if (s.mono_after_us - s.mono_before_us < best->mono_after_us - best->mono_before_us) best = &s;
  const int64_t mono_mid = best->mono_before_us + (best->mono_after_us - best->mono_before_us) / 2;
  return best->unix_us - mono_mid;
}

int64_t timeval_us(const timeval& tv) {
  return static_cast<int64_t>(tv.tv_sec) * 1000000 + static_cast<int64_t>(tv.tv_usec);
}

StampSource stamp_source_from_flags(uint32_t flags) {
  return (flags & V4L2_BUF_FLAG_TSTAMP_SRC_MASK) == V4L2_BUF_FLAG_TSTAMP_SRC_SOE
             ? StampSource::kStartOfExposure
             : StampSource::kEndOfFrame;
}

int64_t exposure_utime(int64_t buffer_mono_us, int64_t offset_us, StampSource source,
                       int64_t exposure_us) {
  int64_t mono = buffer_mono_us;
  if (exposure_us > 0)
    mono += source == StampSource::kStartOfExposure ? exposure_us / 2 : -exposure_us / 2;
  return mono + offset_us;
}

}  // namespace alight::camera
