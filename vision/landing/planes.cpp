// Landing stage 1, the planes (paper 3.2, eqs. 1-2; see planes.hpp).
#include "vision/landing/planes.hpp"

#include <cmath>
#include <utility>

#include "vision/geometry/alignment.hpp"
#include "vision/geometry/homography.hpp"
#include "vision/geometry/known_floor.hpp"
#include "vision/geometry/waypoint.hpp"

namespace alight::vision {
namespace {

std::vector<Vector3d> rays_of(const std::vector<Vector2d>& x, const std::vector<uint8_t>& mask,
                              const Matrix3d& K_inv) {
  std::vector<Vector3d> r;
  for (size_t i = 0; i < x.size(); ++i)
    if (mask[i]) r.push_back(K_inv * x[i].homogeneous());
  return r;
}

}  // namespace

Result<LandingPlanes> paper_planes(const Correspondences& c, const PipelineParams& params,
                                   TargetOutcome* out) {
  const auto pair = fit_two_homographies(c.x1, c.x2, params.homography);
  if (!pair) return Result<LandingPlanes>::fail(pair.reason());
  const HomographyFit& first = pair->first;
  for (size_t i = 0; i < c.size(); ++i)
    if (first.inlier[i]) out->labels[i] = Label::kDominant;
  out->estimate.n_inliers_dominant = first.n_inliers;
  if (!pair->second || pair->second->n_inliers < params.landing.min_platform_inliers)
    return Result<LandingPlanes>::fail(Reason::kNoTargetPlane);
  const HomographyFit& second = *pair->second;

  const Matrix3d K = c.camera->K();
  const Matrix3d K_inv = K.inverse();
  const MocapMotion mocap = mocap_motion(c.pose_1, c.pose_2, *c.mount);
  const auto al = align_two_planes(
      calibrate_homography(first.H, K), rays_of(c.x1, first.inlier, K_inv),
      rays_of(c.x2, first.inlier, K_inv), calibrate_homography(second.H, K),
      rays_of(c.x1, second.inlier, K_inv), rays_of(c.x2, second.inlier, K_inv), params.align,
      params.decomposition, rotation_prior(mocap.R_21, params.align, K(0, 0)));
  if (!al) return Result<LandingPlanes>::fail(al.reason());
  const bool first_is_top = al->plane_a().distance_1() < al->plane_b().distance_1();
  LandingPlanes p;
  p.top = first_is_top ? al->plane_a() : al->plane_b();
  p.floor = first_is_top ? al->plane_b() : al->plane_a();
  const HomographyFit& top_fit = first_is_top ? first : second;
  const HomographyFit& floor_fit = first_is_top ? second : first;
  p.top_in = top_fit.inlier;
  p.floor_in = floor_fit.inlier;
  p.n_top = top_fit.n_inliers;
  p.n_floor = floor_fit.n_inliers;
  return Result<LandingPlanes>::ok(std::move(p));
}

Result<LandingPlanes> known_floor_planes(const Correspondences& c, const PipelineParams& params) {
  const auto floor = known_floor(c.pose_1, *c.mount, params.landing.floor_z_m);
  if (!floor) return Result<LandingPlanes>::fail(Reason::kNoDominantPlane);
  const MocapMotion mocap = mocap_motion(c.pose_1, c.pose_2, *c.mount);
  if (mocap.baseline_m < params.waypoint.min_baseline_m)
    return Result<LandingPlanes>::fail(Reason::kSmallBaseline);
  const Matrix3d K_inv = c.camera->K().inverse();
  std::vector<Vector3d> r1, r2;
  for (size_t i = 0; i < c.size(); ++i) {
    r1.push_back(K_inv * c.x1[i].homogeneous());
    r2.push_back(K_inv * c.x2[i].homogeneous());
  }
  const KnownMotion motion{mocap.R_21, mocap.t_12};  // t12 in metres (eq. 3)
  const double f = c.camera->K()(0, 0);
  const double thr = params.homography.threshold_px;
  auto fit = fit_known_floor_planes(r1, r2, motion, *floor, f, params.landing, thr);
  bool top_alone = false;
  if (!fit && fit.reason() != Reason::kSmallBaseline) {
    if (auto alone = fit_known_top_alone(r1, r2, motion, *floor, f, params.landing, thr)) {
      fit = std::move(alone);
      top_alone = true;
    }
  }
  if (!fit) return Result<LandingPlanes>::fail(fit.reason());
  const double s = mocap.baseline_m;  // PlaneMotion's lengths are in baselines
  LandingPlanes p;
  p.top_alone = top_alone;
  p.top = {fit->motion.R_21, fit->motion.t_12_m / s, fit->n_1 * fit->rho_top * s};
  p.floor = {fit->motion.R_21, fit->motion.t_12_m / s, fit->n_1 * fit->rho_floor * s};
  p.top_in = fit->top;
  p.floor_in = fit->floor;
  p.n_top = fit->n_top;
  p.n_floor = fit->n_floor;
  return Result<LandingPlanes>::ok(std::move(p));
}

bool floor_agrees(const PlaneMotion& floor, const Correspondences& c,
                  const PipelineParams& params) {
  const auto known = known_floor(c.pose_1, *c.mount, params.landing.floor_z_m);
  if (!known) return false;
  const double d_m = floor.distance_1() * mocap_motion(c.pose_1, c.pose_2, *c.mount).baseline_m;
  return std::abs(d_m - known->d_1_m) <= params.landing.floor_tol_frac * known->d_1_m &&
         direction_angle(floor.unit_normal_1(), known->n_1) <=
             params.landing.max_normal_angle_deg * M_PI / 180.0;
}

bool carries(const Matrix3d& H_px, const Correspondences& c, size_t i, double threshold_px) {
  const Vector3d p = H_px * c.x1[i].homogeneous();
  return p.z() > 0 && (p.hnormalized() - c.x2[i]).norm() <= threshold_px;
}

}  // namespace alight::vision
