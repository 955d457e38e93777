#include "tools/vision_eval.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <map>

#include "vision/frontend/frame_checks.hpp"

namespace alight::tools {

using vision::Reason;

Exposure measure_exposure(const cv::Mat& gray) {
  assert(gray.type() == CV_8UC1 && !gray.empty());
  Exposure e;
  e.level = vision::frame_level(gray);
  e.clipped = vision::clipped_share(gray);
  int dark = 0;
  for (int v = 0; v < gray.rows; ++v) {
    const uint8_t* row = gray.ptr<uint8_t>(v);
    for (int u = 0; u < gray.cols; ++u) dark += row[u] <= kDarkLevel;
  }
  e.dark = static_cast<double>(dark) / static_cast<double>(gray.total());
  return e;
}

namespace {

double sorted_at(const std::vector<double>& sorted, double q) {
  return sorted[std::min(sorted.size() - 1,
                         static_cast<size_t>(q * static_cast<double>(sorted.size() - 1) + 0.5))];
}

}  // namespace

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return sorted_at(v, q);
}

Quantiles quantiles(std::vector<double> v) {
  Quantiles q;
  q.n = v.size();
  if (v.empty()) return q;
  std::sort(v.begin(), v.end());
  q.p10 = sorted_at(v, 0.1);
  q.p50 = sorted_at(v, 0.5);
  q.p90 = sorted_at(v, 0.9);
  q.max = v.back();
  return q;
}

namespace {

// Rate, gaps, repeats and jitter from the exposure times in log order.
void summarize_stream(const std::vector<EvalFrame>& frames, EvalSummary& s) {
  std::vector<double> dt_ms, delay_ms;
  for (size_t i = 0; i < frames.size(); ++i) {
    if (i > 0) dt_ms.push_back(static_cast<double>(frames[i].utime - frames[i - 1].utime) / 1e3);
    if (frames[i].log_utime > 0)
      delay_ms.push_back(static_cast<double>(frames[i].log_utime - frames[i].utime) / 1e3);
  }
  s.delay_ms = quantiles(delay_ms);
  std::vector<double> positive;
  for (double d : dt_ms) {
    if (d <= 0.0)
      ++s.repeated_stamps;
    else
      positive.push_back(d);
  }
  if (positive.empty()) return;
  s.interval_ms = percentile(positive, 0.5);
  std::vector<double> jitter;
  for (double d : positive) {
    if (d > kGapIntervals * s.interval_ms) {
      ++s.gaps;
      s.missing_frames += std::max(1, static_cast<int>(std::lround(d / s.interval_ms)) - 1);
    } else {
      jitter.push_back(std::abs(d - s.interval_ms));
    }
  }
  s.jitter_p99_ms = percentile(jitter, 0.99);
}

void summarize_exposure(const std::vector<EvalFrame>& frames, EvalSummary& s) {
  std::vector<double> level, exposure_ms;
  for (const EvalFrame& f : frames) {
    level.push_back(f.exposure.level);
    if (f.exposure_s) exposure_ms.push_back(*f.exposure_s * 1e3);
    s.over_exposed += f.exposure.clipped > kOverExposedShare;
    s.under_exposed += f.exposure.dark > kUnderExposedShare;
  }
  s.level = quantiles(level);
  s.exposure_ms = quantiles(exposure_ms);
}

void summarize_results(const std::vector<EvalFrame>& frames, EvalSummary& s) {
  std::vector<double> features, matches, inliers, ms;
  std::map<Reason, int> count;
  for (const EvalFrame& f : frames) {
    features.push_back(f.n_features);
    matches.push_back(f.n_matches);
    if (f.reason == Reason::kOk) inliers.push_back(f.n_inliers);
    ms.push_back(f.process_ms);
    s.without_pose += !f.has_pose;
    ++count[f.reason];
  }
  s.features = quantiles(features);
  s.matches = quantiles(matches);
  s.inliers = quantiles(inliers);
  s.process_ms = quantiles(ms);
  s.reasons.assign(count.begin(), count.end());
  std::stable_sort(s.reasons.begin(), s.reasons.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
}

std::string line(const char* fmt, auto... args) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, args...);
  return buf;
}

}  // namespace

EvalSummary summarize(const std::vector<EvalFrame>& frames) {
  EvalSummary s;
  s.frames = frames.size();
  if (frames.empty()) return s;
  summarize_stream(frames, s);
  summarize_exposure(frames, s);
  summarize_results(frames, s);
  return s;
}

const char* hint(Reason reason) {
  switch (reason) {
    case Reason::kNoPose:
      return "no pose at the frame's exposure time: is the pose channel in the log "
             "(--pose-channel),"
             " and are the camera's and the poses' stamps on the same clock (see delay)?";
    case Reason::kNoReference:
      return "no reference frame yet: frames after a start, a reset or lost tracks";
    case Reason::kTooFewFeatures:
      return "too few blobs: a textureless or dark view, or the lens out of focus (see level and"
             " features)";
    case Reason::kTooFewMatches:
      return "features not found again between frames: motion blur, an exposure change or a view"
             " that moved too far (see features and matches)";
    case Reason::kSmallBaseline:
      return "the camera moved too little since the reference: hovering, or poses that do not"
             " move";
    case Reason::kBadImage:
      return "frames the pipeline cannot use: wrong size or format against the camera file";
    case Reason::kMotionBlur:
      return "frames smeared by the camera's motion: a shorter exposure (more light or gain), or"
             " slower turns";
    case Reason::kPlanesDisagree:
      return "the floor's and the top's homographies give two motions: a wrong lens model"
             " (distortion, focal length) bends one plane more than the other; or the top's"
             " matches are few or on a repeated print";
    case Reason::kTopMatchesFew:
      return "the top holds too few matches: a small top seen from far, or one with little print"
             " (a top without print is outlined where the floor has texture around it)";
    case Reason::kNoTopHeight:
      return "nothing stands off the known floor: is the platform in view, and is"
             " vision.landing.floor_z_m the floor's height in the pose's frame?";
    case Reason::kMotionDisagrees:
      return "a plane's motion disagrees with the pose's: check the camera's mount (t_B_C_m,"
             " rotation), its calibration and the pose's latency";
    case Reason::kExposureChange:
      return "automatic exposure stepped: lock the exposure or slow its control (the camera"
             " file's exposure settings)";
    case Reason::kDuplicateFrame:
      return "the driver handed out the previous frame again: USB bandwidth, or a frame rate the"
             " camera cannot keep";
    case Reason::kFrameGap:
      return "frames missing in the stream broke the tracks: see gaps; USB bandwidth or a loaded"
             " computer";
    default:
      return nullptr;
  }
}

std::string format_summary(const EvalSummary& s) {
  std::string out = line("frames: %zu\n", s.frames);
  if (s.frames == 0) return out;
  const auto q = [](const Quantiles& v, const char* fmt) {
    return line(fmt, v.p10, v.p50, v.p90, v.max);
  };
  out += line(
      "stream: %.1f Hz (median interval %.2f ms), %d gaps (%d frames missing), %d repeated"
      " or backward stamps, jitter p99 %.2f ms\n",
      s.interval_ms > 0 ? 1e3 / s.interval_ms : 0.0, s.interval_ms, s.gaps, s.missing_frames,
      s.repeated_stamps, s.jitter_p99_ms);
  if (s.delay_ms.n > 0)
    out += "delay_ms (exposure to recorder): " +
           q(s.delay_ms, "p10 %.1f p50 %.1f p90 %.1f max %.1f\n");
  out += "level (mean grey): " + q(s.level, "p10 %.0f p50 %.0f p90 %.0f max %.0f");
  out +=
      line(", %d over-exposed (>%.0f%% clipped), %d under-exposed (>%.0f%% at the noise floor)\n",
           s.over_exposed, 100 * kOverExposedShare, s.under_exposed, 100 * kUnderExposedShare);
  if (s.exposure_ms.n > 0)
    out += "exposure_ms (driver): " + q(s.exposure_ms, "p10 %.2f p50 %.2f p90 %.2f max %.2f\n");
  else
    out += "exposure_ms (driver): not in the frames' metadata\n";
  out += "features: " + q(s.features, "p10 %.0f p50 %.0f p90 %.0f max %.0f\n");
  out += "matches: " + q(s.matches, "p10 %.0f p50 %.0f p90 %.0f max %.0f\n");
  if (s.inliers.n > 0)
    out +=
        "target inliers (found frames): " + q(s.inliers, "p10 %.0f p50 %.0f p90 %.0f max %.0f\n");
  out += line("frames without a pose: %d\n", s.without_pose);
  out += "reasons:\n";
  for (const auto& [reason, n] : s.reasons) {
    const double share = static_cast<double>(n) / static_cast<double>(s.frames);
    out += line("  %3d %-44s %6d  %5.1f%%\n", static_cast<int>(reason), vision::to_string(reason),
                n, 100.0 * share);
    if (const char* h = hint(reason); h && share >= 0.1) out += std::string("      ") + h + "\n";
  }
  out += line("frame_time_ms: median %.2f p90 %.2f max %.2f\n", s.process_ms.p50, s.process_ms.p90,
              s.process_ms.max);
  return out;
}

}  // namespace alight::tools
