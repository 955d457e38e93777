// Ingress stage 1, the wall (paper 3.3, 3.1.2; see wall.hpp).
#include "vision/ingress/wall.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <utility>

#include "common/median.hpp"
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
  if (!z.empty()) depth = upper_median(z);
  return Wall{&f, std::move(plane), depth};
}

// The pixel homography x2 ~ K (R21 + t21 m^T) K^-1 x1 that the plane m . X1 = 1 (camera 1; m
// = n1 / d1, unit n1 towards the plane, d1 > 0 [m]) induces under motion capture's motion
// (X2 = R21 X1 + t21), and the transfer error of match k under it [px].
Matrix3d plane_homography(const Matrix3d& K, const Matrix3d& R_21, const Vector3d& t_21,
                          const Vector3d& m) {
  return K * (R_21 + t_21 * m.transpose()) * K.inverse();
}
double transfer_px(const Matrix3d& H, const Correspondences& c, size_t k) {
  return (H * c.x1[k].homogeneous()).z() > 0 ? transfer_error(H, c.x1[k], c.x2[k])
                                             : std::numeric_limits<double>::infinity();
}

// The plane m that best transfers matches `ks` under the known motion, in closed form: with r1,
// r2 = K^-1 x1, x2 = (u, v, 1) and q = R21 r1, r2 ~ q + t21 (m . r1) gives two equations linear
// in m per match, (u t_z - t_x) r1^T m = q_x - u q_z and (v t_z - t_y) r1^T m = q_y - v q_z.
// nullopt when they do not fix m.
std::optional<Vector3d> plane_of_transfers(const Correspondences& c, const std::vector<size_t>& ks,
                                           const Matrix3d& R_21, const Vector3d& t_21) {
  const Matrix3d K_inv = c.camera->K().inverse();
  Matrix3d AtA = Matrix3d::Zero();
  Vector3d Atb = Vector3d::Zero();
  for (size_t k : ks) {
    const Vector3d r1 = K_inv * c.x1[k].homogeneous(), r2 = K_inv * c.x2[k].homogeneous();
    const Vector3d q = R_21 * r1;
    const double u = r2.x() / r2.z(), v = r2.y() / r2.z();
    const Vector3d a1 = (u * t_21.z() - t_21.x()) * r1, a2 = (v * t_21.z() - t_21.y()) * r1;
    AtA += a1 * a1.transpose() + a2 * a2.transpose();
    Atb += a1 * (q.x() - u * q.z()) + a2 * (q.y() - v * q.z());
  }
  const Eigen::LDLT<Matrix3d> ldlt(AtA);
  if (ldlt.info() != Eigen::Success || !(std::abs(ldlt.vectorD().minCoeff()) > 1e-12))
    return std::nullopt;
  const Vector3d m = ldlt.solve(Atb);
  return m.allFinite() ? std::optional<Vector3d>(m) : std::nullopt;
}

// A room's back wall lies metres behind the wall; a second fit of the wall itself lies at its
// depth, within the triangulation's centimetres: the wall is nearer than another plane by this.
constexpr double kNearerMarginM = 0.5;

// A wall is upright: its normal within this of the horizontal (a plane nearer than the
// dominant one can also be the floor seen from low down, which is no wall).
constexpr double kWallMaxNormalZ = 0.5;  // sin 30 deg
// ... and faces the camera: its normal within 60 deg of the optical axis. A plane through both
// cameras' centres (an epipolar plane) maps every point near its epipolar line onto that line,
// and a plane seen edge-on gathers the room's points strung along the line of sight: both would
// "support" any plane through them.
constexpr double kWallMinFacing = 0.5;  // cos 60 deg
// Three-point samples drawn: with a third of the candidates on the wall one sample in 27 is all
// of the wall's, so 300 miss it with odds under 1e-4.
constexpr int kFewWallDraws = 300;

// The wall of plane m (m . X1 = 1, camera 1) under the known motion: its induced homography and
// inliers (transfer within thr_px) among every match into *fit, its motion (motion capture's by
// construction: t12 of unit length, n1~ = m s) and the median depth of its triangulated
// inliers in camera 2. nullopt under kFewWallMinPoints inliers.
std::optional<Wall> known_motion_wall(const Correspondences& c, const Vector3d& m,
                                      const Matrix3d& R_21, const Vector3d& t_21,
                                      const std::vector<std::optional<Vector3d>>& X_W_match,
                                      double thr_px, HomographyFit* fit) {
  const Isometry3d X_C2W = camera_in_world(c.pose_2.X_WB(), c.mount->X_BC()).inverse();
  fit->H = plane_homography(c.camera->K(), R_21, t_21, m);
  fit->inlier.assign(c.size(), 0);
  fit->n_inliers = 0;
  double sq = 0;
  std::vector<double> z;
  for (size_t k = 0; k < c.size(); ++k) {
    const double e = transfer_px(fit->H, c, k);
    if (!(e < thr_px)) continue;
    fit->inlier[k] = 1;
    ++fit->n_inliers;
    sq += e * e;
    if (X_W_match[k]) z.push_back((X_C2W * *X_W_match[k]).z());
  }
  if (fit->n_inliers < kFewWallMinPoints || z.empty()) return std::nullopt;
  fit->rms_px = std::sqrt(sq / fit->n_inliers);
  fit->iterations = kFewWallDraws;
  const double s = t_21.norm();
  PlaneMotion motion;
  motion.R_21 = R_21;
  motion.t_12 = -(R_21.transpose() * t_21) / s;
  motion.n_1 = m * s;
  return Wall{fit, Result<PlaneMotion>::ok(motion), upper_median(z)};
}

}  // namespace

std::optional<Wall> few_feature_wall(const Correspondences& c, const HomographyFit& dominant,
                                     double dominant_depth_m,
                                     const std::vector<std::optional<Vector3d>>& X_W_match,
                                     const PipelineParams& params, HomographyFit* fit) {
  const Isometry3d X_WC1 = camera_in_world(c.pose_1.X_WB(), c.mount->X_BC());
  const Isometry3d X_WC2 = camera_in_world(c.pose_2.X_WB(), c.mount->X_BC());
  const Isometry3d X_C1W = X_WC1.inverse(), X_C2W = X_WC2.inverse();
  // 1. The candidates: triangulated outliers of the dominant plane well in front of it.
  std::vector<size_t> cand;
  std::vector<Vector3d> X1;
  for (size_t k = 0; k < c.size(); ++k) {
    if (dominant.inlier[k] || !X_W_match[k]) continue;
    const double z2 = (X_C2W * *X_W_match[k]).z();
    if (!(z2 > 0 && z2 < dominant_depth_m - kNearerMarginM)) continue;
    cand.push_back(k);
    X1.push_back(X_C1W * *X_W_match[k]);
  }
  if (static_cast<int>(cand.size()) < kFewWallMinPoints) return std::nullopt;
  // 2. Planes through three of them (seeded draws), upright and facing the camera, scored by
  // the candidates they transfer within the homography's threshold.
  const Isometry3d X_C2C1 = X_C2W * X_WC1;
  const Matrix3d R_21 = X_C2C1.linear();
  const Vector3d t_21 = X_C2C1.translation();
  const Matrix3d K = c.camera->K();
  const double thr = params.homography.threshold_px;
  const auto wall_like = [&](const Vector3d& m) {
    const Vector3d n = m.normalized();  // m . X1 = 1: towards the plane
    return m.norm() > 0 && std::abs((X_WC1.linear() * n).z()) <= kWallMaxNormalZ &&
           n.z() >= kWallMinFacing;
  };
  const auto support = [&](const Vector3d& m) {
    const Matrix3d H = plane_homography(K, R_21, t_21, m);
    std::vector<size_t> in;
    for (size_t k : cand)
      if (transfer_px(H, c, k) < thr) in.push_back(k);
    return in;
  };
  std::mt19937 rng(static_cast<uint32_t>(params.homography.seed));
  std::uniform_int_distribution<size_t> pick(0, cand.size() - 1);
  std::vector<size_t> best;
  for (int draw = 0; draw < kFewWallDraws; ++draw) {
    const size_t i = pick(rng), j = pick(rng), l = pick(rng);
    if (i == j || j == l || i == l) continue;
    const Vector3d n = (X1[j] - X1[i]).cross(X1[l] - X1[i]);
    if (!(n.norm() > 1e-6)) continue;  // near collinear
    const double d = n.dot(X1[i]);
    if (!(std::abs(d) > 1e-9)) continue;  // through the camera
    const Vector3d m = n / d;
    if (!wall_like(m)) continue;
    auto in = support(m);
    if (in.size() > best.size()) best = std::move(in);
  }
  if (static_cast<int>(best.size()) < kFewWallMinPoints) return std::nullopt;
  // 3. The plane that best transfers its supporters, and its inliers among every match.
  const auto m = plane_of_transfers(c, best, R_21, t_21);
  if (!m || !wall_like(*m)) return std::nullopt;
  return known_motion_wall(c, *m, R_21, t_21, X_W_match, thr, fit);
}

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
  if (planes.second) {
    Wall other = candidate(c, *planes.second, X_W_match, params);
    if (other.plane && (!wall.plane || other.depth_m < wall.depth_m - kNearerMarginM))
      wall = std::move(other);
  }
  return wall;
}

}  // namespace alight::vision
