// Checks of a frame as the camera delivered it (see frame_checks.hpp).
#include "vision/frontend/frame_checks.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace alight::vision {

namespace {
// Darkest level a frame is taken to have: keeps a black frame's ratio finite.
constexpr double kMinLevel = 0.5;
}  // namespace

double frame_level(const cv::Mat& gray) {
  if (gray.empty() || gray.type() != CV_8UC1) return 0.0;
  uint64_t sum = 0, n = 0;
  for (int v = 0; v < gray.rows; v += 4) {
    const uint8_t* row = gray.ptr<uint8_t>(v);
    for (int u = 0; u < gray.cols; u += 4) sum += row[u];
    n += static_cast<uint64_t>((gray.cols + 3) / 4);
  }
  return n ? double(sum) / double(n) : 0.0;
}

double clipped_share(const cv::Mat& gray) {
  if (gray.empty() || gray.type() != CV_8UC1) return 0.0;
  uint64_t clipped = 0, n = 0;
  for (int v = 0; v < gray.rows; v += 4) {
    const uint8_t* row = gray.ptr<uint8_t>(v);
    for (int u = 0; u < gray.cols; u += 4) clipped += row[u] >= kClippedLevel;
    n += static_cast<uint64_t>((gray.cols + 3) / 4);
  }
  return n ? double(clipped) / double(n) : 0.0;
}

ExposureCheck ExposureGuard::check(double level, int64_t utime, double clipped) {
  level = std::max(level, kMinLevel);
  ExposureCheck out;
  if (settled_ <= 0.0) {
    settled_ = level;
    settled_clipped_ = clipped;
    return out;
  }
  out.ev = std::log2(level / settled_);
  if (std::abs(out.ev) > kStepEv || clipped - settled_clipped_ > kClipStep) {
    if (step_start_ < 0 || utime < step_start_) step_start_ = utime;
    if (double(utime - step_start_) * 1e-6 <= kMaxStepS) {
      out.step = true;
      return out;
    }
    // The scene's own change: its level is the settled one from now on.
    settled_ = level;
    settled_clipped_ = clipped;
    step_start_ = -1;
    out.ev = 0.0;
    return out;
  }
  step_start_ = -1;
  // Beyond the dead band the frame is on its way back from a step: the settled level stays.
  if (std::abs(out.ev) > kDeadBandEv)
    out.threshold_scale = std::exp2(out.ev);
  else {
    settled_ *= std::exp2(kSettleWeight * out.ev);
    settled_clipped_ += kSettleWeight * (clipped - settled_clipped_);
  }
  return out;
}

void ExposureGuard::reset() {
  settled_ = 0.0;
  settled_clipped_ = 0.0;
  step_start_ = -1;
}

double gain_between(double level_ref, double level_now) {
  if (!(level_ref > 0.0) || !(level_now > 0.0)) return 1.0;
  const double ratio = std::max(level_now, kMinLevel) / std::max(level_ref, kMinLevel);
  return std::abs(std::log2(ratio)) > ExposureGuard::kDeadBandEv ? ratio : 1.0;
}

uint64_t pixel_hash(const cv::Mat& gray) {
  // Eight bytes at a time, each word mixed in with a multiply and a rotation (the frame is
  // hashed once per frame, so it must cost little next to the detector).
  uint64_t h = 0x9E3779B97F4A7C15ull ^ (uint64_t(gray.cols) << 32) ^ uint64_t(gray.rows);
  const auto mix = [&h](uint64_t w) {
    h ^= w * 0xBF58476D1CE4E5B9ull;
    h = (h << 27 | h >> 37) * 0x94D049BB133111EBull;
  };
  for (int v = 0; v < gray.rows; ++v) {
    const uint8_t* row = gray.ptr<uint8_t>(v);
    const size_t n = static_cast<size_t>(gray.cols) * gray.elemSize();
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
      uint64_t w;
      std::memcpy(&w, row + i, 8);
      mix(w);
    }
    uint64_t tail = 0;
    std::memcpy(&tail, row + i, n - i);
    mix(tail ^ (uint64_t(n - i) << 56));
  }
  return h;
}

}  // namespace alight::vision
