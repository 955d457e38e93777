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

namespace alight::vision::testing {

/// Two views of a textured floor with a textured box top (a platform) above it: camera 1 looks
/// down at the floor from d_floor_m, the platform top is a rectangle of the first image at
/// distance d_top_m; camera 2 is moved by (R_21, t_12_m). Each plane is warped by its own
/// homography (side faces and occlusion by the box are ignored: the box is seen from above).
struct TwoPlaneScene {
  cv::Mat image_1, image_2;
  Matrix3d K, H_floor, H_top;  ///< pixel homographies image 1 -> image 2
  cv::Rect top_in_1;           ///< platform top in image 1
  Matrix3d R_21;
  Vector3d t_12_m, n_1;  ///< n_1: unit normal (camera to plane), shared by both planes
  double d_floor_m = 0, d_top_m = 0;
};

inline TwoPlaneScene two_plane_scene(uint64_t seed, const Matrix3d& R_21, const Vector3d& t_12_m,
                                     double d_floor_m = 1.5, double d_top_m = 1.2,
                                     cv::Rect top = cv::Rect(250, 170, 150, 120)) {
  TwoPlaneScene s;
  s.K << 666.667, 0, 319.5, 0, 666.667, 239.5, 0, 0, 1;
  s.R_21 = R_21, s.t_12_m = t_12_m, s.n_1 = Vector3d::UnitZ();
  s.d_floor_m = d_floor_m, s.d_top_m = d_top_m, s.top_in_1 = top;
  auto H_of = [&](double d) {
    return Matrix3d(s.K * R_21 * (Matrix3d::Identity() - t_12_m * s.n_1.transpose() / d) *
                    s.K.inverse());
  };
  s.H_floor = H_of(d_floor_m);
  s.H_top = H_of(d_top_m);
  const cv::Mat floor_tex = procedural_photo(640, 480, seed);
  const cv::Mat top_tex = procedural_photo(640, 480, seed + 1000);
  s.image_1 = floor_tex.clone();
  top_tex(top).copyTo(s.image_1(top));
  cv::Mat floor_2, top_2, mask_2;
  cv::warpPerspective(floor_tex, floor_2, to_cv(s.H_floor), cv::Size(640, 480), cv::INTER_LINEAR,
                      cv::BORDER_REFLECT101);
  cv::Mat top_only(480, 640, CV_8U, cv::Scalar(0)), mask(480, 640, CV_8U, cv::Scalar(0));
  top_tex(top).copyTo(top_only(top));
  mask(top).setTo(255);
  cv::warpPerspective(top_only, top_2, to_cv(s.H_top), cv::Size(640, 480));
  cv::warpPerspective(mask, mask_2, to_cv(s.H_top), cv::Size(640, 480), cv::INTER_NEAREST);
  s.image_2 = floor_2;
  top_2.copyTo(s.image_2, mask_2);
  return s;
}

}  // namespace alight::vision::testing
