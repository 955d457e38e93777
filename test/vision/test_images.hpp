#pragma once
// Photo-like test images: no photographs ship with the machine's OpenCV (no *.jpg under an
// opencv folder), so a seeded procedural texture stands in: multi-octave value noise (ground
// texture) under random blobs, discs, boxes and lines of many sizes and contrasts (gravel,
// stones, markings), lightly blurred like a lens. Views are produced by warping it with known
// homographies (cv::warpPerspective), so the true homography between two views is known.

#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <random>

#include "common/geometry.hpp"

namespace alight::vision::testing {

inline cv::Mat procedural_photo(int width, int height, uint64_t seed) {
  std::mt19937_64 rng(seed);
  cv::Mat acc(height, width, CV_32F, cv::Scalar(0));
  double amplitude = 60.0;
  for (int cell = 64; cell >= 2; cell /= 2) {
    cv::Mat small(height / cell + 2, width / cell + 2, CV_32F);
    std::normal_distribution<float> g(0.f, 1.f);
    for (int r = 0; r < small.rows; ++r)
      for (int c = 0; c < small.cols; ++c) small.at<float>(r, c) = g(rng);
    cv::Mat big;
    cv::resize(small, big, cv::Size(small.cols * cell, small.rows * cell), 0, 0, cv::INTER_CUBIC);
    acc += amplitude * big(cv::Rect(0, 0, width, height));
    amplitude *= 0.6;
  }
  acc += 128.0;
  std::uniform_real_distribution<double> ux(0, width), uy(0, height), grey(20, 235), u01(0, 1);
  const int n_shapes = width * height / 600;
  for (int i = 0; i < n_shapes; ++i) {
    const cv::Point c(int(ux(rng)), int(uy(rng)));
    const double g = grey(rng);
    const int r = 2 + int(14 * std::pow(u01(rng), 2.0));
    const double kind = u01(rng);
    if (kind < 0.55) {
      cv::circle(acc, c, r, cv::Scalar(g), cv::FILLED, cv::LINE_AA);
    } else if (kind < 0.8) {
      cv::ellipse(acc, c, cv::Size(r, std::max(1, r / 2)), 360 * u01(rng), 0, 360, cv::Scalar(g),
                  cv::FILLED, cv::LINE_AA);
    } else if (kind < 0.95) {
      cv::rectangle(acc, cv::Rect(c.x, c.y, r, r + int(6 * u01(rng))), cv::Scalar(g), cv::FILLED);
    } else {
      cv::line(acc, c, c + cv::Point(int(40 * (u01(rng) - 0.5)), int(40 * (u01(rng) - 0.5))),
               cv::Scalar(g), 1 + int(2 * u01(rng)), cv::LINE_AA);
    }
  }
  cv::GaussianBlur(acc, acc, cv::Size(0, 0), 0.8);
  cv::Mat out;
  acc.convertTo(out, CV_8U);
  return out;
}

inline cv::Mat to_cv(const Matrix3d& H) {
  cv::Mat m(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m.at<double>(r, c) = H(r, c);
  return m;
}

inline Matrix3d from_cv(const cv::Mat& m) {
  Matrix3d H;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) H(r, c) = m.at<double>(r, c);
  return H;
}

/// A 640x480 view of `source` through H_view (view pixel = H_view * source pixel).
inline cv::Mat view_of(const cv::Mat& source, const Matrix3d& H_view, double blur_sigma = 0.0,
                       double noise_sigma = 0.0, uint64_t seed = 0) {
  cv::Mat out;
  cv::warpPerspective(source, out, to_cv(H_view), cv::Size(640, 480), cv::INTER_LINEAR,
                      cv::BORDER_REFLECT101);
  if (blur_sigma > 0) cv::GaussianBlur(out, out, cv::Size(0, 0), blur_sigma);
  if (noise_sigma > 0) {
    cv::Mat noise(out.size(), CV_16S);
    cv::RNG rng(seed);
    rng.fill(noise, cv::RNG::NORMAL, 0, noise_sigma);
    cv::Mat o16;
    out.convertTo(o16, CV_16S);
    o16 += noise;
    o16.convertTo(out, CV_8U);
  }
  return out;
}

/// Homography that rotates by angle about the image centre, scales, shifts and tilts, mapping a
/// (w x h) source centred view into a 640x480 view.
inline Matrix3d view_homography(double src_w, double src_h, double angle_rad, double scale,
                                double shift_x, double shift_y, double tilt_x, double tilt_y) {
  Matrix3d to_centre, from_centre, R, P;
  to_centre << 1, 0, -src_w / 2, 0, 1, -src_h / 2, 0, 0, 1;
  from_centre << 1, 0, 320 + shift_x, 0, 1, 240 + shift_y, 0, 0, 1;
  R << scale * std::cos(angle_rad), -scale * std::sin(angle_rad), 0,  //
      scale * std::sin(angle_rad), scale * std::cos(angle_rad), 0, 0, 0, 1;
  P << 1, 0, 0, 0, 1, 0, tilt_x, tilt_y, 1;
  return from_centre * P * R * to_centre;
}

}  // namespace alight::vision::testing
