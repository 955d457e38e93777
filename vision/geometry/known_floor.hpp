#pragma once
// Landing planes from the known motion and the known floor (beyond the paper; paper 3.2, eq. 2).
//
// The paper (3.2) takes the dominant homography of all matches as the floor and a second one,
// over its outliers, as the platform top: a free 8-DOF fit per plane. Over a floor that gives
// little (flat grey tiles with features only at their corners, a pale low-texture floor) the
// dominant fit is weak or wrong. The vehicle knows more than the paper uses: motion capture gives
// the camera motion (R21, t12 in metres, eq. 3) and the floor is a known plane (world z =
// floor_z_m). A plane with unit normal n1 at distance d1 from camera 1 then induces
//
//     H = R21 (I - t12 n1^T / d1)              (eq. 2 with the metric t12; pixels: K H K^-1)
//
// so the floor's homography is known, and every plane parallel to it (a level platform top) is
// one parameter away: rho = 1 / d1, its inverse distance. What remains uncertain is R21: motion
// capture's orientation noise (~0.1 deg a sample) moves the image by ~1-2 px, as much as the
// parallax that tells the platform from the floor at small baselines. So R21 is corrected by a
// small rotation omega that both planes share, fitted together with the top's rho:
//
//   1. hypotheses: each match in turn is taken for floor; omega from its two equations
//      (minimum norm: the roll about the optical axis stays at motion capture's), bounded by
//      max_rotation_correction_deg;
//   2. score: floor inliers (transfer error under the known floor <= threshold) plus the
//      largest set of other matches that share one rho of a plausible platform height (each
//      match's rho by 1-D least squares, intervals of rho within the threshold, swept);
//   3. the best hypothesis (ties: the smaller correction; exhaustive and in match order, so
//      deterministic) is refined by Gauss-Newton on omega and rho over both inlier sets, the
//      matches reclassified after each step.
//
// A wrong hypothesis (platform matches taken for floor) needs a correction of the size of the
// parallax and explains fewer matches than the truth (the true floor's matches fall farther than
// the floor). The top's normal is then checked against the floor's with a free 3-DOF fit of
// n1/d1 (linear given R21, t12): a chance set of outliers at one rho is no plane.

#include <cstdint>
#include <optional>
#include <vector>

#include "common/camera_mount.hpp"
#include "common/geometry.hpp"
#include "common/pose_buffer.hpp"
#include "vision/params.hpp"
#include "vision/status.hpp"

namespace alight::vision {

/// Camera motion from motion capture in metres (eq. 3): x2 = R21 (x1 - t12), camera 1 frame.
struct KnownMotion {
  Matrix3d R_21 = Matrix3d::Identity();
  Vector3d t_12_m = Vector3d::Zero();  ///< camera 2 centre in camera 1 [m]
};

/// The floor in camera 1: unit normal n1 (from the camera towards the plane) and distance [m].
struct KnownPlane {
  Vector3d n_1 = Vector3d::UnitZ();
  double d_1_m = 1.0;
};

/// The floor z = floor_z_m of the world frame seen from camera 1 at pose_1; nullopt when the
/// camera is not above it.
std::optional<KnownPlane> known_floor(const PoseSample& pose_1, const CameraMount& mount,
                                      double floor_z_m);

/// Calibrated homography of a plane of inverse distance rho along n1 (rho n1 = n1~, eq. 2):
/// H = R21 (I - t12 rho n1^T); normalised rays x2 ~ H x1.
Matrix3d plane_homography(const KnownMotion& m, const Vector3d& n_1, double rho_per_m);

struct KnownFloorPlanes {
  KnownMotion motion;  ///< with the fitted rotation correction
  double rotation_correction_rad = 0;
  Vector3d n_1 = Vector3d::UnitZ();           ///< floor normal in camera 1 (shared by the top)
  double rho_floor = 0, rho_top = 0;          ///< inverse distances from camera 1 [1/m]
  Vector3d n_top_free_1 = Vector3d::UnitZ();  ///< the top's unit normal, 3-DOF fit
  std::vector<uint8_t> floor, top;            ///< per match: inlier of the plane
  int n_floor = 0, n_top = 0;
  double height_m() const { return 1.0 / rho_floor - 1.0 / rho_top; }
};

/// Fits the floor (known up to the rotation correction) and a level top from normalised rays
/// (z = 1) of the matches; focal_px converts the thresholds. Fails with kSmallBaseline (no
/// translation), kTooFewMatches, kNoDominantPlane (fewer than min_floor_inliers on the floor) or
/// a top's refusal: kNoTopHeight (no match off the floor in the top's height range),
/// kTopMatchesFew (a height the matches share, but fewer than min_platform_inliers on it, before
/// the refinement or after it), kTopNotParallel (its free normal off the floor's by more than
/// max_normal_angle_deg).
Result<KnownFloorPlanes> fit_known_floor_planes(const std::vector<Vector3d>& rays_1,
                                                const std::vector<Vector3d>& rays_2,
                                                const KnownMotion& motion, const KnownPlane& floor,
                                                double focal_px, const LandingParams& params,
                                                double threshold_px);

/// Beyond the pair: close over a top on a floor too bland for features (the
/// approach's last metre over a paper top on a pale floor) the view holds the top alone, and the
/// pair has no floor to stand on. A level top is still one rho under the known motion: the
/// largest set of matches sharing one rho of a platform height (step 2 without the rotation
/// correction: with no floor it would trade against rho, and over the approach's baselines
/// motion capture's 0.1 deg moves rho by well under a percent). That set is the top alone when
/// it holds a clear majority (0.6) of the matches and min_platform_inliers, its free
/// normal is level with the floor's, and the floor is seen outside it in fewer than
/// min_floor_inliers places (where it is seen, the pair decides). The floor's fields hold the
/// known floor and its matches; n_floor counts them all.
Result<KnownFloorPlanes> fit_known_top_alone(const std::vector<Vector3d>& rays_1,
                                             const std::vector<Vector3d>& rays_2,
                                             const KnownMotion& motion, const KnownPlane& floor,
                                             double focal_px, const LandingParams& params,
                                             double threshold_px);

}  // namespace alight::vision
