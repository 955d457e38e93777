#pragma once
// Plane-induced parallax as an image (Irani & Anandan, ECCV 1996): the absolute difference
// between the current image and the reference image warped into it by a homography, in one pass
// and without the warped image (cv::warpPerspective of the reference, and of a second
// image only to learn which pixels the reference saw, were a fifth of the vision's time on a
// photographed wall).
//
// Each current pixel u = (x, y) looks up the reference at H_12 u (pixel centres at integer
// coordinates, as cv::warpPerspective): exactly every 16 pixels along a row, linearly between
// (the map is smooth: over 16 pixels its curvature moves a point by far less than the 1/256 pixel
// step it is rounded to), and bilinearly interpolated in fixed point (8 fractional bits per axis,
// rounded to the nearest grey level). Where H_12 u falls outside the reference (more than half a
// pixel beyond its outermost pixel centres, or behind the camera), the difference is 0: the
// reference did not see it. The samples next to the reference's border repeat its outermost
// pixels. The result is the same on every x86-64 CPU: the AVX2 variant (when present) does the
// scalar variant's integer arithmetic.

#include <opencv2/core.hpp>
#include <vector>

#include "common/geometry.hpp"

namespace alight::vision {

/// |image(u) - reference(H_12 u)| (CV_8UC1, image's size); both CV_8UC1, at least 2 x 2.
cv::Mat warp_abs_diff(const cv::Mat& image, const cv::Mat& reference, const Matrix3d& H_12);

/// The same without the AVX2 variant (exposed for the test that both agree).
cv::Mat warp_abs_diff_scalar(const cv::Mat& image, const cv::Mat& reference, const Matrix3d& H_12);

/// |image(u) - reference(m(u))| for a map m that is no homography (a distorting lens bends it),
/// given at nodes every `step` pixels: node (i, j) at pixel (min(i step, cols - 1),
/// min(j step, rows - 1)), `node_x` and `node_y` row-major, `nodes_across` a row, each the
/// reference pixel the node's pixel sees (a node that sees nothing: NaN, or -1e6, which puts the
/// pixels between it and its neighbours far outside the reference). Between nodes the map is
/// bilinear (in float, as written), the reference sampled by cv::remap (bilinear, 0 outside); where
/// the reference pixel nearest m(u) (cv::remap's rounding) is outside the reference the difference
/// is 0. image and reference CV_8UC1, at least 2 x 2; step >= 1.
cv::Mat grid_remap_abs_diff(const cv::Mat& image, const cv::Mat& reference,
                            const std::vector<float>& node_x, const std::vector<float>& node_y,
                            int nodes_across, int step);

}  // namespace alight::vision
