// Paper 3.1.1: sub-pixel STAR (CenSurE, Agrawal et al. 2008); see star_detector.hpp.
#include "vision/frontend/star_detector.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "vision/simd.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define ALIGHT_STAR_AVX2 1
#endif

namespace alight::vision {
namespace {

/// One row of the response at filter index n, mean(inner (2n+1)^2) - mean(ring), merged into
/// best_abs: per pixel the largest |response| over the scales seen so far (computed and merged
/// in one loop, without a row of responses in between).
ALIGHT_MULTIVERSION
void merge_response_row(const int* __restrict o0, const int* __restrict o1,
                        const int* __restrict i0, const int* __restrict i1, int n, int x_begin,
                        int x_end, float* __restrict best_abs) {
  const int a = n, b = 2 * n;
  const float in_area = float((2 * a + 1) * (2 * a + 1));
  const float out_area = float((2 * b + 1) * (2 * b + 1));
  const float w_in = 1.f / in_area + 1.f / (out_area - in_area);
  const float w_out = 1.f / (out_area - in_area);
  for (int x = x_begin; x < x_end; ++x) {
    const int inner = i1[x + a + 1] - i1[x - a] - i0[x + a + 1] + i0[x - a];
    const int outer = o1[x + b + 1] - o1[x - b] - o0[x + b + 1] + o0[x - b];
    const float r = w_in * float(inner) - w_out * float(outer);
    best_abs[x] = std::max(best_abs[x], std::abs(r));
  }
}

/// Quadratic peak offset from three samples, clamped to half a sample.
float parabola_offset(float m, float c, float p) {
  const float d2 = m - 2 * c + p;
  if (!(std::abs(d2) > 1e-12f)) return 0.f;
  return std::clamp(0.5f * (m - p) / d2, -0.5f, 0.5f);
}

}  // namespace

cv::Mat integral_image(const cv::Mat& gray) {
  cv::Mat sum;
  cv::integral(gray, sum, CV_32S);
  return sum;
}

namespace {

/// Appends the x in [x_begin, x_end) with v[x] >= d[x] and v[x] > threshold, in order.
void peaks_row_scalar(const float* v, const float* d, int x_begin, int x_end, float threshold,
                      int y, std::vector<cv::Point>& out) {
  for (int x = x_begin; x < x_end; ++x)
    if (v[x] >= d[x] && v[x] > threshold) out.emplace_back(x, y);
}

#ifdef ALIGHT_STAR_AVX2
// peaks_row_scalar eight pixels at a time: the same two comparisons (ordered, so NaN is never
// a peak, as with cv::compare), the few survivors collected from the bit mask in order.
__attribute__((target("avx2"))) void peaks_row_avx2(const float* v, const float* d, int x_begin,
                                                    int x_end, float threshold, int y,
                                                    std::vector<cv::Point>& out) {
  const __m256 thr = _mm256_set1_ps(threshold);
  int x = x_begin;
  for (; x + 8 <= x_end; x += 8) {
    const __m256 a = _mm256_loadu_ps(v + x);
    const __m256 m = _mm256_and_ps(_mm256_cmp_ps(a, _mm256_loadu_ps(d + x), _CMP_GE_OQ),
                                   _mm256_cmp_ps(a, thr, _CMP_GT_OQ));
    for (unsigned bits = unsigned(_mm256_movemask_ps(m)); bits != 0; bits &= bits - 1)
      out.emplace_back(x + __builtin_ctz(bits), y);
  }
  peaks_row_scalar(v, d, x, x_end, threshold, y, out);
}
#endif

}  // namespace

std::vector<cv::Point> star_peaks(const cv::Mat& best_abs, const cv::Mat& dilated,
                                  const cv::Rect& inner, float threshold, bool allow_avx2) {
  assert(best_abs.type() == CV_32F && dilated.type() == CV_32F);
  assert(best_abs.size() == dilated.size());
  const cv::Rect r = inner & cv::Rect(0, 0, best_abs.cols, best_abs.rows);
  bool avx2 = false;
#ifdef ALIGHT_STAR_AVX2
  avx2 = allow_avx2 && __builtin_cpu_supports("avx2");
#endif
  (void)allow_avx2;
  std::vector<cv::Point> out;
  for (int y = r.y; y < r.y + r.height; ++y) {
    const float* v = best_abs.ptr<float>(y);
    const float* d = dilated.ptr<float>(y);
#ifdef ALIGHT_STAR_AVX2
    if (avx2) {
      peaks_row_avx2(v, d, r.x, r.x + r.width, threshold, y, out);
      continue;
    }
#endif
    peaks_row_scalar(v, d, r.x, r.x + r.width, threshold, y, out);
  }
  return out;
}

float star_response(const cv::Mat& integral, int x, int y, int n) {
  const int a = n, b = 2 * n;
  auto box = [&](int h) {
    return integral.at<int>(y + h + 1, x + h + 1) - integral.at<int>(y - h, x + h + 1) -
           integral.at<int>(y + h + 1, x - h) + integral.at<int>(y - h, x - h);
  };
  const float in_area = float((2 * a + 1) * (2 * a + 1));
  const float out_area = float((2 * b + 1) * (2 * b + 1));
  const int inner = box(a), outer = box(b);
  return float(inner) / in_area - float(outer - inner) / (out_area - in_area);
}

Result<std::vector<Keypoint>> detect_star(const cv::Mat& gray, const cv::Mat& integral,
                                          const StarParams& params) {
  using R = Result<std::vector<Keypoint>>;
  const int margin = 2 * params.max_size + 2;  // outer box + one pixel for the 3x3 refinement
  if (gray.empty() || gray.type() != CV_8UC1 || integral.type() != CV_32S ||
      integral.rows != gray.rows + 1 || integral.cols != gray.cols + 1 ||
      gray.cols < 2 * margin + 3 || gray.rows < 2 * margin + 3)
    return R::fail(Reason::kBadImage);
  const int w = gray.cols, h = gray.rows;
  const int x0 = margin, x1 = w - margin, y0 = margin, y1 = h - margin;

  // Non-maximum suppression over scale: each pixel keeps its largest |response|.
  cv::Mat best_abs(h, w, CV_32F, cv::Scalar(0));
  for (int y = y0; y < y1; ++y) {
    float* ba = best_abs.ptr<float>(y);
    for (int n = params.min_size; n <= params.max_size; ++n)
      merge_response_row(integral.ptr<int>(y - 2 * n), integral.ptr<int>(y + 2 * n + 1),
                         integral.ptr<int>(y - n), integral.ptr<int>(y + n + 1), n, x0, x1, ba);
  }

  // Over space: peaks of |response| in a (2r+1)^2 window, above the threshold.
  cv::Mat dilated;
  const int k = 2 * params.nms_radius_px + 1;
  cv::dilate(best_abs, dilated, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)));
  const float thr = float(params.response_threshold);
  // (Both comparisons in one vectorised pass, then the few survivors are collected.)
  const cv::Rect inner(x0 + 1, y0 + 1, x1 - x0 - 2, y1 - y0 - 2);
  std::vector<cv::Point> where = star_peaks(best_abs, dilated, inner, thr);
  std::vector<Keypoint> peaks;
  peaks.reserve(where.size());
  for (const cv::Point& q : where)
    peaks.push_back({float(q.x), float(q.y), 0.f, best_abs.at<float>(q.y, q.x)});
  // Strongest first; the line test runs only until max_features peaks have passed it.
  std::sort(peaks.begin(), peaks.end(),
            [](const Keypoint& a, const Keypoint& b) { return a.response > b.response; });
  const double r = params.line_threshold;
  const double max_ratio = (r + 1) * (r + 1) / r;  // Harris: reject tr^2 / det > (r + 1)^2 / r
  // Spread (params.grid_*): the first pass keeps at most `cap` per cell, the second fills up
  // with the strongest peaks the first pass left.
  const bool grid = params.grid_cols > 0 && params.max_features > 0;
  const int cells = grid ? params.grid_cols * params.grid_rows : 1;
  const int cap = grid ? std::max(1, params.max_features / cells) : 0;
  std::vector<int> per_cell(cells, 0);
  std::vector<uint8_t> taken(grid ? peaks.size() : 0, 0);
  std::vector<Keypoint> kps;
  for (int pass = grid ? 0 : 1; pass < 2; ++pass)
    for (size_t pi = 0; pi < peaks.size(); ++pi) {
      const Keypoint& p = peaks[pi];
      if (params.max_features > 0 && int(kps.size()) >= params.max_features) break;
      int cell = 0;
      if (grid) {
        if (taken[pi]) continue;
        cell = std::min(params.grid_cols - 1, int(p.x) * params.grid_cols / w) +
               params.grid_cols * std::min(params.grid_rows - 1, int(p.y) * params.grid_rows / h);
        if (pass == 0 && per_cell[cell] >= cap) continue;
        taken[pi] = 1;  // tested once: kept, or rejected as a line
      }
      const int x = int(p.x), y = int(p.y);
      // The scale of the peak and its signed response.
      int n_best = params.min_size;
      float r_best = 0.f;
      for (int n = params.min_size; n <= params.max_size; ++n) {
        const float v = star_response(integral, x, y, n);
        if (std::abs(v) > std::abs(r_best)) r_best = v, n_best = n;
      }
      // Second-moment matrix of |response| around the peak, over a window of the blob size.
      const int rad = std::max(2, n_best + 1);
      double sxx = 0, syy = 0, sxy = 0;
      for (int v = std::max(y0 + 1, y - rad); v <= std::min(y1 - 2, y + rad); ++v) {
        const float* br = best_abs.ptr<float>(v);
        const float* bu = best_abs.ptr<float>(v - 1);
        const float* bd = best_abs.ptr<float>(v + 1);
        for (int u = std::max(x0 + 1, x - rad); u <= std::min(x1 - 2, x + rad); ++u) {
          const double gx = 0.5 * (br[u + 1] - br[u - 1]);
          const double gy = 0.5 * (bd[u] - bu[u]);
          sxx += gx * gx, syy += gy * gy, sxy += gx * gy;
        }
      }
      const double det = sxx * syy - sxy * sxy;
      if (!(det > 0) || (sxx + syy) * (sxx + syy) > max_ratio * det) continue;
      kps.push_back({p.x, p.y, float(n_best), r_best});
      ++per_cell[cell];
    }
  if (grid)  // strongest first, as without the grid
    std::sort(kps.begin(), kps.end(), [](const Keypoint& a, const Keypoint& b) {
      return std::abs(a.response) > std::abs(b.response);
    });
  if (kps.size() < 4) return R::fail(Reason::kTooFewFeatures);
  if (params.subpixel) {
    for (auto& kp : kps) {
      const int x = int(kp.x), y = int(kp.y), n = int(kp.size);
      float f[3][3];
      for (int j = -1; j <= 1; ++j)
        for (int i = -1; i <= 1; ++i) f[j + 1][i + 1] = star_response(integral, x + i, y + j, n);
      // Newton step on the 2-D quadratic through the 3x3 neighbourhood.
      const double gx = 0.5 * (f[1][2] - f[1][0]), gy = 0.5 * (f[2][1] - f[0][1]);
      const double hxx = f[1][2] - 2 * f[1][1] + f[1][0];
      const double hyy = f[2][1] - 2 * f[1][1] + f[0][1];
      const double hxy = 0.25 * (f[2][2] - f[2][0] - f[0][2] + f[0][0]);
      const double det = hxx * hyy - hxy * hxy;
      if (std::abs(det) > 1e-12) {
        const double dx = -(hyy * gx - hxy * gy) / det;
        const double dy = -(hxx * gy - hxy * gx) / det;
        if (std::abs(dx) <= 1.0 && std::abs(dy) <= 1.0) {
          kp.x += float(std::clamp(dx, -0.5, 0.5));
          kp.y += float(std::clamp(dy, -0.5, 0.5));
        } else {  // not a clean peak: fall back to the separable 1-D fits
          kp.x += parabola_offset(f[1][0], f[1][1], f[1][2]);
          kp.y += parabola_offset(f[0][1], f[1][1], f[2][1]);
        }
      }
      if (n > params.min_size && n < params.max_size)
        kp.size +=
            parabola_offset(std::abs(star_response(integral, x, y, n - 1)), std::abs(f[1][1]),
                            std::abs(star_response(integral, x, y, n + 1)));
    }
  }
  return R::ok(std::move(kps));
}

}  // namespace alight::vision
