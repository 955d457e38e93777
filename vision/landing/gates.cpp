// Landing stage 2, the gates (paper 3.2; beyond it, the plane-plus-parallax check of Irani &
// Anandan, ECCV 1996; see gates.hpp).
#include "vision/landing/gates.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "common/median.hpp"
#include "vision/geometry/convex_hull.hpp"
#include "vision/geometry/plane_photometric.hpp"

namespace alight::vision {
namespace {

// The photometric samples: the hull's inside at a stride that keeps about kHullPixels; kPatches
// floor patches of (2 kPatchHalf + 1)^2 pixels, clear of the hull by the threshold's margin.
constexpr int kHullPixels = 1000, kPatches = 20, kPatchHalf = 5;
constexpr double kClear = 4.0;  // [px] a patch's pixels this far outside the hull at least

// Whether a pixel set's fit says where it lies: correlated, and certain to max_sigma.
bool informative(const std::optional<PlanePhotometry>& f, double max_sigma,
                 const PhotometricLimits& p) {
  return f && f->ncc_best >= p.min_ncc && f->sigma_gamma <= max_sigma;
}

// The top's pixels off its plane. A certain gamma decides alone; a less certain one only when
// it sits far_sigmas standard deviations beyond the tolerance: a hull on a false top over a busy
// floor can be blurred to a wide fit that still places it nowhere near the top's plane.
bool off_the_top(const std::optional<PlanePhotometry>& f, const PhotometricLimits& p) {
  if (!f || f->ncc_best < p.min_ncc) return false;
  const double beyond = std::abs(f->gamma - 1.0) - p.tol;
  return beyond > 0 && (f->sigma_gamma <= p.max_sigma || beyond > p.far_sigmas * f->sigma_gamma);
}

// The fit of the pixels inside the top's hull (current image), kClear deep at least.
std::optional<PlanePhotometry> hull_photometry(const Correspondences& c,
                                               const std::vector<cv::Point2f>& hull,
                                               const Matrix3d& H_floor_px, const Matrix3d& H_top_px,
                                               const cv::Mat& gray_1, const cv::Mat& gray_2) {
  const cv::Rect inside(0, 0, gray_2.cols, gray_2.rows);
  std::vector<cv::Point> px;
  const cv::Rect box = cv::boundingRect(hull) & inside;
  const double area = std::max(1.0, cv::contourArea(hull));
  const int stride = std::max(1, static_cast<int>(std::ceil(std::sqrt(area / kHullPixels))));
  const ConvexHullDepth depth(hull);
  for (int v = box.y; v < box.y + box.height; v += stride)
    for (int u = box.x; u < box.x + box.width; u += stride)
      if (depth.depth(u, v) >= kClear) px.emplace_back(u, v);
  return plane_photometry(gray_1, gray_2, *c.camera, H_floor_px, H_top_px, px, kHullPixels / 10,
                          c.grid_1.get(), c.readout_2);
}

// The gammas of up to kPatches patches around the floor's matches clear of the top's hull, the
// informative ones only.
std::vector<double> floor_patch_gammas(const Correspondences& c, const LandingPlanes& planes,
                                       const std::vector<cv::Point2f>& hull,
                                       const Matrix3d& H_floor_px, const Matrix3d& H_top_px,
                                       const cv::Mat& gray_1, const cv::Mat& gray_2,
                                       const PhotometricLimits& p) {
  const cv::Rect inside(0, 0, gray_2.cols, gray_2.rows);
  std::vector<size_t> floor_i;
  for (size_t i = 0; i < c.size(); ++i)
    if (planes.floor_in[i] && !planes.top_in[i] &&
        cv::pointPolygonTest(hull, cv::Point2f(c.u2[i].x(), c.u2[i].y()), true) <
            -(kPatchHalf * M_SQRT2 + kClear))
      floor_i.push_back(i);
  const size_t step = std::max<size_t>(1, floor_i.size() / kPatches);
  std::vector<double> gammas;
  std::vector<cv::Point> px;
  for (size_t k = 0; k < floor_i.size(); k += step) {
    const int u0 = static_cast<int>(std::lround(c.u2[floor_i[k]].x()));
    const int v0 = static_cast<int>(std::lround(c.u2[floor_i[k]].y()));
    px.clear();
    for (int dv = -kPatchHalf; dv <= kPatchHalf; ++dv)
      for (int du = -kPatchHalf; du <= kPatchHalf; ++du)
        if (inside.contains(cv::Point(u0 + du, v0 + dv))) px.emplace_back(u0 + du, v0 + dv);
    const auto patch =
        plane_photometry(gray_1, gray_2, *c.camera, H_floor_px, H_top_px, px,
                         (kPatchHalf + 1) * (kPatchHalf + 1), c.grid_1.get(), c.readout_2);
    if (informative(patch, 3 * p.max_sigma, p)) gammas.push_back(patch->gamma);
  }
  return gammas;
}

// The convex hull of the top's inliers in image 2 (undistorted pixels); empty for fewer than 3.
std::vector<cv::Point2f> top_hull_2(const Correspondences& c, const std::vector<uint8_t>& top_in) {
  std::vector<cv::Point2f> top_px, hull;
  for (size_t i = 0; i < c.size(); ++i)
    if (top_in[i])
      top_px.emplace_back(static_cast<float>(c.x2[i].x()), static_cast<float>(c.x2[i].y()));
  if (top_px.size() >= 3) cv::convexHull(top_px, hull);
  return hull;
}

}  // namespace

Reason plane_gates(const Correspondences& c, const LandingPlanes& planes, const Matrix3d& H_top_px,
                   const Matrix3d& H_floor_px, double baseline_m, const PipelineParams& params) {
  if (direction_angle(planes.top.unit_normal_1(), planes.floor.unit_normal_1()) >
      params.landing.max_normal_angle_deg * M_PI / 180.0)
    return Reason::kTopNotParallel;
  // A top alone has no floor in sight by definition: its plane was told from the floor by the
  // known floor's inverse distance instead.
  if (!planes.top_alone &&
      floor_seen_around_top(c, planes, H_top_px, params.homography.threshold_px) <
          params.landing.min_floor_inliers)
    return Reason::kNoFloorAroundTop;
  if (!top_told_from_floor(c, planes.top_in, H_floor_px, params.homography.threshold_px,
                           kMaxTopOnFloorShare))
    return Reason::kTopFitsFloor;
  if (baseline_m < params.waypoint.min_baseline_m) return Reason::kSmallBaseline;
  return Reason::kOk;
}

bool top_clear_of_epipole(const Correspondences& c, const std::vector<uint8_t>& top_in,
                          const Matrix3d& H_floor_px, const Matrix3d& H_top_px,
                          const MocapMotion& mocap, double threshold_px) {
  const std::vector<cv::Point2f> hull = top_hull_2(c, top_in);
  if (hull.empty()) return true;
  const Matrix3d to_floor = H_floor_px * H_top_px.inverse();  // image 2 to image 2
  const auto parallax = [&](const Vector2d& u) {
    const Vector3d q = to_floor * u.homogeneous();
    return q.z() > 0 ? (q.hnormalized() - u).norm() : std::numeric_limits<double>::infinity();
  };
  // The nearest point of the hull to the epipole; with the epipole at infinity (a sideways
  // motion) the parallax barely changes over the view: the hull's corners.
  const Vector3d e = c.camera->K() * (-(mocap.R_21 * mocap.t_12));
  double least = std::numeric_limits<double>::infinity();
  for (const auto& p : hull) least = std::min(least, parallax(Vector2d(p.x, p.y)));
  if (std::abs(e.z()) > 1e-9 * e.norm()) {
    const Vector2d e2 = e.hnormalized();
    if (cv::pointPolygonTest(
            hull, cv::Point2f(static_cast<float>(e2.x()), static_cast<float>(e2.y())), false) >= 0)
      return false;
    for (size_t k = 0; k < hull.size(); ++k) {
      const Vector2d a(hull[k].x, hull[k].y);
      const Vector2d b(hull[(k + 1) % hull.size()].x, hull[(k + 1) % hull.size()].y);
      const double len2 = (b - a).squaredNorm();
      const double s = len2 > 0 ? std::clamp((e2 - a).dot(b - a) / len2, 0.0, 1.0) : 0.0;
      least = std::min(least, parallax(a + s * (b - a)));
    }
  }
  return least >= kMinParallaxThresholds * threshold_px;
}

int floor_seen_around_top(const Correspondences& c, const LandingPlanes& planes,
                          const Matrix3d& H_top_px, double threshold_px) {
  int n = 0;
  const ConvexHullDepth depth(top_hull_2(c, planes.top_in));
  for (size_t i = 0; i < c.size(); ++i) {
    if (!planes.floor_in[i] || planes.top_in[i]) continue;
    const cv::Point2f q(static_cast<float>(c.x2[i].x()), static_cast<float>(c.x2[i].y()));
    n += depth.empty() || carries(H_top_px, c, i, threshold_px) ||
         !depth.inside_by(q.x, q.y, threshold_px);
  }
  return n;
}

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

// Written as refusals: a value that compares false either way (NaN) is not refused here.
bool top_level(const Vector3d& n_W, const LandingParams& params) {
  return !(std::acos(std::clamp(n_W.z(), -1.0, 1.0)) > params.max_tilt_deg * M_PI / 180.0);
}

bool height_in_range(double height_m, const LandingParams& params) {
  return !(height_m < params.min_height_m || height_m > params.max_height_m);
}

bool cut_by_border(const Correspondences& c, const LandingPlanes& planes,
                   const LandingParams& params) {
  const double m = params.edge_margin_px;
  const auto near_border = [&](const Vector2d& u) {
    return u.x() < m || u.y() < m || u.x() > c.camera->width - 1 - m ||
           u.y() > c.camera->height - 1 - m;
  };
  int at_border = 0;
  for (size_t i = 0; i < c.size(); ++i)
    if (planes.top_in[i] && (near_border(c.u2[i]) || (!c.u1.empty() && near_border(c.u1[i]))))
      ++at_border;
  return at_border >= 2;
}

Reason photometric_gate(const Correspondences& c, const LandingPlanes& planes,
                        const Matrix3d& H_floor_px, const Matrix3d& H_top_px, const cv::Mat& gray_1,
                        const cv::Mat& gray_2, const PhotometricLimits& p) {
  std::vector<cv::Point2f> top_u2, hull;
  for (size_t i = 0; i < c.size(); ++i)
    if (planes.top_in[i]) top_u2.emplace_back(c.u2[i].x(), c.u2[i].y());
  if (top_u2.size() < 3) return Reason::kOk;
  cv::convexHull(top_u2, hull);
  if (off_the_top(hull_photometry(c, hull, H_floor_px, H_top_px, gray_1, gray_2), p))
    return Reason::kTopPhotometry;
  if (!floor_patches_agree(
          floor_patch_gammas(c, planes, hull, H_floor_px, H_top_px, gray_1, gray_2, p), p))
    return Reason::kFloorPhotometry;
  return Reason::kOk;
}

bool floor_patches_agree(std::vector<double> gammas, const PhotometricLimits& limits) {
  if (gammas.empty()) return true;
  const double median = upper_median(gammas);
  if (std::abs(median) > limits.tol) return false;
  constexpr size_t kSpreadPatches = 5;  // fewer have no spread to speak of
  if (gammas.size() < kSpreadPatches) return true;
  std::vector<double> dev;
  for (const double g : gammas) dev.push_back(std::abs(g - median));
  return 1.4826 * upper_median(dev) <= limits.max_floor_spread;
}

}  // namespace alight::vision
