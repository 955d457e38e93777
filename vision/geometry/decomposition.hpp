#pragma once
// Homography decomposition (paper 3.1.2, eqs. 1-2; Longuet-Higgins, "The reconstruction of a
// plane surface from two perspective projections", Proc. R. Soc. Lond. B 227, 1986).
//
// The calibrated homography H = R21 (I - t12 n1~^T) (eq. 2) is scaled so that its middle
// singular value is 1, which Longuet-Higgins shows is the scale of R21 (I - t n^T). The
// eigenvectors of H^T H then span the plane normal and the translation, and the closed form
// (written with the SVD as in Ma, Soatto, Kosecka & Sastry, "An Invitation to 3-D Vision", 2004,
// sec. 5.3.3) gives four candidates (R, t, n), two of each sign. Candidates that put the
// inliers behind either camera are dropped (positive depth); the remaining two are told apart
// by a second plane (alignment.hpp) or by a prior (motion capture rotation or plane normal).

#include <optional>
#include <vector>

#include "common/geometry.hpp"
#include "vision/params.hpp"
#include "vision/status.hpp"

namespace alight::vision {

/// One physical interpretation of a calibrated homography, in the paper's symbols (eq. 1):
/// x2 = R21 (x1 - t12), n1~^T x1 = 1, lengths in units of the baseline |t12| = 1.
struct PlaneMotion {
  Matrix3d R_21 = Matrix3d::Identity();  ///< camera 1 axes -> camera 2 axes (R21)
  Vector3d t_12 = Vector3d::UnitX();     ///< camera 2 centre in camera 1, unit length (t12)
  Vector3d n_1 = Vector3d::UnitZ();      ///< n1~ = n1 / d1: plane normal over distance [1/baseline]

  /// H = R21 (I - t12 n1~^T) (eq. 2), with middle singular value 1.
  Matrix3d homography() const;
  /// Unit normal of the plane in camera 1, pointing from the camera to the plane.
  Vector3d unit_normal_1() const { return n_1.normalized(); }
  /// Distance of camera 1 from the plane [baselines].
  double distance_1() const { return 1.0 / n_1.norm(); }
  /// n2~ of eq. 4: the plane seen from camera 2 [1/baseline].
  Vector3d n_2() const { return R_21 * n_1 / (1.0 - t_12.dot(n_1)); }
};

/// Calibrated homography from a pixel homography: K^-1 H K.
Matrix3d calibrate_homography(const Matrix3d& H_px, const Matrix3d& K);

/// All (up to 4) candidates of a calibrated homography, before any disambiguation; empty when
/// H has no translation part (sigma1 - sigma3 < min_singular_gap: pure rotation or a plane at
/// infinity). The sign of H is fixed from the correspondences: x2^T H x1 > 0 (x normalised).
std::vector<PlaneMotion> decompose_homography(const Matrix3d& H_cal,
                                              const std::vector<Vector3d>& rays_1,
                                              const DecompositionParams& params = {});

/// Keeps the candidates for which at least min_front_fraction of the rays (normalised image
/// points, z = 1) lie in front of both cameras: n1~^T x1 > 0 and n2~^T x2 > 0.
std::vector<PlaneMotion> positive_depth(const std::vector<PlaneMotion>& candidates,
                                        const std::vector<Vector3d>& rays_1,
                                        const std::vector<Vector3d>& rays_2,
                                        const DecompositionParams& params = {});

/// Prior knowledge to pick one candidate when no second plane is available.
struct DecompositionPrior {
  std::optional<Matrix3d> R_21;  ///< e.g. from motion capture (R_BC^T R_WB2^T R_WB1 R_BC)
  std::optional<Vector3d> n_1;   ///< expected unit normal in camera 1 (e.g. the floor)
};

/// Decomposes and disambiguates: positive depth, then the candidate closest to the prior (the
/// rotation first, then the normal). Fails with kSmallBaseline (no translation part) or
/// kDecompositionFailed (no candidate in front of both cameras), kDecompositionAmbiguous (two
/// left, distinct, and no prior).
Result<PlaneMotion> decompose(const Matrix3d& H_cal, const std::vector<Vector3d>& rays_1,
                              const std::vector<Vector3d>& rays_2, const DecompositionPrior& prior,
                              const DecompositionParams& params = {});

/// Angle of the rotation R_a^T R_b [rad].
double rotation_angle(const Matrix3d& R_a, const Matrix3d& R_b);
/// Angle between two directions [rad].
double direction_angle(const Vector3d& a, const Vector3d& b);

}  // namespace alight::vision
