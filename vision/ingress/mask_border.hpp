#pragma once
// The border of a mask as a list of pixels: those whose 3x3 neighbourhood (within the image) is
// not uniform, which are the nonzero pixels of the morphological gradient (dilation minus
// erosion, 3x3; Serra, Image Analysis and Mathematical Morphology, 1982), in cv::findNonZero's
// order (row by row, x increasing). One pass, no gradient image: the gradient and the scan for
// its nonzero pixels cost 4 % of the vision's time on a photographed wall.

#include <opencv2/core.hpp>
#include <vector>

namespace alight::vision {

/// `mask`: CV_8UC1, any values. Appends nothing for an empty mask.
std::vector<cv::Point> mask_border_pixels(const cv::Mat& mask);

}  // namespace alight::vision
