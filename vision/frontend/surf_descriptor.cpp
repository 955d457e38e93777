// Paper 3.1.1: upright SURF (Bay et al. 2008) with the sub-region layout of MU-SURF (Agrawal,
// Konolige & Blas 2008, sec. 4) and an optional known rotation; see surf_descriptor.hpp.
#include "vision/frontend/surf_descriptor.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define ALIGHT_SURF_AVX2 1
#endif

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

namespace {

/// What every keypoint of one call shares.
struct Pattern {
  const int* S;  // integral image
  int stride, W, H;
  float c, sn;  // pattern rotation
  const AxisWeights* aw;
  const std::array<float, kGrid * kGrid>* ww;
  float rw[4][4];
  int span[4][2];  // samples [begin, end) of each sub-region along an axis (others weigh 0)
};

/// Sub-region sums of the weighted responses to the unit descriptor (shared by both variants:
/// row_sum[j][ru] = per sample row j and sub-region column ru, (dx, dy, |dx|, |dy|)).
void finish(const Pattern& p, const float (*row_sum)[4][4], float* d) {
  const AxisWeights& aw = *p.aw;
  double norm2 = 0;
  for (int rv = 0; rv < 4; ++rv)
    for (int ru = 0; ru < 4; ++ru) {
      float a[4] = {0.f, 0.f, 0.f, 0.f};
      for (int j = p.span[rv][0]; j < p.span[rv][1]; ++j) {
        const float w = aw[rv][j];
        for (int q = 0; q < 4; ++q) a[q] += w * row_sum[j][ru][q];
      }
      for (int q = 0; q < 4; ++q) {
        const float v = a[q] * p.rw[rv][ru];
        d[(rv * 4 + ru) * 4 + q] = v;
        norm2 += double(v) * v;
      }
    }
  const float inv = norm2 > 0 ? float(1.0 / std::sqrt(norm2)) : 0.f;
  for (int q = 0; q < kSurfLength; ++q) d[q] *= inv;
}

// Nearest pixel without a libm call (valid for coordinates > -4096).
int round_px(float v) { return int(v + 4096.5f) - 4096; }

/// Whether every wavelet of the window, under any rotation, lies inside the image: then no
/// position needs clamping.
bool window_inside(const Pattern& p, const Keypoint& kp, float s, int h) {
  const float reach = 10.f * s * 1.415f + float(h) + 2.f;
  return kp.x - reach >= 0 && kp.y - reach >= 0 && kp.x + reach <= float(p.W) &&
         kp.y + reach <= float(p.H);
}

void describe_scalar(const Pattern& p, const Keypoint& kp, float s, int h, float* d) {
  const int W = p.W, H = p.H, stride = p.stride;
  const int* S = p.S;
  const float c = p.c, sn = p.sn;
  const AxisWeights& aw = *p.aw;
  const auto& ww = *p.ww;
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
  const bool inside = window_inside(p, kp, s, h);
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
      for (int i = p.span[ru][0]; i < p.span[ru][1]; ++i) {
        const float w = aw[ru][i];
        a0 += w * du[i], a1 += w * dv[i], a2 += w * adu[i], a3 += w * adv[i];
      }
      row_sum[j][ru][0] = a0, row_sum[j][ru][1] = a1, row_sum[j][ru][2] = a2;
      row_sum[j][ru][3] = a3;
    }
  }
  finish(p, row_sum, d);
}

#ifdef ALIGHT_SURF_AVX2
constexpr int kLanes = 24;  // a row of 20 samples as three vectors of 8 (the last 4 unused)

// finish's arithmetic with the sub-regions' spans as constants and the four sums of a
// sub-region as one vector; the norm is summed in finish's order.
template <bool kOverlapping>
__attribute__((target("avx2"))) void finish_avx2(const Pattern& p, const float (*row_sum)[4][4],
                                                 float* d) {
  constexpr int kSpanStep = kOverlapping ? 4 : 5, kSpanLength = kOverlapping ? 8 : 5;
  const AxisWeights& aw = *p.aw;
  for (int rv = 0; rv < 4; ++rv)
    for (int ru = 0; ru < 4; ++ru) {
      __m128 a = _mm_setzero_ps();
      for (int t = 0; t < kSpanLength; ++t) {
        const int j = kSpanStep * rv + t;
        a = _mm_add_ps(a, _mm_mul_ps(_mm_set1_ps(aw[rv][j]), _mm_loadu_ps(row_sum[j][ru])));
      }
      _mm_storeu_ps(d + (rv * 4 + ru) * 4, _mm_mul_ps(a, _mm_set1_ps(p.rw[rv][ru])));
    }
  double norm2 = 0;
  for (int q = 0; q < kSurfLength; ++q) norm2 += double(d[q]) * d[q];
  const __m256 inv = _mm256_set1_ps(norm2 > 0 ? float(1.0 / std::sqrt(norm2)) : 0.f);
  for (int q = 0; q < kSurfLength; q += 8)
    _mm256_storeu_ps(d + q, _mm256_mul_ps(_mm256_loadu_ps(d + q), inv));
}

// describe_scalar's arithmetic, eight samples at a time: the same float operations in the same
// order, multiplies and adds kept apart (this target does not enable FMA), the same integers,
// so the result equals describe_scalar's bit for bit.
template <bool kOverlapping>
__attribute__((target("avx2"))) void describe_avx2(const Pattern& p, const Keypoint& kp, float s,
                                                   int h, float* d) {
  // The sub-regions' spans as constants, so that their sums unroll.
  constexpr int kSpanStep = kOverlapping ? 4 : 5, kSpanLength = kOverlapping ? 8 : 5;
  const AxisWeights& aw = *p.aw;
  const auto& ww = *p.ww;
  const __m256 vc = _mm256_set1_ps(p.c), vsn = _mm256_set1_ps(p.sn);
  const __m256 vnsn = _mm256_set1_ps(-p.sn);
  const __m256 vs = _mm256_set1_ps(s), kx = _mm256_set1_ps(kp.x), ky = _mm256_set1_ps(kp.y);
  const __m256 half_grid = _mm256_set1_ps(9.5f), bias = _mm256_set1_ps(4096.5f);
  const __m256i unbias = _mm256_set1_epi32(4096), vh = _mm256_set1_epi32(h);
  const __m256i vstride = _mm256_set1_epi32(p.stride);
  const __m256 sign = _mm256_set1_ps(-0.f);
  // Per lane block, the column offsets u = (i - 9.5) s.
  __m256 u[3];
  for (int b = 0; b < 3; ++b) {
    const __m256 fi = _mm256_cvtepi32_ps(
        _mm256_add_epi32(_mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7), _mm256_set1_epi32(8 * b)));
    u[b] = _mm256_mul_ps(_mm256_sub_ps(fi, half_grid), vs);
  }
  static const std::array<float, kGrid* kLanes> padded_ww = [&ww] {
    std::array<float, kGrid * kLanes> t{};
    for (int j = 0; j < kGrid; ++j)
      for (int i = 0; i < kGrid; ++i) t[j * kLanes + i] = ww[j * kGrid + i];
    return t;
  }();
  alignas(32) int corner[kLanes], gxi[kLanes] = {}, gyi[kLanes] = {};
  alignas(32) int cxl[kLanes], cxm[kLanes], cxr[kLanes], cyt[kLanes], cym[kLanes], cyb[kLanes];
  const bool inside = window_inside(p, kp, s, h);
  const __m256i zero = _mm256_setzero_si256();
  const __m256i vW = _mm256_set1_epi32(p.W), vH = _mm256_set1_epi32(p.H);
  const __m256i first_four = _mm256_setr_epi32(-1, -1, -1, -1, 0, 0, 0, 0);
  const int h2 = 2 * h, hs = h * p.stride, hs2 = 2 * hs;
  alignas(16) float quad[kLanes][4];  // per sample: dx, dy, |dx|, |dy|
  float row_sum[kGrid][4][4];
  for (int j = 0; j < kGrid; ++j) {
    const __m256 v = _mm256_set1_ps((float(j) - 9.5f) * s);
    bool clamped = false;
    for (int b = 0; b < 3; ++b) {
      const __m256i px = _mm256_sub_epi32(
          _mm256_cvttps_epi32(_mm256_add_ps(
              _mm256_sub_ps(_mm256_add_ps(kx, _mm256_mul_ps(vc, u[b])), _mm256_mul_ps(vsn, v)),
              bias)),
          unbias);
      const __m256i py = _mm256_sub_epi32(
          _mm256_cvttps_epi32(_mm256_add_ps(
              _mm256_add_ps(_mm256_add_ps(ky, _mm256_mul_ps(vsn, u[b])), _mm256_mul_ps(vc, v)),
              bias)),
          unbias);
      // The wavelet's top-left corner, used when no sample of the row needs clamping.
      _mm256_store_si256(reinterpret_cast<__m256i*>(corner + 8 * b),
                         _mm256_add_epi32(_mm256_mullo_epi32(_mm256_sub_epi32(py, vh), vstride),
                                          _mm256_sub_epi32(px, vh)));
      if (inside) continue;
      // Near the border: the scalar variant's clamped positions (clamping a position inside
      // the image changes nothing, so only rows that reach past it take the slower reads).
      const __m256i xl = _mm256_sub_epi32(px, vh), xr = _mm256_add_epi32(px, vh);
      const __m256i yt = _mm256_sub_epi32(py, vh), yb = _mm256_add_epi32(py, vh);
      __m256i out = _mm256_or_si256(
          _mm256_or_si256(_mm256_cmpgt_epi32(zero, xl), _mm256_cmpgt_epi32(xr, vW)),
          _mm256_or_si256(_mm256_cmpgt_epi32(zero, yt), _mm256_cmpgt_epi32(yb, vH)));
      if (b == 2) out = _mm256_and_si256(out, first_four);  // lanes 20-23 are no samples
      clamped = clamped || !_mm256_testz_si256(out, out);
      _mm256_store_si256(reinterpret_cast<__m256i*>(cxl + 8 * b),
                         _mm256_min_epi32(_mm256_max_epi32(xl, zero), vW));
      _mm256_store_si256(reinterpret_cast<__m256i*>(cxm + 8 * b),
                         _mm256_min_epi32(_mm256_max_epi32(px, zero), vW));
      _mm256_store_si256(reinterpret_cast<__m256i*>(cxr + 8 * b),
                         _mm256_min_epi32(_mm256_max_epi32(xr, zero), vW));
      _mm256_store_si256(
          reinterpret_cast<__m256i*>(cyt + 8 * b),
          _mm256_mullo_epi32(_mm256_min_epi32(_mm256_max_epi32(yt, zero), vH), vstride));
      _mm256_store_si256(
          reinterpret_cast<__m256i*>(cym + 8 * b),
          _mm256_mullo_epi32(_mm256_min_epi32(_mm256_max_epi32(py, zero), vH), vstride));
      _mm256_store_si256(
          reinterpret_cast<__m256i*>(cyb + 8 * b),
          _mm256_mullo_epi32(_mm256_min_epi32(_mm256_max_epi32(yb, zero), vH), vstride));
    }
    if (clamped) {
      for (int i = 0; i < kGrid; ++i) {
        const int* rt = p.S + cyt[i];
        const int* rm = p.S + cym[i];
        const int* rb = p.S + cyb[i];
        const int xl = cxl[i], xm = cxm[i], xr = cxr[i];
        const int right = rb[xr] - rt[xr] - rb[xm] + rt[xm];
        const int left = rb[xm] - rt[xm] - rb[xl] + rt[xl];
        const int bottom = rb[xr] - rm[xr] - rb[xl] + rm[xl];
        const int top = rm[xr] - rt[xr] - rm[xl] + rt[xl];
        gxi[i] = right - left, gyi[i] = bottom - top;
      }
    } else {
      // Eight reads per sample at fixed distances from its corner: plain loads (a gather of eight
      // is slower than eight loads on the CPUs measured). right - left and bottom - top, exact in
      // 32-bit integers as the scalar sums (an integral image of 8-bit pixels stays below 2^31).
      for (int i = 0; i < kGrid; ++i) {
        const int* q = p.S + corner[i];
        const int t_l = q[0], t_m = q[h], t_r = q[h2];
        const int m_l = q[hs], m_r = q[hs + h2];
        const int b_l = q[hs2], b_m = q[hs2 + h], b_r = q[hs2 + h2];
        gxi[i] = (b_r - t_r) - 2 * (b_m - t_m) + (b_l - t_l);
        gyi[i] = (b_r - b_l) + (t_r - t_l) - 2 * (m_r - m_l);
      }
    }
    for (int b = 0; b < 3; ++b) {
      const __m256 gx =
          _mm256_cvtepi32_ps(_mm256_load_si256(reinterpret_cast<const __m256i*>(gxi + 8 * b)));
      const __m256 gy =
          _mm256_cvtepi32_ps(_mm256_load_si256(reinterpret_cast<const __m256i*>(gyi + 8 * b)));
      __m256 du = _mm256_add_ps(_mm256_mul_ps(vc, gx), _mm256_mul_ps(vsn, gy));
      __m256 dv = _mm256_add_ps(_mm256_mul_ps(vnsn, gx), _mm256_mul_ps(vc, gy));
      if constexpr (!kOverlapping) {  // the overlapping layout's window weight is 1
        const __m256 wt = _mm256_loadu_ps(padded_ww.data() + j * kLanes + 8 * b);
        du = _mm256_mul_ps(wt, du), dv = _mm256_mul_ps(wt, dv);
      }
      const __m256 adu = _mm256_andnot_ps(sign, du), adv = _mm256_andnot_ps(sign, dv);
      // Transpose to one (dx, dy, |dx|, |dy|) quad per sample.
      const __m256 t0 = _mm256_unpacklo_ps(du, dv), t1 = _mm256_unpackhi_ps(du, dv);
      const __m256 t2 = _mm256_unpacklo_ps(adu, adv), t3 = _mm256_unpackhi_ps(adu, adv);
      const __m256 q0 = _mm256_shuffle_ps(t0, t2, 0x44), q1 = _mm256_shuffle_ps(t0, t2, 0xee);
      const __m256 q2 = _mm256_shuffle_ps(t1, t3, 0x44), q3 = _mm256_shuffle_ps(t1, t3, 0xee);
      float(*qb)[4] = quad + 8 * b;
      _mm_store_ps(qb[0], _mm256_castps256_ps128(q0));
      _mm_store_ps(qb[1], _mm256_castps256_ps128(q1));
      _mm_store_ps(qb[2], _mm256_castps256_ps128(q2));
      _mm_store_ps(qb[3], _mm256_castps256_ps128(q3));
      _mm_store_ps(qb[4], _mm256_extractf128_ps(q0, 1));
      _mm_store_ps(qb[5], _mm256_extractf128_ps(q1, 1));
      _mm_store_ps(qb[6], _mm256_extractf128_ps(q2, 1));
      _mm_store_ps(qb[7], _mm256_extractf128_ps(q3, 1));
    }
    for (int ru = 0; ru < 4; ++ru) {
      __m128 a = _mm_setzero_ps();
      for (int t = 0; t < kSpanLength; ++t) {
        const int i = kSpanStep * ru + t;
        a = _mm_add_ps(a, _mm_mul_ps(_mm_set1_ps(aw[ru][i]), _mm_load_ps(quad[i])));
      }
      _mm_storeu_ps(row_sum[j][ru], a);
    }
  }
  finish_avx2<kOverlapping>(p, row_sum, d);
}
#endif

cv::Mat describe_impl(const cv::Mat& integral, const std::vector<Keypoint>& keypoints,
                      const SurfParams& params, double pattern_angle_rad, bool allow_avx2) {
  assert(integral.type() == CV_32S);
  cv::Mat desc(int(keypoints.size()), kSurfLength, CV_32F, cv::Scalar(0));
  Pattern p;
  p.S = integral.ptr<int>(0);
  p.stride = int(integral.step1());
  p.W = integral.cols - 1, p.H = integral.rows - 1;
  p.c = float(std::cos(pattern_angle_rad)), p.sn = float(std::sin(pattern_angle_rad));
  const bool ov = params.overlapping_subregions;
  p.aw = &axis_weights(ov);
  p.ww = &window_weight(ov);
  for (int rv = 0; rv < 4; ++rv)
    for (int ru = 0; ru < 4; ++ru) p.rw[rv][ru] = region_weight(ov, ru, rv);
  for (int r = 0; r < 4; ++r) {
    p.span[r][0] = ov ? 4 * r : 5 * r;
    p.span[r][1] = ov ? 4 * r + 8 : 5 * r + 5;
  }
  bool avx2 = false;
#ifdef ALIGHT_SURF_AVX2
  // The offsets are 32-bit.
  avx2 = allow_avx2 && __builtin_cpu_supports("avx2") &&
         double(integral.rows) * double(p.stride) < 2e9;
#endif
  (void)allow_avx2;
  // Described top to bottom: neighbouring windows share the integral image's rows, which then
  // are still in the cache (the order of the rows in the output stays that of the keypoints).
  std::vector<int> order(keypoints.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = int(k);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return keypoints[a].y < keypoints[b].y; });
  for (const int k : order) {
    const Keypoint& kp = keypoints[k];
    const float s = float(surf_scale(kp, params));
    const int h = std::max(1, int(std::lround(s)));  // Haar wavelet half-size
    float* d = desc.ptr<float>(k);
#ifdef ALIGHT_SURF_AVX2
    if (avx2) {
      if (ov)
        describe_avx2<true>(p, kp, s, h, d);
      else
        describe_avx2<false>(p, kp, s, h, d);
      continue;
    }
#endif
    describe_scalar(p, kp, s, h, d);
  }
  return desc;
}

}  // namespace

cv::Mat describe_surf(const cv::Mat& integral, const std::vector<Keypoint>& keypoints,
                      const SurfParams& params, double pattern_angle_rad) {
  return describe_impl(integral, keypoints, params, pattern_angle_rad, true);
}

cv::Mat describe_surf_scalar(const cv::Mat& integral, const std::vector<Keypoint>& keypoints,
                             const SurfParams& params, double pattern_angle_rad) {
  return describe_impl(integral, keypoints, params, pattern_angle_rad, false);
}

}  // namespace alight::vision
