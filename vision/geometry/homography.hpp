#pragma once
// Robust homography between two views of a plane (paper 3.1.2; the landing's second plane, 3.2).
//
// RANSAC (Fischler & Bolles 1981) over the 4-point DLT in Hartley-normalised coordinates
// (Hartley 1997), with degenerate-sample rejection (collinear triples, orientation flips as in
// OpenCV's checkSubset), MSAC scoring (Torr & Zisserman 2000), local optimisation of each new
// best model (Chum, Matas & Kittler 2003), adaptive stopping with an iteration cap, and a final
// least-squares DLT on the inliers followed by a Cauchy-weighted (IRLS; Holland & Welsch 1977)
// Levenberg-Marquardt refinement (common/robust_lsq.hpp) of the transfer error, robust to the heavy
// tail of real keypoint residuals (see refine_transfer in homography.cpp). Seeded.
//
// Second plane: sample_locally draws the other three points of a sample among the first one's
// nearest neighbours in image 1, and the stopping rule assumes the smallest plane worth finding
// (min_inliers points), so when the outliers of the first plane hold no second plane the search
// ends after a bounded number of cheap samples instead of running to max_iterations.

#include <cstdint>
#include <vector>

#include "common/geometry.hpp"
#include "vision/params.hpp"
#include "vision/status.hpp"

namespace alight::vision {

struct HomographyFit {
  Matrix3d H = Matrix3d::Identity();  ///< x2 ~ H x1 in the coordinates of the input points
  std::vector<uint8_t> inlier;        ///< per correspondence: 1 when an inlier
  int n_inliers = 0;
  double rms_px = 0.0;  ///< RMS transfer error of the inliers [input units]
  int iterations = 0;   ///< RANSAC samples drawn
};

enum class Sampling { kUniform, kLocal };

/// Fits x2 ~ H x1 (pixels, undistorted). Fails with kTooFewMatches (< 4 or < min_inliers
/// correspondences) or kNoDominantPlane (no model with min_inliers inliers).
Result<HomographyFit> fit_homography(const std::vector<Vector2d>& x1,
                                     const std::vector<Vector2d>& x2,
                                     const HomographyParams& params,
                                     Sampling sampling = Sampling::kUniform,
                                     int* iterations = nullptr);

/// The landing's two planes (paper 3.2): the dominant homography over all correspondences, then
/// a second one, locally sampled, over the dominant plane's outliers.
struct PlanePair {
  HomographyFit first;
  std::optional<HomographyFit> second;  ///< inlier mask indexes the ORIGINAL correspondences
  Reason second_reason = Reason::kOk;   ///< kNoTargetPlane when there is no second plane
  int second_iterations = 0;            ///< samples the second search drew
};

/// Fails (kTooFewMatches, kNoDominantPlane) only when there is no first plane; a missing second
/// plane is reported in the result (second empty, second_reason = kNoTargetPlane).
Result<PlanePair> fit_two_homographies(const std::vector<Vector2d>& x1,
                                       const std::vector<Vector2d>& x2,
                                       const HomographyParams& params);

/// Exact homography through 4 correspondences (DLT with h33 = 1); nullopt when degenerate.
std::optional<Matrix3d> homography_from_4(const Vector2d* x1, const Vector2d* x2);

/// Least-squares DLT over all given correspondences (Hartley-normalised), no robustness.
std::optional<Matrix3d> homography_dlt(const std::vector<Vector2d>& x1,
                                       const std::vector<Vector2d>& x2);

/// Forward transfer error |proj(H x1) - x2|.
double transfer_error(const Matrix3d& H, const Vector2d& x1, const Vector2d& x2);

/// Mean distance between H_a and H_b applied to the four corners of a w x h image [px]; the
/// accuracy measure of the tests and bench.
double corner_error(const Matrix3d& H_a, const Matrix3d& H_b, double width, double height);

}  // namespace alight::vision
