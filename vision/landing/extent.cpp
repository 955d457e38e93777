// Landing stage 3, the extent (paper 3.1.3, 3.2; see extent.hpp).
#include "vision/landing/extent.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "vision/geometry/convex_hull.hpp"
#include "vision/geometry/waypoint.hpp"

namespace alight::vision {

double side_from_extent(double range_m, size_t n) {
  if (n < 2) return range_m;
  return range_m * static_cast<double>(n + 1) / static_cast<double>(n - 1);
}

std::vector<uint8_t> without_strays(const Correspondences& c, const LandingPlanes& planes,
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

std::vector<Vector3d> top_points_W(const Correspondences& c, const LandingPlanes& planes,
                                   const Matrix3d& H_top_px, const Isometry3d& X_WC2,
                                   double baseline_m, const PipelineParams& params) {
  const Matrix3d K_inv = c.camera->K().inverse();
  const Vector3d n2 = planes.top.n_2() / baseline_m;  // n2~ in [1/m]
  const std::vector<uint8_t> top_features =
      without_strays(c, planes, H_top_px, params.homography.threshold_px, kMaxStrayTopShare);
  std::vector<Vector3d> pts_W;
  for (size_t i = 0; i < c.size(); ++i) {
    if (!top_features[i]) continue;
    const Vector3d ray = K_inv * c.x2[i].homogeneous();
    const double denom = n2.dot(ray);
    if (denom <= 0) continue;
    pts_W.push_back(X_WC2 * (ray / denom));
  }
  return pts_W;
}

Vector3d top_normal_W(const LandingPlanes& planes, const Isometry3d& X_WC2) {
  return (X_WC2.linear() * -planes.top.n_2()).normalized();
}

std::optional<TopRect> features_extent(const std::vector<Vector3d>& pts_W, const Vector3d& n_W) {
  Vector3d mean = Vector3d::Zero();
  for (const auto& p : pts_W) mean += p;
  mean /= static_cast<double>(pts_W.size());
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
  if (side_a.norm() < 1e-9) return std::nullopt;
  const Eigen::Vector2d a_long = side_a.normalized();
  const Eigen::Vector2d a_short(-a_long.y(), a_long.x());
  return features_rect(pts_W, mean, a_long.x() * e1 + a_long.y() * e2,
                       a_short.x() * e1 + a_short.y() * e2);
}

Result<TopRect> top_features_rect(const std::vector<Vector3d>& pts_W, const Vector3d& n_W) {
  if (pts_W.size() < 4) return Result<TopRect>::fail(Reason::kTopPointsFew);
  auto rect = features_extent(pts_W, n_W);
  if (!rect) return Result<TopRect>::fail(Reason::kTopPointsFew);
  return Result<TopRect>::ok(*rect);
}

TopRect features_rect(const std::vector<Vector3d>& pts_W, const Vector3d& mean,
                      const Vector3d& ax_long, const Vector3d& ax_short) {
  TopRect r{mean, {ax_long, ax_short}, {1e9, 1e9}, {-1e9, -1e9}};
  for (const auto& p : pts_W)
    for (int k = 0; k < 2; ++k) {
      const double s = (p - mean).dot(r.axis[k]);
      r.lo[k] = std::min(r.lo[k], s), r.hi[k] = std::max(r.hi[k], s);
    }
  return r;
}

TopRect widened_by_shortfall(TopRect r, size_t n) {
  for (int k = 0; k < 2; ++k) {
    const double range = r.hi[k] - r.lo[k];
    const double widen = 0.5 * (side_from_extent(range, n) - range);
    r.lo[k] -= widen, r.hi[k] += widen;
  }
  return r;
}

Reason measure_top(const Correspondences& c, const LandingPlanes& planes, const TopRect& r,
                   const Isometry3d& X_WC2, const PipelineParams& params, TargetEstimate* e) {
  const Vector3d centre_W =
      r.origin_W + 0.5 * (r.lo[0] + r.hi[0]) * r.axis[0] + 0.5 * (r.lo[1] + r.hi[1]) * r.axis[1];
  const Vector3d centre_C2 = X_WC2.inverse() * centre_W;
  if (centre_C2.z() <= 0) return Reason::kAimBehindCamera;
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
  e->yaw_rad = wrap_axis_angle(std::atan2(long_W.y(), long_W.x()));
  const auto px = c.pixel2(w_top->p_C2);
  e->pixel = px ? *px : (c.camera->K() * aim_ray).hnormalized();
  e->outline.clear();
  for (int k = 0; k < 4; ++k) {  // the measured rectangle, for the diagnostic image
    const double s0 = (k == 0 || k == 3) ? r.lo[0] : r.hi[0], s1 = k < 2 ? r.lo[1] : r.hi[1];
    const Vector3d corner_C2 = X_WC2.inverse() * (r.origin_W + s0 * r.axis[0] + s1 * r.axis[1]);
    if (const auto q = c.pixel2(corner_C2)) e->outline.push_back(*q);
  }
  return Reason::kOk;
}

}  // namespace alight::vision
