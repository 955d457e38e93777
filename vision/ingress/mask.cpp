// Ingress stage 2, the off-wall mask (beyond paper 3.3: plane-induced parallax, eq. 2; see
// mask.hpp).
#include "vision/ingress/mask.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/median.hpp"
#include "vision/geometry/pixel_rays.hpp"
#include "vision/geometry/warp_diff.hpp"

namespace alight::vision {
namespace {

// The coarse grid's scale: full u = sx (u_small + 0.5) - 0.5 (pixel centres).
struct Coarse {
  cv::Size small;
  double sx, sy;
};

Coarse coarse_grid(cv::Size size, int d) {
  const cv::Size small((size.width + d - 1) / d, (size.height + d - 1) / d);
  return {small, static_cast<double>(size.width) / small.width,
          static_cast<double>(size.height) / small.height};
}

// |a - b warped| where a distorted camera's rays bend the homography: raw current pixel ->
// undistorted -> H^-1 -> raw reference pixel, exactly on a grid every kStep (coarse) pixels and
// bilinearly between (the map is smooth; undistorting every pixel by iteration would cost
// ~100 ms a frame). A pixel the reference did not see differs by 0: no evidence, counts as wall.
cv::Mat remapped_difference(const cv::Mat& a, const cv::Mat& b, const Coarse& g,
                            const Matrix3d& H_21, const CameraModel& camera, int d) {
  const double sx = g.sx, sy = g.sy;
  const int kStep = std::max(2, 8 / d);
  const Matrix3d K = camera.K(), K_inv = K.inverse(), H_12 = H_21.inverse();
  const int cols = g.small.width, rows = g.small.height;
  const int gw = (cols - 1 + kStep - 1) / kStep + 1, gh = (rows - 1 + kStep - 1) / kStep + 1;
  // At full size the nodes are whole pixels, whose rays are kept (pixel_rays.hpp).
  PixelRays* table = d == 1 ? &pixel_rays(camera) : nullptr;
  std::vector<float> grid_x(gw * gh), grid_y(gw * gh);
  for (int j = 0; j < gh; ++j)
    for (int i = 0; i < gw; ++i) {
      const int us = std::min(i * kStep, cols - 1), vs = std::min(j * kStep, rows - 1);
      const Vector3d r2 = table
                              ? table->at(us, vs)
                              : camera.ray(Vector2d(sx * (us + 0.5) - 0.5, sy * (vs + 0.5) - 0.5));
      const Vector3d r1 = K_inv * (H_12 * (K * r2));
      const auto u1 = r1.z() > 0 ? camera.project(r1) : std::nullopt;
      grid_x[j * gw + i] = u1 ? static_cast<float>((u1->x() + 0.5) / sx - 0.5) : -1e6f;
      grid_y[j * gw + i] = u1 ? static_cast<float>((u1->y() + 0.5) / sy - 0.5) : -1e6f;
    }
  return grid_remap_abs_diff(a, b, grid_x, grid_y, gw, kStep);
}

// Where each current pixel's wall point lies in the reference image, and how much the two
// images differ there (coarse grid).
cv::Mat wall_difference(const cv::Mat& a, const cv::Mat& b, const Coarse& g, const Matrix3d& H_21,
                        const CameraModel& camera, int d) {
  if (camera.has_distortion()) return remapped_difference(a, b, g, H_21, camera, d);
  const double sx = g.sx, sy = g.sy;
  Matrix3d S = Matrix3d::Identity(), S_inv = Matrix3d::Identity();  // full -> small, back
  S(0, 0) = 1 / sx, S(1, 1) = 1 / sy, S(0, 2) = 0.5 / sx - 0.5, S(1, 2) = 0.5 / sy - 0.5;
  S_inv(0, 0) = sx, S_inv(1, 1) = sy, S_inv(0, 2) = 0.5 * sx - 0.5, S_inv(1, 2) = 0.5 * sy - 0.5;
  const Matrix3d H_small = S * H_21 * S_inv;
  return warp_abs_diff(a, b, H_small.inverse());
}

// The threshold follows the difference on the wall itself (noise, lighting, a slightly off
// homography), measured at the wall's inlier features.
double wall_threshold(const cv::Mat& diff, const Coarse& g, const std::vector<Vector2d>& wall_px,
                      const IngressParams& p) {
  std::vector<uint8_t> on_wall;
  for (const auto& px : wall_px) {
    if (!px.allFinite()) continue;
    const double us = (px.x() + 0.5) / g.sx - 0.5, vs = (px.y() + 0.5) / g.sy - 0.5;
    if (!(std::abs(us) < 1e6 && std::abs(vs) < 1e6)) continue;
    const int u = static_cast<int>(std::lround(us)), v = static_cast<int>(std::lround(vs));
    if (u >= 0 && v >= 0 && u < diff.cols && v < diff.rows)
      on_wall.push_back(diff.at<uint8_t>(v, u));
  }
  double threshold = p.parallax_min_diff;
  if (!on_wall.empty()) threshold = std::max(threshold, p.parallax_noise_k * upper_median(on_wall));
  return threshold;
}

// The difference thresholded, closed (fills the holes where the view beyond the wall has little
// texture: two samples of it agree by chance) and opened (removes specks on the wall), both of
// which keep a rectangle's border, then at full size.
cv::Mat cleaned_mask(const cv::Mat& diff, double threshold, cv::Size size, const IngressParams& p) {
  const int d = p.parallax_decimation;
  cv::Mat mask;
  cv::threshold(diff, mask, threshold, 255, cv::THRESH_BINARY);
  // On the coarse grid, the odd size nearest below size / d.
  auto coarse = [d](int size_px) { return d == 1 ? size_px : 2 * (size_px / (2 * d)) + 1; };
  if (p.parallax_close_px > 1 && coarse(p.parallax_close_px) > 1) {
    const int k = coarse(p.parallax_close_px);
    cv::morphologyEx(mask, mask, cv::MORPH_CLOSE,
                     cv::getStructuringElement(cv::MORPH_RECT, {k, k}));
  }
  if (p.parallax_open_px > 1 && coarse(p.parallax_open_px) > 1) {
    const int k = coarse(p.parallax_open_px);
    cv::morphologyEx(mask, mask, cv::MORPH_OPEN, cv::getStructuringElement(cv::MORPH_RECT, {k, k}));
  }
  if (d == 1) return mask;
  // Bilinear up and halfway: the border lies between the coarse pixels' centres.
  cv::Mat full;
  cv::resize(mask, full, size, 0, 0, cv::INTER_LINEAR);
  cv::threshold(full, full, 127, 255, cv::THRESH_BINARY);
  return full;
}

}  // namespace

cv::Mat parallax_image(const cv::Mat& gray, const IngressParams& p) {
  assert(gray.type() == CV_8UC1);
  // The mask can be made on a grid parallax_decimation times coarser and scaled back up: the
  // warp, blurs and morphology at full size are a large share of the vision's time on a busy
  // wall. Its border moves by up to half a coarse pixel; mask_cuts fits lines to it and snaps
  // them to the wall's edge in the full-size image.
  const int d = p.parallax_decimation;
  cv::Mat small;
  if (d > 1)
    cv::resize(gray, small, cv::Size((gray.cols + d - 1) / d, (gray.rows + d - 1) / d), 0, 0,
               cv::INTER_AREA);
  else
    small = gray;
  cv::Mat out;
  if (p.parallax_blur_sigma_px > 0)
    cv::GaussianBlur(small, out, cv::Size(), p.parallax_blur_sigma_px / d);
  else
    out = small.clone();  // never the caller's pixels
  return out;
}

cv::Mat off_wall_mask(const cv::Mat& image, const cv::Mat& reference, const Matrix3d& H_21,
                      const CameraModel& camera, const std::vector<Vector2d>& wall_px,
                      const IngressParams& p) {
  assert(image.size() == reference.size());
  return off_wall_mask_of_parallax_images(parallax_image(image, p), parallax_image(reference, p),
                                          image.size(), H_21, camera, wall_px, p);
}

cv::Mat off_wall_mask_of_parallax_images(const cv::Mat& a, const cv::Mat& b, cv::Size size,
                                         const Matrix3d& H_21, const CameraModel& camera,
                                         const std::vector<Vector2d>& wall_px,
                                         const IngressParams& p, cv::Mat* diff_out) {
  assert(a.type() == CV_8UC1 && b.type() == CV_8UC1);
  const int d = p.parallax_decimation;
  const Coarse g = coarse_grid(size, d);
  assert(a.size() == g.small && b.size() == g.small);
  const cv::Mat diff = wall_difference(a, b, g, H_21, camera, d);
  const double threshold = wall_threshold(diff, g, wall_px, p);
  if (diff_out) *diff_out = diff;
  return cleaned_mask(diff, threshold, size, p);
}

}  // namespace alight::vision
