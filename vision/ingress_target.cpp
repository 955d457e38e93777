// Ingress target, paper 3.3 (see ingress_target.hpp).
#include "vision/ingress_target.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "vision/decomposition.hpp"
#include "vision/homography.hpp"
#include "vision/waypoint.hpp"

namespace alight::vision {
namespace {

std::vector<double> merged(std::vector<double> v, double merge_px) {
  std::sort(v.begin(), v.end());
  std::vector<double> out;
  for (double x : v) {
    if (!out.empty() && x - out.back() <= merge_px) continue;  // keep the first of a cluster
    out.push_back(x);
  }
  return out;
}

int cell_of(const std::vector<double>& cuts, double x) {
  const auto it = std::upper_bound(cuts.begin(), cuts.end(), x);
  const int i = static_cast<int>(it - cuts.begin()) - 1;
  return std::clamp(i, 0, static_cast<int>(cuts.size()) - 2);
}

}  // namespace

void line_cuts(const cv::Mat& image, const IngressParams& p, std::vector<double>* x_cuts,
               std::vector<double>* y_cuts, std::vector<cv::Vec4i>* kept) {
  // Smoothing first: the wall's own texture gives short edges everywhere, the opening's border
  // one long straight edge that survives the blur while the texture's break up.
  cv::Mat smooth, edges;
  if (p.blur_sigma_px > 0)
    cv::GaussianBlur(image, smooth, cv::Size(), p.blur_sigma_px);
  else
    smooth = image;
  cv::Canny(smooth, edges, p.canny_low, p.canny_high);
  std::vector<cv::Vec4i> segments;
  cv::HoughLinesP(edges, segments, 1.0, CV_PI / 180.0, p.hough_threshold,
                  p.hough_min_length_frac * image.cols, p.hough_max_gap_px);
  const double tilt = std::tan(p.max_line_tilt_deg * M_PI / 180.0);
  std::vector<double> xs{0.0, static_cast<double>(image.cols)};
  std::vector<double> ys{0.0, static_cast<double>(image.rows)};
  for (const auto& s : segments) {
    const double dx = std::abs(s[2] - s[0]), dy = std::abs(s[3] - s[1]);
    if (dx <= tilt * dy) {
      xs.push_back(0.5 * (s[0] + s[2]));
    } else if (dy <= tilt * dx) {
      ys.push_back(0.5 * (s[1] + s[3]));
    } else {
      continue;
    }
    if (kept) kept->push_back(s);
  }
  *x_cuts = merged(xs, p.merge_px);
  *y_cuts = merged(ys, p.merge_px);
  // The image borders stay the outermost cuts even when a line lies near them.
  x_cuts->front() = 0.0, x_cuts->back() = image.cols;
  y_cuts->front() = 0.0, y_cuts->back() = image.rows;
}

TargetOutcome find_ingress_target(const Correspondences& c, const cv::Mat& image,
                                  const PipelineParams& params) {
  assert(c.camera && c.mount);
  const IngressParams& p = params.ingress;
  TargetOutcome out;
  out.labels.assign(c.size(), Label::kOutlier);
  const auto wall = fit_homography(c.x1, c.x2, params.homography);
  if (!wall) {
    out.reason = wall.reason();
    return out;
  }
  for (size_t i = 0; i < c.size(); ++i)
    if (wall->inlier[i]) out.labels[i] = Label::kDominant;
  out.estimate.n_inliers_dominant = wall->n_inliers;

  // The wall plane; motion capture's rotation picks the physical decomposition.
  const MocapMotion mocap = mocap_motion(c.pose_1, c.pose_2, *c.mount);
  if (mocap.baseline_m < params.waypoint.min_baseline_m) {
    out.reason = Reason::kSmallBaseline;
    return out;
  }
  const Matrix3d K = c.camera->K(), K_inv = K.inverse();
  std::vector<Vector3d> r1, r2;
  for (size_t i = 0; i < c.size(); ++i)
    if (wall->inlier[i]) {
      r1.push_back(K_inv * c.x1[i].homogeneous());
      r2.push_back(K_inv * c.x2[i].homogeneous());
    }
  DecompositionPrior prior;
  prior.R_21 = mocap.R_21;
  const auto plane =
      decompose(calibrate_homography(wall->H, K), r1, r2, prior, params.decomposition);
  if (!plane) {
    out.reason = plane.reason();
    return out;
  }

  // 2D histogram of wall inliers and off-wall features over the cells of the line cuts.
  std::vector<double> xc, yc;
  line_cuts(image, p, &xc, &yc, &out.lines);
  const int nx = static_cast<int>(xc.size()) - 1, ny = static_cast<int>(yc.size()) - 1;
  // Prefix sums (ny+1) x (nx+1) of both counts, so each block costs O(1).
  std::vector<int> in((nx + 1) * (ny + 1), 0), off((nx + 1) * (ny + 1), 0);
  auto at = [&](std::vector<int>& v, int i, int j) -> int& { return v[j * (nx + 1) + i]; };
  for (size_t k = 0; k < c.size(); ++k) {
    const int i = cell_of(xc, c.u2[k].x()), j = cell_of(yc, c.u2[k].y());
    ++at(wall->inlier[k] ? in : off, i + 1, j + 1);
  }
  for (int j = 1; j <= ny; ++j)
    for (int i = 1; i <= nx; ++i) {
      at(in, i, j) += at(in, i - 1, j) + at(in, i, j - 1) - at(in, i - 1, j - 1);
      at(off, i, j) += at(off, i - 1, j) + at(off, i, j - 1) - at(off, i - 1, j - 1);
    }
  auto block = [&](std::vector<int>& v, int i0, int j0, int i1, int j1) {  // cells [i0,i1)x[j0,j1)
    return at(v, i1, j1) - at(v, i0, j1) - at(v, i1, j0) + at(v, i0, j0);
  };
  int best = 0;
  double best_area = 0;
  int b[4] = {0, 0, 0, 0};
  for (int i0 = 0; i0 < nx; ++i0)
    for (int i1 = i0 + 1; i1 <= nx; ++i1)
      for (int j0 = 0; j0 < ny; ++j0)
        for (int j1 = j0 + 1; j1 <= ny; ++j1) {
          if (block(in, i0, j0, i1, j1) > 0) break;  // growing j1 only adds inliers
          const int n = block(off, i0, j0, i1, j1);
          const double area = (xc[i1] - xc[i0]) * (yc[j1] - yc[j0]);
          // Ties: the larger block. The frame's inner faces (wall thickness) hold no wall
          // inliers, so their far edges bound a smaller block with the same features; the
          // opening in the wall plane is bounded by the near edges.
          if (n > best || (n == best && n > 0 && area > best_area)) {
            best = n, best_area = area;
            b[0] = i0, b[1] = j0, b[2] = i1, b[3] = j1;
          }
        }
  out.estimate.n_inliers_target = best;
  if (best < p.min_outliers) {
    out.reason = Reason::kNoOpening;
    return out;
  }
  for (size_t k = 0; k < c.size(); ++k)
    if (!wall->inlier[k]) {
      const int i = cell_of(xc, c.u2[k].x()), j = cell_of(yc, c.u2[k].y());
      if (i >= b[0] && i < b[2] && j >= b[1] && j < b[3]) out.labels[k] = Label::kTarget;
    }
  const double left = xc[b[0]], right = xc[b[2]], top = yc[b[1]], bottom = yc[b[3]];
  const Vector2d centre(0.5 * (left + right), 0.5 * (top + bottom));
  auto on_wall = [&](const Vector2d& px) {
    return compute_waypoint(*plane, c.camera->ray(px), c.pose_1, c.pose_2, *c.mount,
                            params.waypoint);
  };
  const auto w_c = on_wall(centre);
  const auto w_l = on_wall({left, centre.y()}), w_r = on_wall({right, centre.y()});
  const auto w_t = on_wall({centre.x(), top}), w_b = on_wall({centre.x(), bottom});
  for (const auto* w : {&w_c, &w_l, &w_r, &w_t, &w_b})
    if (!*w) {
      out.reason = w->reason();
      return out;
    }
  TargetEstimate& e = out.estimate;
  e.p_W = w_c->p_W;
  e.n_W = w_c->n_W;
  e.pixel = centre;
  e.size_m[0] = (w_r->p_W - w_l->p_W).norm();
  e.size_m[1] = (w_b->p_W - w_t->p_W).norm();
  e.outline = {{left, top}, {right, top}, {right, bottom}, {left, bottom}};
  if (e.size_m[0] < p.min_size_m || e.size_m[1] < p.min_size_m) {
    out.reason = Reason::kNoOpening;
    return out;
  }
  out.reason = Reason::kOk;
  return out;
}

}  // namespace alight::vision
