#pragma once
// Sub-pixel STAR / CenSurE detector (paper 3.1.1; Agrawal, Konolige & Blas, "CenSurE: Center
// Surround Extremas for Realtime Feature Detection and Matching", ECCV 2008).
//
// Bi-level centre-surround filters (difference of boxes: inner box 2n+1, outer box 4n+1, each
// normalised to its mean, so the response is zero on flat ground and comparable across n) at
// the scales n = min_size..max_size, all from one integral image. Each pixel keeps its strongest
// scale (non-maximum suppression over scale), then peaks are kept where they are the maximum of
// |response| in a (2r+1)^2 window (over space) and above the threshold. Line-like peaks are
// rejected with the Harris ratio of the |response| second-moment matrix (CenSurE sec. 3.3),
// strongest peak first until max_features have passed.
// The paper's sub-pixel step refines each peak by a quadratic fit to the 3x3 responses at its
// scale (x, y) and a parabola through the responses at n-1, n, n+1 (scale).

#include <opencv2/core.hpp>
#include <vector>

#include "vision/params.hpp"
#include "vision/status.hpp"

namespace alight::vision {

struct Keypoint {
  float x = 0, y = 0;  ///< position [px] (pixel centres at integers, u right, v down)
  float size = 1;      ///< filter index n, continuous after refinement (blob radius ~ n + 0.5 px)
  float response = 0;  ///< mean(inner) - mean(ring) [grey levels]; > 0: bright blob
};

/// Integral image (CV_32S, (h+1) x (w+1)) of an 8-bit grey image, shared by STAR and SURF.
cv::Mat integral_image(const cv::Mat& gray);

/// Detects keypoints in a grey image given its integral image. Fails with kBadImage (not 8-bit
/// single-channel, or smaller than the largest filter) or kTooFewFeatures (fewer than 4 peaks,
/// e.g. a blank image).
Result<std::vector<Keypoint>> detect_star(const cv::Mat& gray, const cv::Mat& integral,
                                          const StarParams& params);

/// Non-maximum suppression over space, given best_abs dilated by the (2r+1)^2 rectangle: the
/// pixels of `inner`, row by row, with best_abs >= dilated (the window's maximum) and
/// best_abs > threshold; as cv::compare twice, cv::bitwise_and and cv::findNonZero would give.
/// allow_avx2 = false: the scalar variant (for the test that both agree).
std::vector<cv::Point> star_peaks(const cv::Mat& best_abs, const cv::Mat& dilated,
                                  const cv::Rect& inner, float threshold, bool allow_avx2 = true);

/// Centre-surround response at an integer pixel and filter index (for tests and refinement).
float star_response(const cv::Mat& integral, int x, int y, int n);

}  // namespace alight::vision
