#pragma once
// Diagnostic image of one frame (paper Figs. 5 and 7): features (grey: unmatched; green: on the
// dominant plane; blue: off it; red: the target's), Hough segments (ingress), the platform's
// extent or the opening box, the aiming point, and a status line.

#include <opencv2/core.hpp>

#include "vision/pipeline.hpp"

namespace alight::vision {

/// BGR copy of `gray` with the result drawn on it.
cv::Mat draw_diag_image(const cv::Mat& gray, const FrameResult& result);

}  // namespace alight::vision
