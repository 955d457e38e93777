// Dense photometric check of a platform top (see plane_photometric.hpp).
#include "vision/geometry/plane_photometric.hpp"

#include <algorithm>
#include <cmath>

#include "vision/geometry/bilinear.hpp"
#include "vision/geometry/pixel_rays.hpp"

namespace alight::vision {

std::optional<PlanePhotometry> plane_photometry(
    const cv::Mat& gray_1, const cv::Mat& gray_2, const CameraModel& camera,
    const Matrix3d& H_floor_px, const Matrix3d& H_top_px, const std::vector<cv::Point>& pixels_u2,
    int min_pixels, const EpochPixelGrid* grid_1, const Readout* readout_2) {
  if (gray_1.empty() || gray_2.empty()) return std::nullopt;
  const bool rolling_2 = readout_2 && readout_2->rolling();
  const Matrix3d K = camera.K(), K_inv = K.inverse();
  const Matrix3d Hf_inv = H_floor_px.inverse(), Ht_inv = H_top_px.inverse();
  constexpr int kSteps = 13;  // gamma -1 .. 2
  constexpr double kStep = 0.25;
  auto gamma_of = [](int k) { return -1.0 + kStep * k; };
  // Sums for each gamma's normalised cross-correlation, in one pass over the pixels.
  double s_b = 0, s_bb = 0, s_a[kSteps] = {}, s_aa[kSteps] = {}, s_ab[kSteps] = {};
  int n = 0;
  // A pixel's reference position at gamma 0 and 1; between and beyond, along the straight line
  // through them (the lens bends it by a negligible amount over a parallax of a few pixels).
  const double x_max = gray_1.cols - 1, y_max = gray_1.rows - 1;
  // A lens's rays are kept per pixel (pixel_rays.hpp); without one a ray is two divisions.
  PixelRays* rays = camera.has_distortion() ? &pixel_rays(camera) : nullptr;
  for (const cv::Point& q : pixels_u2) {
    if (q.x < 0 || q.y < 0 || q.x >= gray_2.cols || q.y >= gray_2.rows) continue;
    const Vector3d x2 = K * (rolling_2 ? ray_at_epoch(camera, Vector2d(q.x, q.y), *readout_2)
                             : rays    ? rays->at(q.x, q.y)
                                       : camera.ray(Vector2d(q.x, q.y)));
    const Vector3d a = Hf_inv * x2, b = Ht_inv * x2;
    if (!(a.z() > 0 && b.z() > 0)) continue;
    const auto u_floor = grid_1 ? grid_1->pixel(K_inv * a) : camera.project(K_inv * a);
    const auto u_top = grid_1 ? grid_1->pixel(K_inv * b) : camera.project(K_inv * b);
    if (!u_floor || !u_top) continue;
    const Vector2d step = *u_top - *u_floor;
    const Vector2d lo = *u_floor + gamma_of(0) * step, hi = *u_floor + gamma_of(kSteps - 1) * step;
    // Out of the reference at some gamma: left out at every gamma, so all compare one set.
    if (!(std::min(lo.x(), hi.x()) >= 0 && std::min(lo.y(), hi.y()) >= 0 &&
          std::max(lo.x(), hi.x()) < x_max && std::max(lo.y(), hi.y()) < y_max))
      continue;
    const double v2 = gray_2.at<uint8_t>(q.y, q.x);
    s_b += v2, s_bb += v2 * v2, ++n;
    for (int k = 0; k < kSteps; ++k) {
      const Vector2d u1 = lo + (kStep * k) * step;
      const double v1 = bilinear(gray_1, u1.x(), u1.y());
      s_a[k] += v1, s_aa[k] += v1 * v1, s_ab[k] += v1 * v2;
    }
  }
  if (n < std::max(min_pixels, 2)) return std::nullopt;
  PlanePhotometry out;
  out.n = n;
  double c[kSteps];
  int best = 0;
  const double var_b = s_bb - s_b * s_b / n;
  for (int k = 0; k < kSteps; ++k) {
    const double var_a = s_aa[k] - s_a[k] * s_a[k] / n, cov = s_ab[k] - s_a[k] * s_b / n;
    c[k] = var_a > 0 && var_b > 0 ? cov / std::sqrt(var_a * var_b) : 0.0;
    if (c[k] > c[best]) best = k;
  }
  out.ncc_best = c[best];
  double frac = 0;
  out.sigma_gamma = 1e9;  // at the grid's end, or flat: no information
  if (best > 0 && best < kSteps - 1) {
    const double den = c[best - 1] - 2 * c[best] + c[best + 1];
    if (den < 0) {
      frac = 0.5 * (c[best - 1] - c[best + 1]) / den;
      // 1 - ncc ~ (1 - ncc*) + curv (gamma - gamma*)^2; var(gamma*) = (1 - ncc*) / (n_eff curv)
      const double curv = -den / (2 * kStep * kStep);
      const double n_eff = out.n / 4.0;
      out.sigma_gamma = std::sqrt(std::max(1e-6, 1 - c[best]) / (n_eff * curv));
    }
  }
  out.gamma = gamma_of(best) + kStep * frac;
  return out;
}

}  // namespace alight::vision
