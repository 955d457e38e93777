#pragma once
// Bilinear grey level of a CV_8UC1 image between its pixels, shared by the plane check
// (plane_photometric.cpp) and the rim search (landing_target.cpp).

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <opencv2/core.hpp>

namespace alight::vision {

/// The caller keeps (x, y) at least one pixel inside the image (0 <= x < cols - 1, likewise y).
inline double bilinear(const cv::Mat& g, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  const uint8_t* r0 = g.ptr<uint8_t>(y0) + x0;
  const uint8_t* r1 = g.ptr<uint8_t>(y0 + 1) + x0;
  return (1 - fy) * ((1 - fx) * r0[0] + fx * r0[1]) + fy * ((1 - fx) * r1[0] + fx * r1[1]);
}

/// As bilinear, false (value untouched) within a pixel of the border or for non-finite u.
inline bool bilinear_inside(const cv::Mat& g, const Eigen::Vector2d& u, double* value) {
  if (!(u.x() >= 0 && u.y() >= 0 && u.x() < g.cols - 1 && u.y() < g.rows - 1)) return false;
  *value = bilinear(g, u.x(), u.y());
  return true;
}

}  // namespace alight::vision
