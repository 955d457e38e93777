// Landing target, paper 3.2 (see landing_target.hpp).
#include "vision/landing_target.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "vision/alignment.hpp"
#include "vision/homography.hpp"
#include "vision/known_floor.hpp"
#include "vision/plane_photometric.hpp"
#include "vision/waypoint.hpp"

namespace alight::vision {
namespace {

std::vector<Vector3d> rays_of(const std::vector<Vector2d>& x, const std::vector<uint8_t>& mask,
                              const Matrix3d& K_inv) {
  std::vector<Vector3d> r;
  for (size_t i = 0; i < x.size(); ++i)
    if (mask[i]) r.push_back(K_inv * x[i].homogeneous());
  return r;
}

// The two planes of one frame, however found.
struct Planes {
  PlaneMotion top, floor;
  std::vector<uint8_t> top_in, floor_in;
  int n_top = 0, n_floor = 0;
};

// Paper 3.2: two free homographies, aligned; the nearer plane is the top.
Result<Planes> paper_planes(const Correspondences& c, const PipelineParams& params,
                            TargetOutcome* out) {
  const auto pair = fit_two_homographies(c.x1, c.x2, params.homography);
  if (!pair) return Result<Planes>::fail(pair.reason());
  const HomographyFit& first = pair->first;
  for (size_t i = 0; i < c.size(); ++i)
    if (first.inlier[i]) out->labels[i] = Label::kDominant;
  out->estimate.n_inliers_dominant = first.n_inliers;
  if (!pair->second || pair->second->n_inliers < params.landing.min_platform_inliers)
    return Result<Planes>::fail(Reason::kNoTargetPlane);
  const HomographyFit& second = *pair->second;

  const Matrix3d K = c.camera->K();
  const Matrix3d K_inv = K.inverse();
  const MocapMotion mocap = mocap_motion(c.pose_1, c.pose_2, *c.mount);
  const auto al = align_two_planes(
      calibrate_homography(first.H, K), rays_of(c.x1, first.inlier, K_inv),
      rays_of(c.x2, first.inlier, K_inv), calibrate_homography(second.H, K),
      rays_of(c.x1, second.inlier, K_inv), rays_of(c.x2, second.inlier, K_inv), params.align,
      params.decomposition, rotation_prior(mocap.R_21, params.align, K(0, 0)));
  if (!al) return Result<Planes>::fail(al.reason());
  // The nearer of the two planes is the platform top.
  const bool first_is_top = al->plane_a().distance_1() < al->plane_b().distance_1();
  Planes p;
  p.top = first_is_top ? al->plane_a() : al->plane_b();
  p.floor = first_is_top ? al->plane_b() : al->plane_a();
  const HomographyFit& top_fit = first_is_top ? first : second;
  const HomographyFit& floor_fit = first_is_top ? second : first;
  p.top_in = top_fit.inlier;
  p.floor_in = floor_fit.inlier;
  p.n_top = top_fit.n_inliers;
  p.n_floor = floor_fit.n_inliers;
  return Result<Planes>::ok(std::move(p));
}

// Beyond the paper: the floor known, the motion known up to a small rotation (known_floor.hpp).
Result<Planes> known_floor_planes(const Correspondences& c, const PipelineParams& params) {
  const auto floor = known_floor(c.pose_1, *c.mount, params.landing.floor_z_m);
  if (!floor) return Result<Planes>::fail(Reason::kNoDominantPlane);
  const MocapMotion mocap = mocap_motion(c.pose_1, c.pose_2, *c.mount);
  if (mocap.baseline_m < params.waypoint.min_baseline_m)
    return Result<Planes>::fail(Reason::kSmallBaseline);
  const Matrix3d K_inv = c.camera->K().inverse();
  std::vector<Vector3d> r1, r2;
  for (size_t i = 0; i < c.size(); ++i) {
    r1.push_back(K_inv * c.x1[i].homogeneous());
    r2.push_back(K_inv * c.x2[i].homogeneous());
  }
  const KnownMotion motion{mocap.R_21, mocap.t_12};  // t12 in metres (eq. 3)
  const auto fit = fit_known_floor_planes(r1, r2, motion, *floor, c.camera->K()(0, 0),
                                          params.landing, params.homography.threshold_px);
  if (!fit) return Result<Planes>::fail(fit.reason());
  const double s = mocap.baseline_m;  // PlaneMotion's lengths are in baselines
  Planes p;
  p.top = {fit->motion.R_21, fit->motion.t_12_m / s, fit->n_1 * fit->rho_top * s};
  p.floor = {fit->motion.R_21, fit->motion.t_12_m / s, fit->n_1 * fit->rho_floor * s};
  p.top_in = fit->top;
  p.floor_in = fit->floor;
  p.n_top = fit->n_top;
  p.n_floor = fit->n_floor;
  return Result<Planes>::ok(std::move(p));
}

// The paper's floor is the known one: distance from camera 1 within floor_tol_frac, normals
// within max_normal_angle_deg.
bool floor_agrees(const PlaneMotion& floor, const Correspondences& c,
                  const PipelineParams& params) {
  const auto known = known_floor(c.pose_1, *c.mount, params.landing.floor_z_m);
  if (!known) return false;
  const double d_m = floor.distance_1() * mocap_motion(c.pose_1, c.pose_2, *c.mount).baseline_m;
  return std::abs(d_m - known->d_1_m) <= params.landing.floor_tol_frac * known->d_1_m &&
         direction_angle(floor.unit_normal_1(), known->n_1) <=
             params.landing.max_normal_angle_deg * M_PI / 180.0;
}

// A platform top is opaque: the floor is seen around it, never through it (the known floor's
// hypotheses keep to the same rule, known_floor.cpp). The paper's planes split a bare floor into
// a "top" a few centimetres up that holds most of the view and a "floor" of the rest, all of it
// inside that "top" (landing_none_photo 9505). The floor's
// matches seen outside the convex hull of the top's in image 2 (by more than the threshold, or
// inside it but off the top's plane: a match near the epipole fits both planes).
int floor_seen_around_top(const Correspondences& c, const Planes& planes, const Matrix3d& H_top_px,
                          double threshold_px) {
  std::vector<cv::Point2f> top_px, hull;
  for (size_t i = 0; i < c.size(); ++i)
    if (planes.top_in[i])
      top_px.emplace_back(static_cast<float>(c.x2[i].x()), static_cast<float>(c.x2[i].y()));
  int n = 0;
  if (top_px.size() >= 3) cv::convexHull(top_px, hull);
  for (size_t i = 0; i < c.size(); ++i) {
    if (!planes.floor_in[i] || planes.top_in[i]) continue;
    const cv::Point2f q(static_cast<float>(c.x2[i].x()), static_cast<float>(c.x2[i].y()));
    const Vector3d p = H_top_px * c.x1[i].homogeneous();
    const bool fits_top = p.z() > 0 && (p.hnormalized() - c.x2[i]).norm() <= threshold_px;
    n += hull.size() < 3 || fits_top || cv::pointPolygonTest(hull, q, true) <= threshold_px;
  }
  return n;
}

// The images' verdict on the planes the features found (plane_photometric.hpp): the pixels
// inside the top's features (their convex hull in the current image) must follow the top's
// plane, and the pixels around the floor's features outside it the floor's. False tops over a
// bare floor are features tracked a few pixels wrong: every other pixel of their "top" and
// their "floor" lies on one surface, at one gamma, and rarely at 1 and 0. A pixel set too bland
// or too uncertain to tell gives no verdict (blank paper, a grey tile): the features decide.
bool follows_its_planes(const Correspondences& c, const Planes& planes, const Matrix3d& H_floor_px,
                        const Matrix3d& H_top_px, const cv::Mat& gray_1, const cv::Mat& gray_2,
                        const LandingParams& p) {
  // Samples: the hull's inside at a stride that keeps about kHullPixels; kPatches floor
  // patches of (2 kPatchHalf + 1)^2 pixels, clear of the hull by the threshold's margin.
  constexpr int kHullPixels = 1000, kPatches = 20, kPatchHalf = 5;
  constexpr double kClear = 4.0;  // [px] a patch's pixels this far outside the hull at least
  std::vector<cv::Point2f> top_u2, hull;
  for (size_t i = 0; i < c.size(); ++i)
    if (planes.top_in[i]) top_u2.emplace_back(c.u2[i].x(), c.u2[i].y());
  if (top_u2.size() < 3) return true;
  cv::convexHull(top_u2, hull);
  const cv::Rect inside(0, 0, gray_2.cols, gray_2.rows);
  const auto informative = [&](const std::optional<PlanePhotometry>& f, double max_sigma) {
    return f && f->ncc_best >= p.photometric_min_ncc && f->sigma_gamma <= max_sigma;
  };
  // A certain gamma decides alone; a less certain one only when it sits photometric_far_sigmas
  // standard deviations beyond the tolerance: a hull on a false top over a busy floor can be
  // blurred to a wide fit that still places it nowhere near the top's plane.
  const auto off_the_top = [&](const std::optional<PlanePhotometry>& f) {
    if (!f || f->ncc_best < p.photometric_min_ncc) return false;
    const double beyond = std::abs(f->gamma - 1.0) - p.photometric_tol;
    return beyond > 0 && (f->sigma_gamma <= p.photometric_max_sigma ||
                          beyond > p.photometric_far_sigmas * f->sigma_gamma);
  };

  std::vector<cv::Point> px;
  const cv::Rect box = cv::boundingRect(hull) & inside;
  const double area = std::max(1.0, cv::contourArea(hull));
  const int stride = std::max(1, static_cast<int>(std::ceil(std::sqrt(area / kHullPixels))));
  for (int v = box.y; v < box.y + box.height; v += stride)
    for (int u = box.x; u < box.x + box.width; u += stride)
      if (cv::pointPolygonTest(hull, cv::Point2f(u, v), true) >= kClear) px.emplace_back(u, v);
  const auto on_top =
      plane_photometry(gray_1, gray_2, *c.camera, H_floor_px, H_top_px, px, kHullPixels / 10);
  if (off_the_top(on_top)) return false;

  std::vector<size_t> floor_i;
  for (size_t i = 0; i < c.size(); ++i)
    if (planes.floor_in[i] && !planes.top_in[i] &&
        cv::pointPolygonTest(hull, cv::Point2f(c.u2[i].x(), c.u2[i].y()), true) <
            -(kPatchHalf * M_SQRT2 + kClear))
      floor_i.push_back(i);
  const size_t step = std::max<size_t>(1, floor_i.size() / kPatches);
  std::vector<double> gammas;
  for (size_t k = 0; k < floor_i.size(); k += step) {
    const int u0 = static_cast<int>(std::lround(c.u2[floor_i[k]].x()));
    const int v0 = static_cast<int>(std::lround(c.u2[floor_i[k]].y()));
    px.clear();
    for (int dv = -kPatchHalf; dv <= kPatchHalf; ++dv)
      for (int du = -kPatchHalf; du <= kPatchHalf; ++du)
        if (inside.contains(cv::Point(u0 + du, v0 + dv))) px.emplace_back(u0 + du, v0 + dv);
    const auto patch = plane_photometry(gray_1, gray_2, *c.camera, H_floor_px, H_top_px, px,
                                        (kPatchHalf + 1) * (kPatchHalf + 1));
    if (informative(patch, 3 * p.photometric_max_sigma)) gammas.push_back(patch->gamma);
  }
  if (static_cast<int>(gammas.size()) < p.photometric_min_patches) return true;
  std::nth_element(gammas.begin(), gammas.begin() + gammas.size() / 2, gammas.end());
  return std::abs(gammas[gammas.size() / 2]) <= p.photometric_tol;
}

TargetOutcome platform_of(const Correspondences& c, const PipelineParams& params,
                          const Planes& planes, TargetOutcome out, const cv::Mat& gray_1,
                          const cv::Mat& gray_2);

}  // namespace

double side_from_extent(double range_m, size_t n) {
  if (n < 2) return range_m;
  return range_m * static_cast<double>(n + 1) / static_cast<double>(n - 1);
}

TargetOutcome find_landing_target(const Correspondences& c, const PipelineParams& params,
                                  const cv::Mat& gray_1, const cv::Mat& gray_2) {
  assert(c.camera && c.mount);
  const auto usable = [&](const cv::Mat& m) {
    return !m.empty() && m.type() == CV_8UC1 && m.cols == c.camera->width &&
           m.rows == c.camera->height;
  };
  if ((!gray_1.empty() || !gray_2.empty()) && !(usable(gray_1) && usable(gray_2)))
    return find_landing_target(c, params);
  TargetOutcome out;
  out.labels.assign(c.size(), Label::kOutlier);
  const auto found = [](const TargetOutcome& o) {
    return o.reason == Reason::kOk || o.reason == Reason::kPartialView;
  };
  const std::string& mode = params.landing.floor_prior;
  TargetOutcome paper = out;
  if (mode != "always") {
    const auto planes = paper_planes(c, params, &paper);
    bool floor_known = false;
    if (!planes) {
      paper.reason = planes.reason();
    } else {
      paper = platform_of(c, params, *planes, paper, gray_1, gray_2);
      floor_known = floor_agrees(planes->floor, c, params);
    }
    if (mode == "off" || (found(paper) && floor_known)) return paper;
  }
  // The paper's planes gave no platform, or their floor is not the floor: the known floor's turn.
  TargetOutcome known = out;
  if (const auto planes = known_floor_planes(c, params)) {
    known = platform_of(c, params, *planes, out, gray_1, gray_2);
  } else {
    known.reason = planes.reason();
  }
  // Where the prior finds nothing either, the paper's outcome stands (a floor a few percent off
  // is the paper's bas-relief ambiguity, not a false platform).
  return mode == "always" || found(known) ? known : paper;
}

namespace {

TargetOutcome platform_of(const Correspondences& c, const PipelineParams& params,
                          const Planes& planes, TargetOutcome out, const cv::Mat& gray_1,
                          const cv::Mat& gray_2) {
  const PlaneMotion& top = planes.top;
  const PlaneMotion& floor = planes.floor;
  const Matrix3d K = c.camera->K();
  const Matrix3d K_inv = K.inverse();
  const MocapMotion mocap = mocap_motion(c.pose_1, c.pose_2, *c.mount);
  for (size_t i = 0; i < c.size(); ++i)
    out.labels[i] = planes.top_in[i]     ? Label::kTarget
                    : planes.floor_in[i] ? Label::kDominant
                                         : Label::kOutlier;
  out.estimate.n_inliers_dominant = planes.n_floor;
  out.estimate.n_inliers_target = planes.n_top;
  if (direction_angle(top.unit_normal_1(), floor.unit_normal_1()) >
      params.landing.max_normal_angle_deg * M_PI / 180.0) {
    out.reason = Reason::kNoTargetPlane;
    return out;
  }

  // The floor seen around the top in fewer than min_floor_inliers places: the "top" is the
  // floor, or most of it (floor_seen_around_top).
  if (floor_seen_around_top(c, planes, K * top.homography() * K_inv,
                            params.homography.threshold_px) < params.landing.min_floor_inliers) {
    out.reason = Reason::kNoTargetPlane;
    return out;
  }

  // Platform features on the platform plane, in world (eqs. 4-6 with the motion-capture scale).
  if (mocap.baseline_m < params.waypoint.min_baseline_m) {
    out.reason = Reason::kSmallBaseline;
    return out;
  }
  const Isometry3d X_WC2 = camera_in_world(c.pose_2.X_WB(), c.mount->X_BC());
  const Vector3d n2 = top.n_2() / mocap.baseline_m;  // n2~ in [1/m]
  std::vector<Vector3d> pts_W;
  for (size_t i = 0; i < c.size(); ++i) {
    if (!planes.top_in[i]) continue;
    const Vector3d ray = K_inv * c.x2[i].homogeneous();
    const double denom = n2.dot(ray);
    if (denom <= 0) continue;
    pts_W.push_back(X_WC2 * (ray / denom));
  }
  if (pts_W.size() < 4) {
    out.reason = Reason::kDecompositionFailed;
    return out;
  }
  // Axes of the features' minimum-area bounding rectangle in the plane (Freeman & Shapira 1975,
  // rotating calipers, as cv::minAreaRect); the centre of that extent is the aim point (the mean
  // would follow the texture's feature density, the extent follows the edges). Principal axes
  // were 15-20 deg off on the nearly square 21.6 x 27.9 cm ream (Monte Carlo landing_c).
  Vector3d mean = Vector3d::Zero();
  for (const auto& p : pts_W) mean += p;
  mean /= static_cast<double>(pts_W.size());
  const Vector3d n_W = (X_WC2.linear() * -top.n_2()).normalized();  // towards camera 2
  if (std::acos(std::clamp(n_W.z(), -1.0, 1.0)) > params.landing.max_tilt_deg * M_PI / 180.0) {
    out.reason = Reason::kNoTargetPlane;
    return out;
  }
  Vector3d e1 = n_W.unitOrthogonal();
  Vector3d e2 = n_W.cross(e1);
  std::vector<cv::Point2f> q2;
  for (const auto& p : pts_W)
    q2.emplace_back(static_cast<float>((p - mean).dot(e1)), static_cast<float>((p - mean).dot(e2)));
  cv::Point2f corner[4];
  cv::minAreaRect(q2).points(corner);
  Eigen::Vector2d side_a(corner[1].x - corner[0].x, corner[1].y - corner[0].y);
  Eigen::Vector2d side_b(corner[2].x - corner[1].x, corner[2].y - corner[1].y);
  if (side_a.norm() < side_b.norm()) std::swap(side_a, side_b);
  if (side_a.norm() < 1e-9) {
    out.reason = Reason::kDecompositionFailed;
    return out;
  }
  const Eigen::Vector2d a_long = side_a.normalized();
  const Eigen::Vector2d a_short(-a_long.y(), a_long.x());
  const Vector3d ax_long = a_long.x() * e1 + a_long.y() * e2;
  const Vector3d ax_short = a_short.x() * e1 + a_short.y() * e2;
  double lo[2] = {1e9, 1e9}, hi[2] = {-1e9, -1e9};
  for (const auto& p : pts_W) {
    const double s[2] = {(p - mean).dot(ax_long), (p - mean).dot(ax_short)};
    for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], s[k]), hi[k] = std::max(hi[k], s[k]);
  }
  const Vector3d centre_W =
      mean + 0.5 * (lo[0] + hi[0]) * ax_long + 0.5 * (lo[1] + hi[1]) * ax_short;
  const Vector3d centre_C2 = X_WC2.inverse() * centre_W;
  if (centre_C2.z() <= 0) {
    out.reason = Reason::kDecompositionFailed;
    return out;
  }
  const Vector3d aim_ray = centre_C2 / centre_C2.z();
  const auto w_top = compute_waypoint(top, aim_ray, c.pose_1, c.pose_2, *c.mount, params.waypoint);
  if (!w_top) {
    out.reason = w_top.reason();
    return out;
  }
  const auto w_floor =
      compute_waypoint(floor, aim_ray, c.pose_1, c.pose_2, *c.mount, params.waypoint);
  if (!w_floor) {
    out.reason = w_floor.reason();
    return out;
  }
  TargetEstimate& e = out.estimate;
  e.p_W = w_top->p_W;
  e.n_W = w_top->n_W;
  e.height_m = w_floor->distance_m - w_top->distance_m;
  e.size_m[0] = side_from_extent(hi[0] - lo[0], pts_W.size());
  e.size_m[1] = side_from_extent(hi[1] - lo[1], pts_W.size());
  // The plane is level (max_tilt_deg), so the long axis' direction in the world xy plane is the
  // platform's yaw; autonomy aligns the gear with the edges before touch-down.
  e.yaw_rad = std::atan2(ax_long.y(), ax_long.x());
  if (e.yaw_rad <= -M_PI / 2) e.yaw_rad += M_PI;
  if (e.yaw_rad > M_PI / 2) e.yaw_rad -= M_PI;
  const auto px = c.camera->project(w_top->p_C2);
  e.pixel = px ? *px : (K * aim_ray).hnormalized();
  for (int k = 0; k < 4; ++k) {  // the extent's rectangle, for the diagnostic image
    const double s0 = (k == 0 || k == 3) ? lo[0] : hi[0], s1 = k < 2 ? lo[1] : hi[1];
    const Vector3d corner_C2 = X_WC2.inverse() * (mean + s0 * ax_long + s1 * ax_short);
    if (const auto q = c.camera->project(corner_C2)) e.outline.push_back(*q);
  }
  if (e.height_m < params.landing.min_height_m || e.height_m > params.landing.max_height_m) {
    out.reason = Reason::kNoTargetPlane;
    return out;
  }
  // A platform cut by the border of either image: only features seen in both are matched, so
  // the extent is that of the part visible in both. A cut platform has a row of features along
  // the border; one stray inlier there is no cut.
  const double m = params.landing.edge_margin_px;
  const auto near_border = [&](const Vector2d& u) {
    return u.x() < m || u.y() < m || u.x() > c.camera->width - 1 - m ||
           u.y() > c.camera->height - 1 - m;
  };
  int at_border = 0;
  for (size_t i = 0; i < c.size(); ++i)
    if (planes.top_in[i] && (near_border(c.u2[i]) || (!c.u1.empty() && near_border(c.u1[i]))))
      ++at_border;
  const bool cut = at_border >= 2;
  if (!gray_1.empty() && !gray_2.empty() && params.landing.photometric_tol > 0 &&
      !follows_its_planes(c, planes, K * floor.homography() * K_inv, K * top.homography() * K_inv,
                          gray_1, gray_2, params.landing)) {
    out.reason = Reason::kNoTargetPlane;
    return out;
  }
  out.reason = cut ? Reason::kPartialView : Reason::kOk;
  return out;
}

}  // namespace
}  // namespace alight::vision
