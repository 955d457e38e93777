#pragma once
// Multiple-homography alignment (paper 3.2 and its ref. 20). Two planes seen in the same two
// views share the camera motion: H_a = R21 (I - t12 n_a~^T), H_b = R21 (I - t12 n_b~^T), so they
// share the epipole and H_a^-1 H_b is a planar homology (Zelnik-Manor & Irani, "Multiview
// constraints on homographies", PAMI 2002; Hartley & Zisserman, 2nd ed., sec. 13.2). Each
// homography is decomposed separately (Longuet-Higgins 1986, decomposition.hpp); the pair of
// candidates whose rotation and translation agree is the physical one (the false solution of a
// homography depends on its plane, so false solutions of two planes disagree). From that pair a
// joint Levenberg-Marquardt refinement of R21, t12 and both n~ over both inlier sets minimises
// the Cauchy-weighted transfer error (IRLS, AlignParams::robust), which makes the two
// homographies consistent by construction.

#include <optional>
#include <vector>

#include "vision/geometry/decomposition.hpp"
#include "vision/params.hpp"
#include "vision/status.hpp"

namespace alight::vision {

struct TwoPlaneMotion {
  Matrix3d R_21 = Matrix3d::Identity();
  Vector3d t_12 = Vector3d::UnitX();     ///< unit length
  Vector3d n_a = Vector3d::UnitZ();      ///< n~ of plane a in camera 1 [1/baseline]
  Vector3d n_b = Vector3d::UnitZ();      ///< n~ of plane b in camera 1 [1/baseline]
  double rms_before = 0, rms_after = 0;  ///< transfer error of both sets [normalised units]
  double rotation_disagreement_rad = 0;  ///< between the two separate decompositions
  double translation_disagreement_rad = 0;

  bool used_rotation_prior = false;

  PlaneMotion plane_a() const { return {R_21, t_12, n_a}; }
  PlaneMotion plane_b() const { return {R_21, t_12, n_b}; }
};

/// A prior on R21 from motion capture (beyond the paper): a residual weight * log(R_prior^T R21)
/// joins the transfer errors, so weight is the transfer error [normalised image units] that one
/// radian of disagreement costs as much as: (feature sigma / focal length) / (prior sigma).
struct RotationPrior {
  Matrix3d R_21 = Matrix3d::Identity();
  double weight = 0.0;
};

/// The prior of params (rotation_prior_sigma_deg, feature_sigma_px) for a camera of focal length
/// focal_px; none when the prior is switched off.
std::optional<RotationPrior> rotation_prior(const Matrix3d& R_21_mocap, const AlignParams& params,
                                            double focal_px);

/// Aligns the calibrated homographies of two planes given each one's inlier rays (normalised,
/// z = 1) in both images. Fails with kSmallBaseline (no translation in either), or
/// kDecompositionFailed (either plane has no candidate in front of the cameras), kPlanesDisagree
/// (no pair of candidates agrees within the limits: the two "planes" are not two planes of one
/// rigid scene), or kAlignedPlaneBehind (the joint refinement moved a plane behind a camera).
Result<TwoPlaneMotion> align_two_planes(const Matrix3d& H_a, const std::vector<Vector3d>& rays_1a,
                                        const std::vector<Vector3d>& rays_2a, const Matrix3d& H_b,
                                        const std::vector<Vector3d>& rays_1b,
                                        const std::vector<Vector3d>& rays_2b,
                                        const AlignParams& params = {},
                                        const DecompositionParams& dparams = {},
                                        const std::optional<RotationPrior>& prior = std::nullopt);

}  // namespace alight::vision
