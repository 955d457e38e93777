// Landing target, paper 3.2, and beyond it the top's rim (see landing_target.hpp).
#include "vision/landing/landing_target.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <utility>

#include "vision/geometry/alignment.hpp"
#include "vision/geometry/bilinear.hpp"
#include "vision/geometry/convex_hull.hpp"
#include "vision/geometry/homography.hpp"
#include "vision/geometry/known_floor.hpp"
#include "vision/geometry/plane_photometric.hpp"
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

// The two planes of one frame, however found.
struct Planes {
  PlaneMotion top, floor;
  std::vector<uint8_t> top_in, floor_in;
  int n_top = 0, n_floor = 0;
  bool top_alone = false;  ///< the view holds the top alone (fit_known_top_alone)
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
  if (!fit) return Result<Planes>::fail(fit.reason());
  const double s = mocap.baseline_m;  // PlaneMotion's lengths are in baselines
  Planes p;
  p.top_alone = top_alone;
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

// Whether the plane of pixel homography H_px carries match i's x1 to its x2 within threshold_px.
bool carries(const Matrix3d& H_px, const Correspondences& c, size_t i, double threshold_px) {
  const Vector3d p = H_px * c.x1[i].homogeneous();
  return p.z() > 0 && (p.hnormalized() - c.x2[i]).norm() <= threshold_px;
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
  const ConvexHullDepth depth(hull);
  for (size_t i = 0; i < c.size(); ++i) {
    if (!planes.floor_in[i] || planes.top_in[i]) continue;
    const cv::Point2f q(static_cast<float>(c.x2[i].x()), static_cast<float>(c.x2[i].y()));
    n += depth.empty() || carries(H_top_px, c, i, threshold_px) ||
         !depth.inside_by(q.x, q.y, threshold_px);
  }
  return n;
}

// The top's features without the strays that stretch them over the floor (issue 15,
// landing_photo seed 10405: one floor match that fitted the top's homography put a side of the
// features' rectangle 21 cm out over the floor for a whole vantage, the centre 9 cm off). The
// top is opaque, so no floor match off its plane lies inside the hull of its features (as in
// floor_seen_around_top). While some do and removing one hull corner leaves fewer inside, the
// corner that leaves the fewest goes (the one farthest from the features' centroid on a tie),
// up to max_stray_top_share of the features; at that limit with floor still inside, the
// features are left as they were (the features, not a few strays, cover the floor: the checks
// before decide about those).
std::vector<uint8_t> without_strays(const Correspondences& c, const Planes& planes,
                                    const Matrix3d& H_top_px, double threshold_px,
                                    double max_share) {
  std::vector<cv::Point2f> floor_px;  // floor matches off the top's plane
  for (size_t i = 0; i < c.size(); ++i)
    if (planes.floor_in[i] && !planes.top_in[i] && !carries(H_top_px, c, i, threshold_px))
      floor_px.emplace_back(static_cast<float>(c.x2[i].x()), static_cast<float>(c.x2[i].y()));
  if (floor_px.empty()) return planes.top_in;
  std::vector<size_t> index;  // of the top's features still kept
  std::vector<cv::Point2f> pts;
  for (size_t i = 0; i < c.size(); ++i)
    if (planes.top_in[i]) {
      index.push_back(i);
      pts.emplace_back(static_cast<float>(c.x2[i].x()), static_cast<float>(c.x2[i].y()));
    }
  const auto inside = [&](const std::vector<cv::Point2f>& p) {
    if (p.size() < 3) return 0;
    std::vector<cv::Point2f> hull;
    cv::convexHull(p, hull);
    const ConvexHullDepth depth(hull);
    int n = 0;
    for (const auto& q : floor_px) n += depth.inside_by(q.x, q.y, threshold_px);
    return n;
  };
  const int max_removed = static_cast<int>(std::floor(max_share * static_cast<double>(pts.size())));
  int covered = inside(pts);
  std::vector<uint8_t> pruned = planes.top_in;
  for (int removed = 0; covered > 0; ++removed) {
    if (removed >= max_removed || pts.size() <= 4) return planes.top_in;
    cv::Point2f centroid(0, 0);
    for (const auto& q : pts) centroid += q;
    centroid *= 1.0f / static_cast<float>(pts.size());
    std::vector<int> corners;
    cv::convexHull(pts, corners);
    int best = -1, best_covered = covered;
    float best_far = -1;
    for (const int k : corners) {
      std::vector<cv::Point2f> rest = pts;
      rest.erase(rest.begin() + k);
      const int n = inside(rest);
      const cv::Point2f d = pts[static_cast<size_t>(k)] - centroid;
      const float far = d.dot(d);
      if (n < best_covered || (n == best_covered && best >= 0 && far > best_far))
        best = k, best_covered = n, best_far = far;
    }
    if (best < 0) break;  // no corner alone uncovers any: the rest are no strays
    pruned[index[static_cast<size_t>(best)]] = 0;
    index.erase(index.begin() + best);
    pts.erase(pts.begin() + best);
    covered = best_covered;
  }
  return pruned;
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
  const ConvexHullDepth depth(hull);
  for (int v = box.y; v < box.y + box.height; v += stride)
    for (int u = box.x; u < box.x + box.width; u += stride)
      if (depth.depth(u, v) >= kClear) px.emplace_back(u, v);
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
  return floor_patches_agree(std::move(gammas), p);
}

TargetOutcome platform_of(const Correspondences& c, const PipelineParams& params,
                          const Planes& planes, TargetOutcome out, const cv::Mat& gray_1,
                          const cv::Mat& gray_2);

}  // namespace

bool top_told_from_floor(const Correspondences& c, const std::vector<uint8_t>& top_in,
                         const Matrix3d& H_floor_px, double threshold_px, double max_share) {
  int n = 0, on_floor = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    if (!top_in[i]) continue;
    ++n;
    on_floor += carries(H_floor_px, c, i, threshold_px);
  }
  return on_floor <= max_share * n;
}

bool floor_patches_agree(std::vector<double> gammas, const LandingParams& params) {
  if (static_cast<int>(gammas.size()) < params.photometric_min_patches) return true;
  std::nth_element(gammas.begin(), gammas.begin() + gammas.size() / 2, gammas.end());
  const double median = gammas[gammas.size() / 2];
  if (std::abs(median) > params.photometric_tol) return false;
  constexpr size_t kSpreadPatches = 5;  // fewer have no spread to speak of
  if (gammas.size() < kSpreadPatches) return true;
  std::vector<double> dev;
  for (const double g : gammas) dev.push_back(std::abs(g - median));
  std::nth_element(dev.begin(), dev.begin() + dev.size() / 2, dev.end());
  return 1.4826 * dev[dev.size() / 2] <= params.photometric_max_floor_spread;
}

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

// The top's rectangle in its plane: its axes (long, short) and its sides' places along them from
// origin_W [m].
struct Rect {
  Vector3d origin_W, axis[2];
  double lo[2], hi[2];
};

// The features' extent along the axes, from their mean.
Rect features_rect(const std::vector<Vector3d>& pts_W, const Vector3d& mean,
                   const Vector3d& ax_long, const Vector3d& ax_short) {
  Rect r{mean, {ax_long, ax_short}, {1e9, 1e9}, {-1e9, -1e9}};
  for (const auto& p : pts_W)
    for (int k = 0; k < 2; ++k) {
      const double s = (p - mean).dot(r.axis[k]);
      r.lo[k] = std::min(r.lo[k], s), r.hi[k] = std::max(r.hi[k], s);
    }
  return r;
}

// The extent widened by side_from_extent's (n + 1) / (n - 1), half on each side: the features'
// expected shortfall of the top's edges.
Rect widened_by_shortfall(Rect r, size_t n) {
  for (int k = 0; k < 2; ++k) {
    const double range = r.hi[k] - r.lo[k];
    const double widen = 0.5 * (side_from_extent(range, n) - range);
    r.lo[k] -= widen, r.hi[k] += widen;
  }
  return r;
}

// The estimate of a top measured as r: the waypoint of its centre on the top's plane and the
// height above the floor's along the same ray (eqs. 4-6), its sizes, yaw and outline; the
// waypoint's failure as the reason.
Reason measure_top(const Correspondences& c, const Planes& planes, const Rect& r,
                   const Isometry3d& X_WC2, const PipelineParams& params, TargetEstimate* e) {
  const Vector3d centre_W =
      r.origin_W + 0.5 * (r.lo[0] + r.hi[0]) * r.axis[0] + 0.5 * (r.lo[1] + r.hi[1]) * r.axis[1];
  const Vector3d centre_C2 = X_WC2.inverse() * centre_W;
  if (centre_C2.z() <= 0) return Reason::kDecompositionFailed;
  const Vector3d aim_ray = centre_C2 / centre_C2.z();
  const auto w_top =
      compute_waypoint(planes.top, aim_ray, c.pose_1, c.pose_2, *c.mount, params.waypoint);
  if (!w_top) return w_top.reason();
  const auto w_floor =
      compute_waypoint(planes.floor, aim_ray, c.pose_1, c.pose_2, *c.mount, params.waypoint);
  if (!w_floor) return w_floor.reason();
  e->p_W = w_top->p_W;
  e->n_W = w_top->n_W;
  e->height_m = w_floor->distance_m - w_top->distance_m;
  e->size_m[0] = r.hi[0] - r.lo[0];
  e->size_m[1] = r.hi[1] - r.lo[1];
  // The rims can make the features' short axis the longer one.
  const bool swapped = e->size_m[1] > e->size_m[0];
  if (swapped) std::swap(e->size_m[0], e->size_m[1]);
  const Vector3d& long_W = r.axis[swapped ? 1 : 0];
  // The plane is level (max_tilt_deg), so the long axis' direction in the world xy plane is the
  // platform's yaw; autonomy aligns the gear with the edges before touch-down.
  e->yaw_rad = std::atan2(long_W.y(), long_W.x());
  if (e->yaw_rad <= -M_PI / 2) e->yaw_rad += M_PI;
  if (e->yaw_rad > M_PI / 2) e->yaw_rad -= M_PI;
  const auto px = c.camera->project(w_top->p_C2);
  e->pixel = px ? *px : (c.camera->K() * aim_ray).hnormalized();
  e->outline.clear();
  for (int k = 0; k < 4; ++k) {  // the measured rectangle, for the diagnostic image
    const double s0 = (k == 0 || k == 3) ? r.lo[0] : r.hi[0], s1 = k < 2 ? r.lo[1] : r.hi[1];
    const Vector3d corner_C2 = X_WC2.inverse() * (r.origin_W + s0 * r.axis[0] + s1 * r.axis[1]);
    if (const auto q = c.camera->project(corner_C2)) e->outline.push_back(*q);
  }
  return Reason::kOk;
}

// One side of the features' extent in the top's plane (world): the line base_W + t along_W,
// t in [t_lo, t_hi], moved outward by d along out_W.
struct Side {
  Vector3d base_W, out_W, along_W;
  double t_lo, t_hi;
};

// The least-squares line y = a + b x through points v (x, y); false for fewer than three or all
// at one x.
bool fit_line(const std::vector<Eigen::Vector2d>& v, double* a, double* b) {
  const double n = static_cast<double>(v.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const auto& q : v) sx += q.x(), sy += q.y(), sxx += q.x() * q.x(), sxy += q.x() * q.y();
  const double den = n * sxx - sx * sx;
  if (v.size() < 3 || den <= 0) return false;
  *b = (n * sxy - sx * sy) / den;
  *a = (sy - *b * sx) / n;
  return true;
}

// Where a profile P (P[j] at offset j steps) darkens outward: G_j = P[j - k] - P[j + k], its
// local maxima over j >= j0 at least min_step and at least half the strongest, innermost first,
// each to a fraction of a step by a parabola through it (offset in steps, G).
std::vector<std::pair<double, double>> darkening_steps(const std::vector<double>& P, int j0, int k,
                                                       double min_step) {
  const int n = static_cast<int>(P.size());
  std::vector<double> g(n, 0.0);
  double strongest = 0;
  for (int j = std::max(j0, k); j + k < n; ++j) {
    g[j] = P[j - k] - P[j + k];
    strongest = std::max(strongest, g[j]);
  }
  std::vector<std::pair<double, double>> steps;
  for (int j = std::max(j0, k) + 1; j + k + 1 < n; ++j) {
    const double l = g[j - 1], c = g[j], r = g[j + 1];
    if (c < min_step || c < 0.5 * strongest || c < l || c < r) continue;
    const double den = l - 2 * c + r;
    steps.emplace_back(j + (den < 0 ? 0.5 * (l - r) / den : 0.0), c);
  }
  return steps;
}

// Both images' grey levels at a grid of points of the top's plane beside a side (rim_offset,
// top_end_offset): n_t lines along the side, t_step_m apart (min_t_step_m at least, max_lines at
// most), and columns outward col_m apart, at offsets [j_lo, j_hi) past the side and margin
// columns further either way, so that lines read turned by up to max_tan stay on the grid
// (offset j is column j - j_lo + margin). g2 is the current image at the point, g1 the reference
// at the same point of the top's plane (H_12 takes a current ray to the reference's), kUnseen
// where either is out of view. nullopt: fewer than min_lines lines.
struct SideGrid {
  static constexpr float kUnseen = -1.0f;
  int n_t = 0, n_g = 0, margin = 0;
  double t_step_m = 0, t_mid = 0;    // along the side; t_mid the middle of [t_lo, t_hi]
  Vector3d corner_C2, di_C2, dj_C2;  // the point of line i, column j: corner + i di + j dj
  std::vector<float> g1, g2;
  Vector3d point_C2(int i, int j) const { return corner_C2 + i * di_C2 + j * dj_C2; }
  size_t at(int i, int j) const { return static_cast<size_t>(i) * n_g + j; }
};
std::optional<SideGrid> read_side(const Correspondences& c, const cv::Mat& gray_1,
                                  const cv::Mat& gray_2, const Matrix3d& H_12,
                                  const Isometry3d& X_WC2, const Side& side, double min_t_step_m,
                                  int max_lines, int min_lines, double col_m, int j_lo, int j_hi,
                                  double max_tan) {
  SideGrid g;
  g.t_step_m = std::max(min_t_step_m, (side.t_hi - side.t_lo) / (max_lines - 1));
  g.n_t = static_cast<int>(std::floor((side.t_hi - side.t_lo) / g.t_step_m)) + 1;
  if (g.n_t < min_lines) return std::nullopt;
  g.margin = static_cast<int>(std::ceil(0.5 * (side.t_hi - side.t_lo) * max_tan / col_m)) + 1;
  const int n_g = g.n_g = (j_hi - j_lo) + 2 * g.margin;
  const double first_col_m = (j_lo - g.margin) * col_m;
  g.t_mid = 0.5 * (side.t_lo + side.t_hi);
  // The grid is affine in the top's plane, and so in camera 2's frame.
  const Isometry3d X_C2W = X_WC2.inverse();
  g.corner_C2 = X_C2W * (side.base_W + first_col_m * side.out_W + side.t_lo * side.along_W);
  g.dj_C2 = X_C2W.linear() * (col_m * side.out_W);
  g.di_C2 = X_C2W.linear() * (g.t_step_m * side.along_W);
  g.g1.assign(static_cast<size_t>(g.n_t) * n_g, SideGrid::kUnseen);
  g.g2.assign(g.g1.size(), SideGrid::kUnseen);
  for (int i = 0; i < g.n_t; ++i)
    for (int j = 0; j < n_g; ++j) {
      const Vector3d X_C2 = g.point_C2(i, j);
      if (X_C2.z() <= 0) continue;
      const Vector3d r1 = H_12 * (X_C2 / X_C2.z());
      if (r1.z() <= 0) continue;
      const auto u1 = c.camera->project(r1), u2 = c.camera->project(X_C2);
      double v1, v2;
      if (!u1 || !u2 || !bilinear_inside(gray_1, *u1, &v1) || !bilinear_inside(gray_2, *u2, &v2))
        continue;
      g.g1[g.at(i, j)] = static_cast<float>(v1);
      g.g2[g.at(i, j)] = static_cast<float>(v2);
    }
  return g;
}

// The side's rim, or nullopt when the two images do not show one step at the same place of the
// top's plane (landing_target.hpp). step_m is half a pixel of the current image on the top.
struct Rim {
  double d_m;       // outward from the side where the rim crosses the middle of the stretch read
  double turn_rad;  // the rim's turn from the side: offset d_m + (t - mid) tan(turn_rad)
};
std::optional<Rim> rim_offset(const Correspondences& c, const cv::Mat& gray_1,
                              const cv::Mat& gray_2, const Matrix3d& H_12, const Isometry3d& X_WC2,
                              const Side& side, double step_m, const LandingParams& p) {
  const int k = 2;   // G across one pixel either side
  const int j0 = 8;  // four pixels inside the side: the top's own level
  // A line a pixel along the side at least, at most kMaxLines of them: a long side's mean is
  // steady with fewer, and every line is read at every offset (the vision's p99 per frame was
  // 52 ms on landing_lowtex with a line every pixel and a search over 37 turns, 25-29 ms with 96
  // lines).
  constexpr int kMaxLines = 48;
  // The turn from kStretches stretches of the side: each a sixth of a 14 cm side, across which
  // a rim turned 15 deg spreads its step over 6 mm, a pixel and a half at the search height.
  constexpr int kStretches = 6;
  const double max_tan = std::tan(p.rim_max_turn_deg * M_PI / 180.0);
  const int n_d = j0 + static_cast<int>(std::ceil(p.rim_search_m / step_m)) + k + 1;
  // Profile index j is the offset (j - j0) step_m.
  const auto grid = read_side(c, gray_1, gray_2, H_12, X_WC2, side, 2 * step_m, kMaxLines,
                              2 * kStretches, step_m, -j0, n_d - j0, max_tan);
  if (!grid) return std::nullopt;
  const int n_t = grid->n_t, n_g = grid->n_g, margin = grid->margin;
  const double t_step_m = grid->t_step_m, t_mid = grid->t_mid;
  const std::vector<float>&g1 = grid->g1, &g2 = grid->g2;
  // The mean over lines [i0, i1) turned by tan_turn at each offset; it ends where most of them
  // are out of either view (a side cut by the border).
  const auto profile = [&](const std::vector<float>& g, double tan_turn, int i0, int i1) {
    std::vector<double> P;
    for (int j = 0; j < n_d; ++j) {
      double sum = 0;
      int n = 0;
      for (int i = i0; i < i1; ++i) {
        const double x = j + margin + (side.t_lo + i * t_step_m - t_mid) * tan_turn / step_m;
        const int x0 = std::clamp(static_cast<int>(std::floor(x)), 0, n_g - 2);
        const double f = std::clamp(x - x0, 0.0, 1.0);
        const float a = g[static_cast<size_t>(i) * n_g + x0],
                    b = g[static_cast<size_t>(i) * n_g + x0 + 1];
        if (a < 0 || b < 0) continue;
        sum += (1 - f) * a + f * b, ++n;
      }
      if (5 * n < 4 * (i1 - i0)) break;
      P.push_back(sum / n);
    }
    return P;
  };
  // The turn: the strongest darkening of each stretch in the current image, unturned, and a
  // straight line through them (least squares; the stretches more than a pixel off it dropped
  // once). Fewer than three stretches that step, or a turn beyond rim_max_turn_deg: none.
  std::vector<Eigen::Vector2d> at;  // (t - t_mid [m], offset [steps])
  for (int s = 0; s < kStretches; ++s) {
    const int i0 = s * n_t / kStretches, i1 = (s + 1) * n_t / kStretches;
    const auto steps = darkening_steps(profile(g2, 0.0, i0, i1), j0, k, p.rim_min_step);
    if (steps.empty()) continue;
    const auto strongest =
        std::max_element(steps.begin(), steps.end(),
                         [](const auto& a, const auto& b) { return a.second < b.second; });
    at.emplace_back(side.t_lo + 0.5 * (i0 + i1 - 1) * t_step_m - t_mid, strongest->first);
  }
  double tan_turn = 0, a = 0, b = 0;
  if (fit_line(at, &a, &b)) {
    std::vector<Eigen::Vector2d> near;
    for (const auto& q : at)
      if (std::abs(q.y() - (a + b * q.x())) <= 2.0) near.push_back(q);
    if (near.size() < at.size() && !fit_line(near, &a, &b)) b = 0;
    if (std::abs(b * step_m) <= max_tan) tan_turn = b * step_m;
  }
  const std::vector<double> P1 = profile(g1, tan_turn, 0, n_t), P2 = profile(g2, tan_turn, 0, n_t);
  const auto steps_1 = darkening_steps(P1, j0, k, p.rim_min_step);
  const int n = static_cast<int>(P2.size());
  for (const auto& [j2, g2_step] : darkening_steps(P2, j0, k, p.rim_min_step)) {
    // A dark band on the top (a row of print) darkens and brightens again: beyond the rim the
    // profile stays below the top's level (its median inside the step) to the search's end.
    const int inner = static_cast<int>(std::floor(j2)) - k;
    const int outer = static_cast<int>(std::ceil(j2)) + k;
    if (inner < 1 || outer + 4 * k > n) break;  // too near the search's end to tell
    std::vector<double> in(P2.begin(), P2.begin() + inner);
    std::nth_element(in.begin(), in.begin() + in.size() / 2, in.end());
    const double level = in[in.size() / 2];
    const double beyond = *std::max_element(P2.begin() + outer, P2.end());
    if (beyond > level - 0.5 * p.rim_min_step) continue;
    // The first step that stays dark is the rim or nothing: the reference must step there too.
    for (const auto& step_1 : steps_1)
      if (std::abs(step_1.first - j2) <= 2 * p.rim_max_disagreement_px)
        return Rim{std::max(0.0, (j2 - j0) * step_m), std::atan(tan_turn)};
    return std::nullopt;
  }
  return std::nullopt;
}

// Where the top's plane stops explaining the images beyond a side (landing_target.hpp, the top's
// end): the side's offset and turn, or nullopt where the floor beyond shows no texture to tell
// it by, or its lines do not end along one straight line. H_12_top / H_12_floor take a current
// ray to the reference's ray of the same point on the top's / the floor's plane; px_m is a
// pixel of the current image on the top.
std::optional<Rim> top_end_offset(const Correspondences& c, const cv::Mat& gray_1,
                                  const cv::Mat& gray_2, const Matrix3d& H_12_top,
                                  const Matrix3d& H_12_floor, const Isometry3d& X_WC2,
                                  const Side& side, double px_m, const LandingParams& p) {
  constexpr int kInside = 4;   // [px] the strip inside the side that calibrates the threshold
  constexpr int kBeyond = 30;  // [px] the floor read beyond an end, in kParts parts
  constexpr int kParts = 3;
  constexpr int kWindow = 3;  // [px] the shares' box means either side of a step
  constexpr int kMaxLines = 36;
  constexpr int kStretches = 6;
  const double max_tan = std::tan(p.rim_max_turn_deg * M_PI / 180.0);
  // Offsets j (pixels past the side) from -kInside to n_search + kBeyond.
  const int n_search = static_cast<int>(std::ceil(p.top_end_search_m / px_m));
  const int j_lo = -kInside, j_hi = n_search + kBeyond;  // offsets [j_lo, j_hi)
  const auto grid = read_side(c, gray_1, gray_2, H_12_top, X_WC2, side, px_m, kMaxLines,
                              2 * kStretches, px_m, j_lo, j_hi, max_tan);
  if (!grid) return std::nullopt;
  const int n_t = grid->n_t, n_g = grid->n_g, margin = grid->margin;
  const double t_step_m = grid->t_step_m, t_mid = grid->t_mid;
  const std::vector<float>&v1_top = grid->g1, &v2 = grid->g2;
  const auto cell = [&](int i, int j) {  // line i at offset j, or -1 outside the grid
    const int col = j - j_lo + margin;
    return col < 0 || col >= n_g ? std::ptrdiff_t{-1}
                                 : static_cast<std::ptrdiff_t>(grid->at(i, col));
  };
  // The images' gains differ (automatic gain, flicker): the inside strip's ratio evens them.
  double sum_2 = 0, sum_1 = 0;
  std::vector<std::ptrdiff_t> inside;
  for (int i = 0; i < n_t; ++i)
    for (int j = j_lo; j < 0; ++j)
      if (const auto at = cell(i, j); at >= 0 && v2[at] >= 0) {
        inside.push_back(at);
        sum_2 += v2[at], sum_1 += v1_top[at];
      }
  if (5 * inside.size() < 4 * static_cast<size_t>(n_t * kInside) || sum_1 <= 0) return std::nullopt;
  const double gain = sum_2 / sum_1;
  const auto e_top = [&](std::ptrdiff_t at) { return std::abs(v2[at] - gain * v1_top[at]); };
  // The threshold: above the top's own disagreement in the inside strip (noise, blur, the
  // plane's error across its texture): twice its 90th percentile, and top_end_min_diff.
  std::vector<double> e_inside;
  for (const auto at : inside) e_inside.push_back(e_top(at));
  const auto q90 = e_inside.begin() + static_cast<std::ptrdiff_t>(0.9 * (e_inside.size() - 1));
  std::nth_element(e_inside.begin(), q90, e_inside.end());
  const double tau = std::max(p.top_end_min_diff, 2.0 * *q90);
  // The share of the pixels the top's plane does not explain over lines [i0, i1) read along a
  // turn (offsets grow by slope_px pixels per metre along the side): f[k] at offset k + j_lo,
  // from the inside strip on. It ends where more than a fifth of the lines are out of either
  // view.
  const auto share_off_top = [&](double slope_px, int i0, int i1) {
    std::vector<double> f;
    for (int j = j_lo; j < j_hi; ++j) {
      int off = 0, seen = 0;
      for (int i = i0; i < i1; ++i) {
        const auto at = cell(
            i, j + static_cast<int>(std::lround((side.t_lo + i * t_step_m - t_mid) * slope_px)));
        if (at < 0 || v2[at] < 0) continue;
        ++seen;
        off += e_top(at) > tau;
      }
      if (5 * seen < 4 * (i1 - i0)) break;
      f.push_back(static_cast<double>(off) / seen);
    }
    return f;
  };
  // The end: the innermost offset within the search where that share steps up (box means of
  // kWindow pixels either side) by at least half its strongest step there (beyond a rim a side
  // face or a second texture can step again), to a fraction of a pixel by a parabola;
  // (offset [px], rise).
  const auto step_up = [&](const std::vector<double>& f) -> std::optional<Eigen::Vector2d> {
    const int n_k = std::min(static_cast<int>(f.size()), n_search - j_lo + kWindow);
    std::vector<double> rise(n_k, -1.0);
    for (int k = kWindow; k + kWindow <= n_k; ++k) {
      double in = 0, out = 0;
      for (int w = 1; w <= kWindow; ++w) in += f[k - w], out += f[k + w - 1];
      rise[k] = (out - in) / kWindow;
    }
    const auto best = std::max_element(rise.begin(), rise.end());
    if (best == rise.end() || *best <= 0) return std::nullopt;
    int k = static_cast<int>(best - rise.begin());
    for (int q = 1; q + 1 < k; ++q)
      if (rise[q] >= 0.5 * *best && rise[q] >= rise[q - 1] && rise[q] >= rise[q + 1]) {
        k = q;
        break;
      }
    double at = k;
    if (k > 0 && k + 1 < n_k && rise[k - 1] >= 0 && rise[k + 1] >= 0) {
      const double den = rise[k - 1] - 2 * rise[k] + rise[k + 1];
      if (den < 0) at += 0.5 * (rise[k - 1] - rise[k + 1]) / den;
    }
    return Eigen::Vector2d(at - 0.5 + j_lo, rise[k]);  // the step lies between k - 1 and k
  };
  // The turn, as rim_offset's: the stretches' ends unturned and a least-squares line through
  // them. A straight end steps in most stretches: the one farthest off is dropped while it lies
  // more than two pixels off, down to kStretches - 2 of them.
  std::vector<Eigen::Vector2d> at_stretch;  // (t - t_mid [m], end [px])
  for (int s = 0; s < kStretches; ++s) {
    const int i0 = s * n_t / kStretches, i1 = (s + 1) * n_t / kStretches;
    const auto e = step_up(share_off_top(0.0, i0, i1));
    if (e && e->y() >= p.top_end_min_rise)
      at_stretch.emplace_back(side.t_lo + 0.5 * (i0 + i1 - 1) * t_step_m - t_mid, e->x());
  }
  double slope = 0;  // [px / m]
  for (;;) {
    double mid = 0;  // [px] at t_mid
    if (at_stretch.size() + 2 < kStretches || !fit_line(at_stretch, &mid, &slope))
      return std::nullopt;
    const auto off = [&](const Eigen::Vector2d& q) {
      return std::abs(q.y() - mid - slope * q.x());
    };
    const auto worst =
        std::max_element(at_stretch.begin(), at_stretch.end(),
                         [&](const auto& a, const auto& b) { return off(a) < off(b); });
    if (off(*worst) <= 2.0) break;
    at_stretch.erase(worst);
  }
  if (std::abs(slope * px_m) > max_tan) return std::nullopt;
  const std::vector<double> f = share_off_top(slope, 0, n_t);
  const auto e = step_up(f);
  if (!e || e->y() < p.top_end_min_rise) return std::nullopt;
  // The top's plane explains the images from the features' side up to the end. Beyond it, it
  // fails as often for kBeyond pixels (the floor is busy from the end on: the band that an edge
  // of a rug moves by between the views is no end), and the floor's plane explains most of
  // those pixels (a floor, not a second top or a side face).
  const int j_end = static_cast<int>(std::lround(e->x()));
  const auto f_at = [&](int j) { return f[static_cast<size_t>(j - j_lo)]; };
  if (j_end + 1 + kBeyond - j_lo > static_cast<int>(f.size())) return std::nullopt;
  double inside_share = 0;
  for (int j = 0; j < j_end - 1; ++j) inside_share = std::max(inside_share, f_at(j));
  if (inside_share > 0.5 * e->y()) return std::nullopt;
  for (int part = 0; part < kParts; ++part) {
    double share = 0;
    for (int j = 0; j < kBeyond / kParts; ++j)
      share += f_at(j_end + 1 + part * kBeyond / kParts + j);
    if (share / (kBeyond / kParts) - inside_share < p.top_end_min_rise) return std::nullopt;
  }
  int off_top = 0, on_floor = 0;
  for (int i = 0; i < n_t; ++i) {
    const int shift = static_cast<int>(std::lround((side.t_lo + i * t_step_m - t_mid) * slope));
    for (int j = j_end + 1; j < j_end + 1 + kBeyond; ++j) {
      const auto at = cell(i, j + shift);
      if (at < 0 || v2[at] < 0 || e_top(at) <= tau) continue;
      ++off_top;
      const Vector3d r1 = H_12_floor * grid->point_C2(i, static_cast<int>(at % n_g));
      double v1_floor;
      const auto u1 = r1.z() > 0 ? c.camera->project(r1) : std::nullopt;
      on_floor += u1 && bilinear_inside(gray_1, *u1, &v1_floor) &&
                  std::abs(v2[at] - gain * v1_floor) <= tau;
    }
  }
  if (2 * on_floor < off_top) return std::nullopt;
  return Rim{std::max(0.0, e->x()) * px_m, std::atan(slope * px_m)};
}

// The top out to its rims (landing_target.hpp): each side of the features' extent moved to its
// rim where both images show one, else widened as `widened`; nullopt where no side has a rim.
// Two or more rims that agree on a turn turn the rectangle onto them, each side with a rim then
// where its rim crosses the middle of the stretch read.
std::optional<Rect> rim_rect(const Correspondences& c, const cv::Mat& gray_1, const cv::Mat& gray_2,
                             const PlaneMotion& top, const PlaneMotion& floor,
                             const Isometry3d& X_WC2, const std::vector<Vector3d>& pts_W,
                             const Rect& features, const Rect& widened, const LandingParams& p) {
  // The reference's point of the top's plane seen at a current ray: the top's homography
  // (calibrated, x2 ~ H x1), which explains the top's features, not the poses' motion.
  const Matrix3d H_12 = top.homography().inverse();
  const Matrix3d H_12_floor = floor.homography().inverse();
  const double step_m =
      0.5 * (X_WC2.inverse() * features.origin_W).z() / c.camera->K()(0, 0);  // half a pixel
  struct Found {
    int k, sign;
    Vector3d at_W;    // from origin_W: where the rim crosses the middle of the stretch read
    double turn_rad;  // the whole rectangle's turn that squares it to this rim
  };
  std::vector<Found> found;
  Rect r = widened;
  for (int k = 0; k < 2; ++k) {
    // Along the middle of the other axis' extent: near the corners the lines run into the
    // neighbouring sides' rims.
    const int o = 1 - k;
    const double span = features.hi[o] - features.lo[o];
    const double t_lo = features.lo[o] + 0.15 * span, t_hi = features.hi[o] - 0.15 * span;
    for (const int sign : {-1, 1}) {
      const double at = sign < 0 ? features.lo[k] : features.hi[k];
      const Side side{features.origin_W + at * features.axis[k], sign * features.axis[k],
                      features.axis[o], t_lo, t_hi};
      auto rim = rim_offset(c, gray_1, gray_2, H_12, X_WC2, side, step_m, p);
      if (!rim && p.top_end_search_m > 0)
        rim = top_end_offset(c, gray_1, gray_2, H_12, H_12_floor, X_WC2, side, 2 * step_m, p);
      if (!rim) continue;
      const double s = at + sign * rim->d_m;
      (sign < 0 ? r.lo[k] : r.hi[k]) = s;
      // The turn that takes axis k's side onto the rim, as a turn of the whole rectangle about
      // the top's normal (from the long axis towards the short one).
      found.push_back({k, sign, s * features.axis[k] + 0.5 * (t_lo + t_hi) * features.axis[o],
                       (k == 1 ? sign : -sign) * rim->turn_rad});
    }
  }
  if (found.empty()) return std::nullopt;
  if (found.size() < 2) return r;
  std::vector<double> turns;
  for (const auto& f : found) turns.push_back(f.turn_rad);
  std::sort(turns.begin(), turns.end());
  const double turn = turns[turns.size() / 2];
  if (turns.back() - turns.front() > 4.0 * M_PI / 180.0 || std::abs(turn) <= 0.5 * M_PI / 180.0)
    return r;
  // Turned: the features' extent along the turned axes (widened where no rim is), each rim's
  // side where its crossing lies along them.
  const Vector3d l = std::cos(turn) * features.axis[0] + std::sin(turn) * features.axis[1];
  const Vector3d sh = -std::sin(turn) * features.axis[0] + std::cos(turn) * features.axis[1];
  Rect t = widened_by_shortfall(features_rect(pts_W, features.origin_W, l, sh), pts_W.size());
  for (const auto& f : found) (f.sign < 0 ? t.lo[f.k] : t.hi[f.k]) = f.at_W.dot(t.axis[f.k]);
  return t;
}

TargetOutcome platform_of(const Correspondences& c, const PipelineParams& params,
                          const Planes& planes, TargetOutcome out, const cv::Mat& gray_1,
                          const cv::Mat& gray_2) {
  const PlaneMotion& top = planes.top;
  const PlaneMotion& floor = planes.floor;
  const Matrix3d K = c.camera->K();
  const Matrix3d K_inv = K.inverse();
  const Matrix3d H_top_px = K * top.homography() * K_inv;
  const Matrix3d H_floor_px = K * floor.homography() * K_inv;
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
  // floor, or most of it (floor_seen_around_top). A top alone has no floor in sight by
  // definition: its plane was told from the floor by the known floor's rho instead.
  if (!planes.top_alone &&
      floor_seen_around_top(c, planes, H_top_px, params.homography.threshold_px) <
          params.landing.min_floor_inliers) {
    out.reason = Reason::kNoTargetPlane;
    return out;
  }

  if (!top_told_from_floor(c, planes.top_in, H_floor_px, params.homography.threshold_px,
                           params.landing.max_top_on_floor_share)) {
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
  const std::vector<uint8_t> top_features =
      params.landing.max_stray_top_share > 0
          ? without_strays(c, planes, H_top_px, params.homography.threshold_px,
                           params.landing.max_stray_top_share)
          : planes.top_in;
  std::vector<Vector3d> pts_W;
  for (size_t i = 0; i < c.size(); ++i) {
    if (!top_features[i]) continue;
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
  const Rect features = features_rect(pts_W, mean, a_long.x() * e1 + a_long.y() * e2,
                                      a_short.x() * e1 + a_short.y() * e2);
  const Rect widened = widened_by_shortfall(features, pts_W.size());
  if (const Reason r = measure_top(c, planes, widened, X_WC2, params, &out.estimate);
      r != Reason::kOk) {
    out.reason = r;
    return out;
  }
  const TargetEstimate& e = out.estimate;
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
      !follows_its_planes(c, planes, H_floor_px, H_top_px, gray_1, gray_2, params.landing)) {
    out.reason = Reason::kNoTargetPlane;
    return out;
  }
  // A top alone (no floor matches in sight) is seen whole where its features stop short of both
  // images' borders, as any top: over a floor too bland for features the refinement's views
  // hold the whole top and no floor match (landing_photo 10617: 928 such frames of 1780, the
  // centre within 5 mm, reported as partial views, and the refinement ran out of time). Close
  // over it, it fills the view and is cut.
  out.reason = cut ? Reason::kPartialView : Reason::kOk;
  // The top's rim, on a top seen whole (a cut top's size is never used, landing_target.hpp):
  // where the rims give no estimate (a waypoint fails, the height leaves its range), the
  // features' stands.
  if (out.reason == Reason::kOk && !gray_1.empty() && !gray_2.empty() &&
      params.landing.rim_search_m > 0) {
    if (const auto rim = rim_rect(c, gray_1, gray_2, top, floor, X_WC2, pts_W, features, widened,
                                  params.landing)) {
      TargetEstimate at_rim = out.estimate;
      if (measure_top(c, planes, *rim, X_WC2, params, &at_rim) == Reason::kOk &&
          at_rim.height_m >= params.landing.min_height_m &&
          at_rim.height_m <= params.landing.max_height_m)
        out.estimate = at_rim;
    }
  }
  return out;
}

}  // namespace
}  // namespace alight::vision
