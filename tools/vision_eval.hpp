#pragma once
// What alight-vision-eval says about a session's frames beyond the vision's own result: how the
// camera and its driver delivered them (rate, gaps, repeated stamps, jitter, the delay from
// exposure to the recorder), how they were exposed (the driver's exposure time, the frames'
// brightness, clipped and black pixels), what the front end found in them (features, matches)
// and, per refusal reason, what a user can check on the vehicle. A recorded flight with a real
// camera has no truth to score against; these are what say why the vision saw nothing, and they
// are what a bug report needs (docs/real-vehicle.md#a-camera-session-for-a-bug-report).
//
// Pure: the frames' records in, a summary and its text out; alight-vision-eval reads the log.

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "vision/status.hpp"

namespace alight::tools {

/// A grey level this close to black is the sensor's noise floor: a blob there is noise, and a
/// frame mostly this dark is under-exposed whatever its mean says.
constexpr int kDarkLevel = 8;
/// A frame with more of its pixels clipped white than this has lost the blobs of that part of the
/// view (ExposureGuard refuses a step of kClipStep = 0.2; this flags a lasting over-exposure).
constexpr double kOverExposedShare = 0.1;
/// A frame with more of its pixels at the noise floor than this is under-exposed.
constexpr double kUnderExposedShare = 0.5;
/// An interval longer than this many nominal intervals lost at least one frame.
constexpr double kGapIntervals = 1.5;

/// The frame's picture as exposed: mean grey level (vision::frame_level), the shares of its
/// pixels clipped white (vision::clipped_share) and at the noise floor (<= kDarkLevel).
struct Exposure {
  double level = 0.0;
  double clipped = 0.0;
  double dark = 0.0;
};
/// `gray`: CV_8UC1, not empty.
Exposure measure_exposure(const cv::Mat& gray);

/// One frame as alight-vision-eval saw it.
struct EvalFrame {
  int64_t utime = 0;      ///< exposure time [us]
  int64_t log_utime = 0;  ///< when the recorder received it [us]; 0 when unknown
  vision::Reason reason = vision::Reason::kOk;
  int n_features = 0, n_matches = 0;
  int n_inliers = 0;  ///< the target plane's inliers (found frames)
  bool has_pose = false;
  Exposure exposure;
  std::optional<double> exposure_s;  ///< the driver's exposure time [s], when it says
  double process_ms = 0.0;
};

struct Quantiles {
  double p10 = 0, p50 = 0, p90 = 0, max = 0;
  size_t n = 0;
};
/// The nearest-rank q-quantile (q in [0, 1]) of v; 0 for none.
double percentile(std::vector<double> v, double q);
Quantiles quantiles(std::vector<double> v);

struct EvalSummary {
  size_t frames = 0;
  // The stream: intervals between consecutive frames' exposure times, in log order.
  double interval_ms = 0.0;    ///< the median interval (the nominal rate's period) [ms]
  int gaps = 0;                ///< intervals longer than kGapIntervals nominal ones
  int missing_frames = 0;      ///< frames those gaps lost, by the nominal interval
  int repeated_stamps = 0;     ///< intervals <= 0: a stamp equal to or before the previous one
  double jitter_p99_ms = 0.0;  ///< |interval - nominal| over the intervals that are not gaps
  Quantiles delay_ms;          ///< exposure to the recorder's reception (log_utime known)
  // Exposure.
  Quantiles level, exposure_ms;  ///< exposure_ms.n = 0: the driver never said
  int over_exposed = 0, under_exposed = 0;
  // The front end and the result.
  Quantiles features, matches, inliers;  ///< inliers over found frames
  int without_pose = 0;
  std::vector<std::pair<vision::Reason, int>> reasons;  ///< most frequent first
  Quantiles process_ms;
};

/// `frames` in log order. Empty frames give an empty summary.
EvalSummary summarize(const std::vector<EvalFrame>& frames);

/// What a user can check when `reason` refuses many frames: the camera, its driver, the
/// exposure, the pose source or the scene; nullptr for the geometric gates (docs/vision-*.md
/// say what each looks at).
const char* hint(vision::Reason reason);

/// The report alight-vision-eval prints: stream, exposure, features, the reasons' histogram
/// with a hint for each reason refusing at least a tenth of the frames, and the time per frame.
std::string format_summary(const EvalSummary& s);

}  // namespace alight::tools
