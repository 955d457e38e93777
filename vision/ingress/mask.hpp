#pragma once
// Ingress, stage 2 of 4 (wall -> blocks -> faces -> opening), its first part: the off-wall mask
// (beyond the paper). The reference image warped by the wall's homography (plane-induced
// parallax, Irani & Anandan, ECCV 1996) disagrees with the current image exactly where the view
// leaves the wall plane, so the mask's border is the opening's border in the wall plane (the
// frame's inner faces, off the plane, fall inside it), where the paper's edges of the grey image
// see the wall's texture and the inner faces too. Both images smoothed, their difference
// thresholded at the larger of parallax_min_diff and parallax_noise_k times its median at the
// wall's inliers, then closed (the view beyond the wall with little texture agrees with it by
// chance in places) and opened (specks on the wall).

#include <opencv2/core.hpp>
#include <vector>

#include "common/camera_model.hpp"
#include "vision/params.hpp"

namespace alight::vision {

/// A grey image as the off-wall mask compares it: parallax_decimation times smaller, blurred
/// by parallax_blur_sigma_px. The pipeline keeps each frame's, so a reference is smoothed once
/// rather than once for every later frame compared with it.
cv::Mat parallax_image(const cv::Mat& gray, const IngressParams& params);

/// Off-wall mask (CV_8UC1, 255 off the wall): both images smoothed, the reference warped into
/// the current view by H_21 (undistorted pixels, x2 ~ H_21 x1; warp_diff.hpp), the absolute
/// difference thresholded at max(parallax_min_diff, parallax_noise_k x its median at the wall
/// inliers `wall_px` (raw current pixels)), then closed and opened. Pixels the reference did
/// not see count as wall.
cv::Mat off_wall_mask(const cv::Mat& image, const cv::Mat& reference, const Matrix3d& H_21,
                      const CameraModel& camera, const std::vector<Vector2d>& wall_px,
                      const IngressParams& params);
/// The same on both images' parallax_image(); `size` is the full-size images' size; `diff`
/// (optional) receives their absolute difference on the coarse grid, before the threshold.
cv::Mat off_wall_mask_of_parallax_images(const cv::Mat& image_parallax,
                                         const cv::Mat& reference_parallax, cv::Size size,
                                         const Matrix3d& H_21, const CameraModel& camera,
                                         const std::vector<Vector2d>& wall_px,
                                         const IngressParams& params, cv::Mat* diff = nullptr);

}  // namespace alight::vision
