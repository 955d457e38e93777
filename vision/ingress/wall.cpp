// Ingress stage 1, the wall (paper 3.3, 3.1.2; see wall.hpp).
#include "vision/ingress/wall.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "vision/geometry/waypoint.hpp"

namespace alight::vision {
namespace {

// The point nearest both rays c_a + s d_a and c_b + t d_b (world); nullopt when the rays are
// near parallel, it lies behind either camera, or the rays pass farther apart than
// max_gap_rad seen from camera B (a mismatch: two views of one point meet, up to the poses'
// noise; 0 disables).
std::optional<Vector3d> triangulate_midpoint(const Isometry3d& X_WA, const Vector3d& d_a,
                                             const Isometry3d& X_WB, const Vector3d& d_b,
                                             double max_gap_rad) {
  const Vector3d w = X_WA.translation() - X_WB.translation();
  const double a = d_a.dot(d_a), b = d_a.dot(d_b), c = d_b.dot(d_b);
  const double d = d_a.dot(w), e = d_b.dot(w);
  const double den = a * c - b * b;
  if (den < 1e-12 * a * c) return std::nullopt;
  const double s = (b * e - c * d) / den, t = (a * e - b * d) / den;
  if (s <= 0 || t <= 0) return std::nullopt;
  const Vector3d p_a = X_WA.translation() + s * d_a, p_b = X_WB.translation() + t * d_b;
  if (max_gap_rad > 0 && (p_a - p_b).norm() > max_gap_rad * t * std::sqrt(c)) return std::nullopt;
  return 0.5 * (p_a + p_b);
}

// One homography as the wall: its decomposition (motion capture's rotation picks the physical
// solution; a motion other than motion capture's refuses it) and the median depth of its
// triangulated inliers in camera 2.
Wall candidate(const Correspondences& c, const HomographyFit& f,
               const std::vector<std::optional<Vector3d>>& X_W_match,
               const PipelineParams& params) {
  const Matrix3d K = c.camera->K(), K_inv = K.inverse();
  const MocapMotion mocap = mocap_motion(c.pose_1, c.pose_2, *c.mount);
  const Isometry3d X_C2W = camera_in_world(c.pose_2.X_WB(), c.mount->X_BC()).inverse();
  std::vector<Vector3d> r1, r2;
  std::vector<double> z;
  for (size_t k = 0; k < c.size(); ++k) {
    if (!f.inlier[k]) continue;
    r1.push_back(K_inv * c.x1[k].homogeneous());
    r2.push_back(K_inv * c.x2[k].homogeneous());
    if (X_W_match[k]) z.push_back((X_C2W * *X_W_match[k]).z());
  }
  DecompositionPrior prior;
  prior.R_21 = mocap.R_21;
  auto plane = decompose(calibrate_homography(f.H, K), r1, r2, prior, params.decomposition);
  if (plane) {
    constexpr double kDeg = M_PI / 180.0;
    if (direction_angle(plane->t_12, mocap.t_12) >
            params.waypoint.max_translation_angle_deg * kDeg ||
        rotation_angle(plane->R_21, mocap.R_21) > params.waypoint.max_rotation_error_deg * kDeg)
      plane = Result<PlaneMotion>::fail(Reason::kMotionDisagrees);
  }
  double depth = std::numeric_limits<double>::infinity();
  if (!z.empty()) {
    std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
    depth = z[z.size() / 2];
  }
  return Wall{&f, std::move(plane), depth};
}

}  // namespace

std::vector<std::optional<Vector3d>> triangulate_matches(const Correspondences& c,
                                                         double max_ray_gap_px) {
  const Isometry3d X_WC1 = camera_in_world(c.pose_1.X_WB(), c.mount->X_BC());
  const Isometry3d X_WC2 = camera_in_world(c.pose_2.X_WB(), c.mount->X_BC());
  const double max_gap_rad = max_ray_gap_px / c.camera->K()(0, 0);
  std::vector<std::optional<Vector3d>> X_W_match(c.size());
  for (size_t k = 0; k < c.size(); ++k)
    X_W_match[k] = triangulate_midpoint(X_WC1, X_WC1.linear() * c.ray1(k), X_WC2,
                                        X_WC2.linear() * c.ray2(k), max_gap_rad);
  return X_W_match;
}

Wall choose_wall(const Correspondences& c, const PlanePair& planes,
                 const std::vector<std::optional<Vector3d>>& X_W_match,
                 const PipelineParams& params) {
  Wall wall = candidate(c, planes.first, X_W_match, params);
  // A room's back wall lies metres behind the wall; a second fit of the wall itself lies at its
  // depth, within the triangulation's centimetres.
  constexpr double kNearerMarginM = 0.5;
  if (planes.second) {
    Wall other = candidate(c, *planes.second, X_W_match, params);
    if (other.plane && (!wall.plane || other.depth_m < wall.depth_m - kNearerMarginM))
      wall = std::move(other);
  }
  return wall;
}

}  // namespace alight::vision
