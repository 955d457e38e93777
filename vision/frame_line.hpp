#pragma once
// One frame's whole result on one line, doubles printed as %a (exact) and no timing, so that two
// builds' outputs over the same frames compare with diff: a refactor of the vision must leave
// them identical. Used by alight-vision-eval --frames and alight_vision_cpu_bench --frames.

#include <cstdint>
#include <cstdio>
#include <string>

#include "vision/pipeline.hpp"

namespace alight::vision {

/// FNV-1a over bytes: a digest of the per-match and per-pixel parts of a result.
struct FrameDigest {
  uint64_t h = 1469598103934665603ull;
  void add(const void* data, size_t n) {
    const auto* b = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  }
  void add(const Vector2d& v) { add(v.data(), 2 * sizeof(double)); }
};

/// The line (with its newline) for `r`.
inline std::string frame_line(const FrameResult& r) {
  const TargetEstimate& t = r.target;
  FrameDigest d;
  for (const auto& p : r.features_px) d.add(p);
  for (const auto& p : r.matched_px) d.add(p);
  for (const Label l : r.labels) d.add(&l, sizeof l);
  for (const auto& l : r.lines) d.add(&l, sizeof l);
  for (const auto& p : t.outline) d.add(p);
  char buf[1024];
  std::snprintf(
      buf, sizeof buf,
      "frame %lld seq %lld ref %lld reason %d found %d held %d p_W %a %a %a n_W %a %a %a "
      "pixel %a %a height %a size %a %a yaw %a baseline %a blur %a feat %d match %d tracked %d "
      "in %d/%d digest %016llx\n",
      (long long)r.utime, (long long)r.seq, (long long)r.ref_utime, static_cast<int>(r.reason),
      r.found(), r.ref_held, t.p_W.x(), t.p_W.y(), t.p_W.z(), t.n_W.x(), t.n_W.y(), t.n_W.z(),
      t.pixel.x(), t.pixel.y(), t.height_m, t.size_m[0], t.size_m[1], t.yaw_rad, r.baseline_m,
      r.blur_px, r.n_features, r.n_matches, r.n_tracked, t.n_inliers_dominant, t.n_inliers_target,
      static_cast<unsigned long long>(d.h));
  return buf;
}

}  // namespace alight::vision
