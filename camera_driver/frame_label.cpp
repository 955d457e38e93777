#include "camera_driver/frame_label.hpp"

namespace alight::camera {

FrameLabeler::FrameLabeler(int64_t clock_offset_us, int64_t exposure_us)
    : offset_us_(clock_offset_us), exposure_us_(exposure_us) {}

FrameLabel FrameLabeler::label(const Frame& f, uint64_t stream, int64_t now_mono_us) {
  if (stream != stream_) {
    stream_ = stream;
    seq_base_ = last_seq_ + 1;
  }
  FrameLabel out;
  out.seq = seq_base_ + f.sequence;
  last_seq_ = out.seq;
  if (f.monotonic_clock) {
    out.utime = exposure_utime(f.buffer_mono_us, offset_us_, f.stamp_source, exposure_us_);
  } else {
    out.utime = now_mono_us + offset_us_;
    used_dequeue_time_ = true;
  }
  return out;
}

}  // namespace alight::camera
