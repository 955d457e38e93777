#pragma once
// Ingress target (paper 3.3, Fig. 7): the dominant homography is the wall; matches off it are
// seen through the opening. Straight edges (Canny, then the probabilistic Hough transform of
// Matas, Galambos & Kittler, CVIU 2000, as cv::HoughLinesP) kept only when near-vertical or
// near-horizontal cut the image into cells; a 2D histogram counts wall inliers and off-wall
// features per cell, and the rectangular block of cells without any inlier that holds the most
// off-wall features (at least min_outliers; the larger block on a tie) is the opening. Its
// centre, intersected with the wall plane (paper 3.1.3), is the waypoint; its left and right
// borders at the centre row give the width (paper Fig. 12), top and bottom the height.
// Beyond the paper, the edges come from a dense off-wall mask rather than the grey image: the
// reference image warped by the wall homography (plane-induced parallax, Irani & Anandan,
// ECCV 1996) disagrees with the current image exactly where the view leaves the wall plane, so
// the mask's border is the opening's border in the wall plane (the frame's inner faces, off the
// plane, fall inside it). The mask also decides what the features alone cannot (issue 15, a
// dark, flat wall photograph): an outlier of the wall's homography where the mask finds the
// wall is not seen through the opening, a block is not bounded by a row or column of cells
// without off-wall features that the mask leaves mostly clear (unless the cut beyond them is
// the opening's edge: mask along it on their side, the wall beyond), and it may hold a few inliers
// (block_inlier_share of its off-wall features: the inner faces' features fit the wall's
// homography).

#include <opencv2/core.hpp>
#include <vector>

#include "common/camera_model.hpp"
#include "vision/geometry/decomposition.hpp"
#include "vision/params.hpp"
#include "vision/target.hpp"

namespace alight::vision {

/// A grey image as the off-wall mask compares it: parallax_decimation times smaller, blurred
/// by parallax_blur_sigma_px. The pipeline keeps each frame's, so a reference is smoothed once
/// rather than once for every later frame compared with it.
cv::Mat parallax_image(const cv::Mat& gray, const IngressParams& params);

/// `image` is the current grey image (raw pixels, as c.u2), `reference` the reference frame's
/// (as c.u1; empty: the paper's edges of `image`, as with params.ingress.parallax_mask false).
/// Fails with kTooFewMatches / kNoDominantPlane (no wall), kSmallBaseline /
/// kDecompositionFailed, or kNoOpening.
TargetOutcome find_ingress_target(const Correspondences& c, const cv::Mat& image,
                                  const cv::Mat& reference, const PipelineParams& params);
/// The same with both frames' parallax_image() already made (`image_parallax`,
/// `reference_parallax`; an empty reference_parallax: the paper's edges of `image`).
TargetOutcome find_ingress_target(const Correspondences& c, const cv::Mat& image,
                                  const cv::Mat& image_parallax, const cv::Mat& reference_parallax,
                                  const PipelineParams& params);

/// Off-wall mask (CV_8UC1, 255 off the wall): both images smoothed, the reference warped into
/// the current view by H_21 (undistorted pixels, x2 ~ H_21 x1; warp_diff.hpp), the absolute
/// difference thresholded at max(parallax_min_diff, parallax_noise_k x its median at the wall
/// inliers `wall_px` (raw current pixels)), then closed and opened. Pixels the reference did
/// not see count as wall. Exposed for tests.
cv::Mat off_wall_mask(const cv::Mat& image, const cv::Mat& reference, const Matrix3d& H_21,
                      const CameraModel& camera, const std::vector<Vector2d>& wall_px,
                      const IngressParams& params);
/// The same on both images' parallax_image(); `size` is the full-size images' size.
cv::Mat off_wall_mask_of_parallax_images(const cv::Mat& image_parallax,
                                         const cv::Mat& reference_parallax, cv::Size size,
                                         const Matrix3d& H_21, const CameraModel& camera,
                                         const std::vector<Vector2d>& wall_px,
                                         const IngressParams& params, cv::Mat* diff = nullptr);

/// The near-vertical (x) and near-horizontal (y) cut positions of the image's straight edges
/// (Canny, probabilistic Hough), sorted, merged, including the image borders. Exposed for tests.
/// The same cuts from an off-wall mask's border: standard Hough lines, each refined by a
/// least-squares fit to the border pixels along it and, given the grey `image`, moved to the
/// wall's edge: the step in the image within snap_px on the wall's side. Exposed for tests.
void mask_cuts(const cv::Mat& mask, const IngressParams& params, std::vector<double>* x_cuts,
               std::vector<double>* y_cuts, std::vector<cv::Vec4i>* kept_segments,
               const cv::Mat& image = cv::Mat());

/// Where the wall's inner faces (jambs, sill, lintel) can show, and the two views to test them.
struct CutGeometry {
  Vector2d principal_px = Vector2d::Zero();
  double wall_depth_m = 0;              ///< along the optical axis
  PlaneMotion wall;                     ///< the wall's homography, decomposed (camera 1: reference)
  const CameraModel* camera = nullptr;  ///< nullptr: no face search
  cv::Mat image, reference;             ///< both frames' parallax_image(), full size
};

/// The across-coordinate of the wall's front edge beyond the inner face next to the cut
/// a + b (along - mean_along), along in [lo, hi] (x of a vertical cut at row y), the wall on
/// the cut's `side` (-1: lower across-coordinates, +1: higher): where a face plane through that
/// edge along the wall's normal and the wall beyond it explain the two views best. `a`
/// unchanged when no face shows. Exposed for tests.
double face_front_edge(int side, bool vertical, double a, double b, double mean_along, int lo,
                       int hi, const CutGeometry& geometry, const IngressParams& params);

void line_cuts(const cv::Mat& image, const IngressParams& params, std::vector<double>* x_cuts,
               std::vector<double>* y_cuts, std::vector<cv::Vec4i>* kept_segments);

}  // namespace alight::vision
