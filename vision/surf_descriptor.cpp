// Paper 3.1.1: upright SURF (Bay et al. 2008) with an optional known rotation; see
// surf_descriptor.hpp.
#include "vision/surf_descriptor.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace alight::vision {
namespace {

/// Gaussian weights (sigma 3.3 s) of the 20 x 20 samples; independent of s in sample units.
const std::array<float, 400>& gaussian_weights() {
  static const std::array<float, 400> w = [] {
    std::array<float, 400> t{};
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 20; ++i) {
        const double u = i - 9.5, v = j - 9.5;
        t[j * 20 + i] = float(std::exp(-(u * u + v * v) / (2 * 3.3 * 3.3)));
      }
    return t;
  }();
  return w;
}

}  // namespace

double surf_scale(const Keypoint& kp, const SurfParams& params) {
  return std::max(params.min_scale, params.scale_per_size * (kp.size + 0.5));
}

cv::Mat describe_surf(const cv::Mat& integral, const std::vector<Keypoint>& keypoints,
                      const SurfParams& params, double pattern_angle_rad) {
  assert(integral.type() == CV_32S);
  cv::Mat desc(int(keypoints.size()), kSurfLength, CV_32F, cv::Scalar(0));
  const int W = integral.cols - 1, H = integral.rows - 1;
  const float c = float(std::cos(pattern_angle_rad)), sn = float(std::sin(pattern_angle_rad));
  const auto& gw = gaussian_weights();
  const int stride = int(integral.step1());
  const int* S = integral.ptr<int>(0);
  // Nearest pixel without a libm call (valid for coordinates > -4096).
  auto round_px = [](float v) { return int(v + 4096.5f) - 4096; };
  for (size_t k = 0; k < keypoints.size(); ++k) {
    const Keypoint& kp = keypoints[k];
    const float s = float(surf_scale(kp, params));
    const int h = std::max(1, int(std::lround(s)));  // Haar wavelet half-size
    float* d = desc.ptr<float>(int(k));
    float acc[16][4] = {};
    // Sample pixels; the pattern is rotated by the known angle (identity when upright).
    int px[400], py[400];
    for (int j = 0; j < 20; ++j) {
      const float v = (float(j) - 9.5f) * s;
      for (int i = 0; i < 20; ++i) {
        const float u = (float(i) - 9.5f) * s;
        px[j * 20 + i] = round_px(kp.x + c * u - sn * v);
        py[j * 20 + i] = round_px(kp.y + sn * u + c * v);
      }
    }
    // Clamping is needed only when the window reaches the border.
    const float reach = 10.f * s * 1.415f + float(h) + 2.f;
    const bool inside = kp.x - reach >= 0 && kp.y - reach >= 0 && kp.x + reach <= float(W) &&
                        kp.y + reach <= float(H);
    for (int q = 0; q < 400; ++q) {
      int xl = px[q] - h, xm = px[q], xr = px[q] + h;
      int yt = py[q] - h, ym = py[q], yb = py[q] + h;
      if (!inside) {  // samples past the border see a truncated wavelet
        xl = std::clamp(xl, 0, W), xm = std::clamp(xm, 0, W), xr = std::clamp(xr, 0, W);
        yt = std::clamp(yt, 0, H), ym = std::clamp(ym, 0, H), yb = std::clamp(yb, 0, H);
      }
      const int* rt = S + yt * stride;
      const int* rm = S + ym * stride;
      const int* rb = S + yb * stride;
      const int right = rb[xr] - rt[xr] - rb[xm] + rt[xm];
      const int left = rb[xm] - rt[xm] - rb[xl] + rt[xl];
      const int bottom = rb[xr] - rm[xr] - rb[xl] + rm[xl];
      const int top = rm[xr] - rt[xr] - rm[xl] + rt[xl];
      const float gx = float(right - left), gy = float(bottom - top);
      const float wt = gw[q];
      const float du = wt * (c * gx + sn * gy);  // wavelet responses in the pattern axes
      const float dv = wt * (-sn * gx + c * gy);
      float* a = acc[((q / 20) / 5) * 4 + (q % 20) / 5];
      a[0] += du, a[1] += dv, a[2] += std::abs(du), a[3] += std::abs(dv);
    }
    double norm2 = 0;
    for (int r = 0; r < 16; ++r)
      for (int q = 0; q < 4; ++q) norm2 += double(acc[r][q]) * acc[r][q];
    const float inv = norm2 > 0 ? float(1.0 / std::sqrt(norm2)) : 0.f;
    for (int r = 0; r < 16; ++r)
      for (int q = 0; q < 4; ++q) d[r * 4 + q] = acc[r][q] * inv;
  }
  return desc;
}

}  // namespace alight::vision
