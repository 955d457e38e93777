// Paper 3.1.1: upright SURF (Bay et al. 2008) with the sub-region layout of MU-SURF (Agrawal,
// Konolige & Blas 2008, sec. 4) and an optional known rotation; see surf_descriptor.hpp.
#include "vision/surf_descriptor.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace alight::vision {
namespace {

constexpr int kGrid = 20;  // samples per side of the 20s x 20s window

/// Per axis, the weight of sample i (0..19) in sub-region r (0..3).
/// Overlapping (MU-SURF): sub-region r spans samples 4r..4r+7 (8s wide, reaching 2s into each
/// neighbour), weighted by a Gaussian of sigma 2.5s about its centre; a sample near a boundary
/// then moves weight gradually from one sub-region to the next instead of jumping, which is what
/// makes the descriptor tolerate the small shifts, rotations and scale errors of a real match.
/// Plain (SURF): sub-region r is samples 5r..5r+4, weight 1 (the window's Gaussian is applied
/// separately, see window_weight).
using AxisWeights = std::array<std::array<float, kGrid>, 4>;

const AxisWeights& axis_weights(bool overlapping) {
  static const auto make = [](bool ov) {
    AxisWeights w{};
    for (int r = 0; r < 4; ++r)
      for (int i = 0; i < kGrid; ++i) {
        if (ov) {
          const double d = i - (4 * r + 3.5);
          w[r][i] = (i >= 4 * r && i < 4 * r + 8) ? float(std::exp(-d * d / (2 * 2.5 * 2.5))) : 0.f;
        } else {
          w[r][i] = (i / 5 == r) ? 1.f : 0.f;
        }
      }
    return w;
  };
  static const AxisWeights overlapping_w = make(true), plain_w = make(false);
  return overlapping ? overlapping_w : plain_w;
}

/// Weight of each of the 20 x 20 samples before they are split into sub-regions.
/// Plain SURF: one Gaussian of sigma 3.3s over the window. MU-SURF: none here (its per-sub-region
/// Gaussians are in axis_weights, and a second Gaussian of sigma 1.5 over the 4 x 4 grid of
/// sub-regions follows in region_weight).
const std::array<float, kGrid * kGrid>& window_weight(bool overlapping) {
  static const auto make = [](bool ov) {
    std::array<float, kGrid * kGrid> t{};
    for (int j = 0; j < kGrid; ++j)
      for (int i = 0; i < kGrid; ++i) {
        const double u = i - 9.5, v = j - 9.5;
        t[j * kGrid + i] = ov ? 1.f : float(std::exp(-(u * u + v * v) / (2 * 3.3 * 3.3)));
      }
    return t;
  };
  static const auto overlapping_w = make(true), plain_w = make(false);
  return overlapping ? overlapping_w : plain_w;
}

float region_weight(bool overlapping, int ru, int rv) {
  if (!overlapping) return 1.f;
  const double u = ru - 1.5, v = rv - 1.5;
  return float(std::exp(-(u * u + v * v) / (2 * 1.5 * 1.5)));
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
  const bool ov = params.overlapping_subregions;
  const AxisWeights& aw = axis_weights(ov);
  const auto& ww = window_weight(ov);
  float rw[4][4];
  for (int rv = 0; rv < 4; ++rv)
    for (int ru = 0; ru < 4; ++ru) rw[rv][ru] = region_weight(ov, ru, rv);
  // Samples [begin, end) of each sub-region along an axis (the others weigh zero).
  int span[4][2];
  for (int r = 0; r < 4; ++r) {
    span[r][0] = ov ? 4 * r : 5 * r;
    span[r][1] = ov ? 4 * r + 8 : 5 * r + 5;
  }
  const int stride = int(integral.step1());
  const int* S = integral.ptr<int>(0);
  // Nearest pixel without a libm call (valid for coordinates > -4096).
  auto round_px = [](float v) { return int(v + 4096.5f) - 4096; };
  for (size_t k = 0; k < keypoints.size(); ++k) {
    const Keypoint& kp = keypoints[k];
    const float s = float(surf_scale(kp, params));
    const int h = std::max(1, int(std::lround(s)));  // Haar wavelet half-size
    float* d = desc.ptr<float>(int(k));
    // Sample pixels; the pattern is rotated by the known angle (identity when upright).
    int px[kGrid * kGrid], py[kGrid * kGrid];
    for (int j = 0; j < kGrid; ++j) {
      const float v = (float(j) - 9.5f) * s;
      for (int i = 0; i < kGrid; ++i) {
        const float u = (float(i) - 9.5f) * s;
        px[j * kGrid + i] = round_px(kp.x + c * u - sn * v);
        py[j * kGrid + i] = round_px(kp.y + sn * u + c * v);
      }
    }
    // Clamping is needed only when the window reaches the border.
    const float reach = 10.f * s * 1.415f + float(h) + 2.f;
    const bool inside = kp.x - reach >= 0 && kp.y - reach >= 0 && kp.x + reach <= float(W) &&
                        kp.y + reach <= float(H);
    // Wavelet responses in the pattern axes, one row of samples at a time, each row reduced at
    // once to its four per-sub-region-column sums (the weights are separable: row x column).
    float row_sum[kGrid][4][4];  // [sample row j][sub-region column ru][dx, dy, |dx|, |dy|]
    for (int j = 0; j < kGrid; ++j) {
      float du[kGrid], dv[kGrid];
      for (int i = 0; i < kGrid; ++i) {
        const int q = j * kGrid + i;
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
        const float wt = ww[q];
        du[i] = wt * (c * gx + sn * gy);
        dv[i] = wt * (-sn * gx + c * gy);
      }
      float adu[kGrid], adv[kGrid];
      for (int i = 0; i < kGrid; ++i) adu[i] = std::abs(du[i]), adv[i] = std::abs(dv[i]);
      for (int ru = 0; ru < 4; ++ru) {
        float a0 = 0.f, a1 = 0.f, a2 = 0.f, a3 = 0.f;
        for (int i = span[ru][0]; i < span[ru][1]; ++i) {
          const float w = aw[ru][i];
          a0 += w * du[i], a1 += w * dv[i], a2 += w * adu[i], a3 += w * adv[i];
        }
        row_sum[j][ru][0] = a0, row_sum[j][ru][1] = a1, row_sum[j][ru][2] = a2;
        row_sum[j][ru][3] = a3;
      }
    }
    double norm2 = 0;
    for (int rv = 0; rv < 4; ++rv)
      for (int ru = 0; ru < 4; ++ru) {
        float a[4] = {0.f, 0.f, 0.f, 0.f};
        for (int j = span[rv][0]; j < span[rv][1]; ++j) {
          const float w = aw[rv][j];
          for (int q = 0; q < 4; ++q) a[q] += w * row_sum[j][ru][q];
        }
        for (int q = 0; q < 4; ++q) {
          const float v = a[q] * rw[rv][ru];
          d[(rv * 4 + ru) * 4 + q] = v;
          norm2 += double(v) * v;
        }
      }
    const float inv = norm2 > 0 ? float(1.0 / std::sqrt(norm2)) : 0.f;
    for (int q = 0; q < kSurfLength; ++q) d[q] *= inv;
  }
  return desc;
}

}  // namespace alight::vision
