// Plane-induced parallax as an image; see warp_diff.hpp.
#include "vision/geometry/warp_diff.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstring>
#include <opencv2/imgproc.hpp>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define ALIGHT_WARP_DIFF_AVX2 1
#endif

namespace alight::vision {
namespace {

constexpr int kBits = 8;          // fractional bits of a reference coordinate
constexpr int kOne = 1 << kBits;  // one pixel
constexpr int kKnot = 16;         // exact coordinates every kKnot pixels along a row
constexpr int kKnotBits = 4;
static_assert(1 << kKnotBits == kKnot);
constexpr double kFar = 4096.0;  // |coordinate| beyond this [px]: not seen (keeps int32 exact)

struct Images {
  const uint8_t* image_row;  // the current row of the image
  const uint8_t* ref;        // the reference's first pixel
  size_t ref_step;           // bytes
  int cols, rows;            // the reference's size
};

// H_12 (u, v) in fixed point; false when behind the camera or farther than kFar.
inline bool exact_at(const double* h, double u, double v, int32_t* x, int32_t* y) {
  const double w = h[6] * u + h[7] * v + h[8];
  const double sx = (h[0] * u + h[1] * v + h[2]) / w, sy = (h[3] * u + h[4] * v + h[5]) / w;
  const bool ok = w > 0 && std::abs(sx) < kFar && std::abs(sy) < kFar;
  *x = ok ? static_cast<int32_t>(std::floor(sx * kOne + 0.5)) : static_cast<int32_t>(-kFar * kOne);
  *y = ok ? static_cast<int32_t>(std::floor(sy * kOne + 0.5)) : static_cast<int32_t>(-kFar * kOne);
  return ok;
}

// The coordinate j pixels past a knot at x0, the next knot dx further.
inline int32_t between(int32_t x0, int32_t dx, int j) {
  return x0 + ((dx * j + kKnot / 2) >> kKnotBits);
}

// One pixel: the difference at reference coordinate (x, y) (fixed point).
inline uint8_t diff_at(const Images& m, int32_t x, int32_t y, int u) {
  const int cols = m.cols, rows = m.rows;
  const bool seen =
      x >= -kOne / 2 && x < cols * kOne - kOne / 2 && y >= -kOne / 2 && y < rows * kOne - kOne / 2;
  const int cx = std::clamp(x, 0, (cols - 1) * kOne), cy = std::clamp(y, 0, (rows - 1) * kOne);
  const int x0 = std::min(cx >> kBits, cols - 2), y0 = std::min(cy >> kBits, rows - 2);
  const int fx = cx - (x0 << kBits), fy = cy - (y0 << kBits);
  const uint8_t* p = m.ref + static_cast<size_t>(y0) * m.ref_step + x0;
  const int top = (p[0] << kBits) + fx * (p[1] - p[0]);
  const int bottom = (p[m.ref_step] << kBits) + fx * (p[m.ref_step + 1] - p[m.ref_step]);
  const int value = ((top << kBits) + fy * (bottom - top) + (1 << (2 * kBits - 1))) >> (2 * kBits);
  const int d = m.image_row[u] - value;
  return seen ? static_cast<uint8_t>(d < 0 ? -d : d) : 0;
}

// The pixels [u0, u0 + n) of row v between knots (x0, y0) and (x1, y1), or exactly at each
// pixel where a knot was not ok.
inline void segment_scalar(const Images& m, const double* h, int v, int u0, int n, bool ok,
                           int32_t x0, int32_t y0, int32_t x1, int32_t y1, uint8_t* out) {
  for (int j = 0; j < n; ++j) {
    int32_t x, y;
    if (ok)
      x = between(x0, x1 - x0, j), y = between(y0, y1 - y0, j);
    else
      exact_at(h, u0 + j, v, &x, &y);
    out[u0 + j] = diff_at(m, x, y, u0 + j);
  }
}

void row_scalar(const Images& m, const double* h, int v, int cols, uint8_t* out) {
  int32_t x0, y0, x1, y1;
  bool ok0 = exact_at(h, 0, v, &x0, &y0);
  for (int u0 = 0; u0 < cols; u0 += kKnot) {
    const bool ok1 = exact_at(h, u0 + kKnot, v, &x1, &y1);
    segment_scalar(m, h, v, u0, std::min(kKnot, cols - u0), ok0 && ok1, x0, y0, x1, y1, out);
    x0 = x1, y0 = y1, ok0 = ok1;
  }
}

#ifdef ALIGHT_WARP_DIFF_AVX2
// row_scalar's arithmetic, eight pixels at a time; the four reference pixels of each come from
// two 32-bit gathers (a pixel and its right neighbour in the low bytes).
__attribute__((target("avx2"))) void row_avx2(const Images& m, const double* h, int v, int cols,
                                              uint8_t* out) {
  const __m256i below = _mm256_set1_epi32(-kOne / 2 - 1);
  const __m256i x_end = _mm256_set1_epi32(m.cols * kOne - kOne / 2);
  const __m256i y_end = _mm256_set1_epi32(m.rows * kOne - kOne / 2);
  const __m256i zero = _mm256_setzero_si256();
  const __m256i x_max = _mm256_set1_epi32((m.cols - 1) * kOne);
  const __m256i y_max = _mm256_set1_epi32((m.rows - 1) * kOne);
  const __m256i x0_max = _mm256_set1_epi32(m.cols - 2), y0_max = _mm256_set1_epi32(m.rows - 2);
  const __m256i step = _mm256_set1_epi32(static_cast<int>(m.ref_step));
  // A 32-bit read at byte i stays inside the reference when i <= last.
  const __m256i last = _mm256_set1_epi32(static_cast<int>((m.rows - 1) * m.ref_step) + m.cols - 4);
  const __m256i byte = _mm256_set1_epi32(0xff);
  const __m256i round = _mm256_set1_epi32(1 << (2 * kBits - 1));
  const __m256i knot_round = _mm256_set1_epi32(kKnot / 2);
  const __m256i j_first = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i j_second = _mm256_setr_epi32(8, 9, 10, 11, 12, 13, 14, 15);
  static_assert(kKnot == 16);
  int32_t x0, y0, x1, y1;
  bool ok0 = exact_at(h, 0, v, &x0, &y0);
  for (int u0 = 0; u0 < cols; u0 += kKnot) {
    const bool ok1 = exact_at(h, u0 + kKnot, v, &x1, &y1);
    const int n = std::min(kKnot, cols - u0);
    if (!(ok0 && ok1) || n < kKnot) {
      segment_scalar(m, h, v, u0, n, ok0 && ok1, x0, y0, x1, y1, out);
      x0 = x1, y0 = y1, ok0 = ok1;
      continue;
    }
    const __m256i vx0 = _mm256_set1_epi32(x0), vdx = _mm256_set1_epi32(x1 - x0);
    const __m256i vy0 = _mm256_set1_epi32(y0), vdy = _mm256_set1_epi32(y1 - y0);
    for (int half = 0; half < 2; ++half) {
      const int u = u0 + 8 * half;
      const __m256i j = half ? j_second : j_first;
      const __m256i x = _mm256_add_epi32(
          vx0,
          _mm256_srai_epi32(_mm256_add_epi32(_mm256_mullo_epi32(vdx, j), knot_round), kKnotBits));
      const __m256i y = _mm256_add_epi32(
          vy0,
          _mm256_srai_epi32(_mm256_add_epi32(_mm256_mullo_epi32(vdy, j), knot_round), kKnotBits));
      const __m256i seen = _mm256_and_si256(
          _mm256_and_si256(_mm256_cmpgt_epi32(x, below), _mm256_cmpgt_epi32(x_end, x)),
          _mm256_and_si256(_mm256_cmpgt_epi32(y, below), _mm256_cmpgt_epi32(y_end, y)));
      const __m256i cx = _mm256_min_epi32(_mm256_max_epi32(x, zero), x_max);
      const __m256i cy = _mm256_min_epi32(_mm256_max_epi32(y, zero), y_max);
      const __m256i xi = _mm256_min_epi32(_mm256_srai_epi32(cx, kBits), x0_max);
      const __m256i yi = _mm256_min_epi32(_mm256_srai_epi32(cy, kBits), y0_max);
      const __m256i fx = _mm256_sub_epi32(cx, _mm256_slli_epi32(xi, kBits));
      const __m256i fy = _mm256_sub_epi32(cy, _mm256_slli_epi32(yi, kBits));
      const __m256i i0 = _mm256_add_epi32(_mm256_mullo_epi32(yi, step), xi);
      const __m256i i1 = _mm256_add_epi32(i0, step);
      if (_mm256_movemask_epi8(_mm256_cmpgt_epi32(i1, last))) {
        // Next to the reference's last pixel: the 32-bit reads would run past it.
        for (int k = 0; k < 8; ++k)
          out[u + k] = diff_at(m, between(x0, x1 - x0, 8 * half + k),
                               between(y0, y1 - y0, 8 * half + k), u + k);
        continue;
      }
      const auto* base = reinterpret_cast<const int*>(m.ref);
      const __m256i g0 = _mm256_i32gather_epi32(base, i0, 1);
      const __m256i g1 = _mm256_i32gather_epi32(base, i1, 1);
      const __m256i p00 = _mm256_and_si256(g0, byte);
      const __m256i p01 = _mm256_and_si256(_mm256_srli_epi32(g0, 8), byte);
      const __m256i p10 = _mm256_and_si256(g1, byte);
      const __m256i p11 = _mm256_and_si256(_mm256_srli_epi32(g1, 8), byte);
      const __m256i top = _mm256_add_epi32(_mm256_slli_epi32(p00, kBits),
                                           _mm256_mullo_epi32(fx, _mm256_sub_epi32(p01, p00)));
      const __m256i bottom = _mm256_add_epi32(_mm256_slli_epi32(p10, kBits),
                                              _mm256_mullo_epi32(fx, _mm256_sub_epi32(p11, p10)));
      const __m256i value = _mm256_srai_epi32(
          _mm256_add_epi32(_mm256_add_epi32(_mm256_slli_epi32(top, kBits),
                                            _mm256_mullo_epi32(fy, _mm256_sub_epi32(bottom, top))),
                           round),
          2 * kBits);
      const __m256i a =
          _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(m.image_row + u)));
      const __m256i d = _mm256_and_si256(_mm256_abs_epi32(_mm256_sub_epi32(a, value)), seen);
      const __m256i words = _mm256_packus_epi32(d, d);  // [d0..3 d0..3 | d4..7 d4..7]
      const __m256i bytes = _mm256_packus_epi16(words, words);
      const uint32_t first = static_cast<uint32_t>(_mm256_extract_epi32(bytes, 0));
      const uint32_t second = static_cast<uint32_t>(_mm256_extract_epi32(bytes, 4));
      std::memcpy(out + u, &first, 4);
      std::memcpy(out + u + 4, &second, 4);
    }
    x0 = x1, y0 = y1, ok0 = ok1;
  }
}
#endif

cv::Mat warp_abs_diff_impl(const cv::Mat& image, const cv::Mat& reference, const Matrix3d& H_12,
                           bool allow_avx2) {
  assert(image.type() == CV_8UC1 && reference.type() == CV_8UC1);
  assert(reference.cols >= 2 && reference.rows >= 2);
  cv::Mat out(image.size(), CV_8UC1);
  double h[9];
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) h[3 * r + k] = H_12(r, k);
  Images m{nullptr, reference.ptr<uint8_t>(0), reference.step[0], reference.cols, reference.rows};
  bool avx2 = false;
#ifdef ALIGHT_WARP_DIFF_AVX2
  avx2 = allow_avx2 && __builtin_cpu_supports("avx2");
#endif
  (void)allow_avx2;
  for (int v = 0; v < image.rows; ++v) {
    m.image_row = image.ptr<uint8_t>(v);
#ifdef ALIGHT_WARP_DIFF_AVX2
    if (avx2) {
      row_avx2(m, h, v, image.cols, out.ptr<uint8_t>(v));
      continue;
    }
#endif
    row_scalar(m, h, v, image.cols, out.ptr<uint8_t>(v));
  }
  return out;
}

// Where each node's place along its row or column of the grid falls for a pixel: the node
// before it and the weight of the node after (bilinear between nodes).
struct Run {
  int node, begin, end;  // the pixels [begin, end) lie between node and node + 1
};
struct Lerp {
  std::vector<int> node;
  std::vector<float> frac;
  std::vector<Run> runs;
};

Lerp lerp_of(int n, int step, int nodes) {
  Lerp l{std::vector<int>(n), std::vector<float>(n), {}};
  for (int u = 0; u < n; ++u) {
    const int i = std::min(u / step, nodes - 2);
    const float x0 = i * step, x1 = std::min((i + 1) * step, n - 1);
    l.node[u] = i;
    l.frac[u] = (u - x0) / (x1 - x0);
    if (l.runs.empty() || l.runs.back().node != i) l.runs.push_back({i, u, u});
    l.runs.back().end = u + 1;
  }
  return l;
}

// Bilinear between the four nodes a0, b0 (this row of nodes) and a1, b1 (the next) for n pixels
// at fractions fx across, fy down: the nodes are constant over the run, so the loop has no gather
// and the geometry library's -O3 vectorises it.
void lerp_run(float fy, float a0, float b0, float a1, float b1, const float* fx, int n,
              float* out) {
  for (int u = 0; u < n; ++u)
    out[u] = (1 - fy) * ((1 - fx[u]) * a0 + fx[u] * b0) + fy * ((1 - fx[u]) * a1 + fx[u] * b1);
}

}  // namespace

cv::Mat grid_remap_abs_diff(const cv::Mat& image, const cv::Mat& reference,
                            const std::vector<float>& node_x, const std::vector<float>& node_y,
                            int nodes_across, int step) {
  assert(image.type() == CV_8UC1 && reference.type() == CV_8UC1);
  assert(reference.cols >= 2 && reference.rows >= 2 && image.cols >= 2 && image.rows >= 2);
  assert(step >= 1 && node_x.size() == node_y.size());
  const int cols = image.cols, rows = image.rows, gw = nodes_across;
  const int gh = static_cast<int>(node_x.size()) / gw;
  assert(gw == (cols - 1 + step - 1) / step + 1 && gh == (rows - 1 + step - 1) / step + 1);
  const Lerp across = lerp_of(cols, step, gw), down = lerp_of(rows, step, gh);
  // seen: where the reference holds the pixel nearest the map's point, as cv::remap's nearest
  // neighbour rounds it (to the nearest, ties to even: -0.5 is pixel 0, cols - 0.5 is pixel
  // cols when cols is even); NaN is not seen.
  const float hi_x = reference.cols - 0.5f, hi_y = reference.rows - 0.5f;
  const bool tie_x_in = (reference.cols - 1) % 2 == 0, tie_y_in = (reference.rows - 1) % 2 == 0;
  cv::Mat map_x(image.size(), CV_32FC1), map_y(image.size(), CV_32FC1);
  cv::Mat seen(image.size(), CV_8UC1);
  for (int v = 0; v < rows; ++v) {
    const int j = down.node[v];
    const float fy = down.frac[v];
    const float *x0 = &node_x[j * gw], *x1 = x0 + gw, *y0 = &node_y[j * gw], *y1 = y0 + gw;
    float* mx = map_x.ptr<float>(v);
    float* my = map_y.ptr<float>(v);
    for (const auto& [i, u0, u1] : across.runs)
      lerp_run(fy, x0[i], x0[i + 1], x1[i], x1[i + 1], &across.frac[u0], u1 - u0, mx + u0);
    for (const auto& [i, u0, u1] : across.runs)
      lerp_run(fy, y0[i], y0[i + 1], y1[i], y1[i + 1], &across.frac[u0], u1 - u0, my + u0);
    uint8_t* s = seen.ptr<uint8_t>(v);
    // Bitwise, not short-circuit: the loop has no branch and is vectorised.
    for (int u = 0; u < cols; ++u) {
      const bool in_x = (mx[u] >= -0.5f) & ((mx[u] < hi_x) | (tie_x_in & (mx[u] == hi_x)));
      const bool in_y = (my[u] >= -0.5f) & ((my[u] < hi_y) | (tie_y_in & (my[u] == hi_y)));
      s[u] = static_cast<uint8_t>(-static_cast<int>(in_x & in_y));
    }
  }
  cv::Mat warped, diff;
  cv::remap(reference, warped, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  cv::absdiff(image, warped, diff);
  cv::bitwise_and(diff, seen, diff);
  return diff;
}

cv::Mat warp_abs_diff(const cv::Mat& image, const cv::Mat& reference, const Matrix3d& H_12) {
  return warp_abs_diff_impl(image, reference, H_12, true);
}

cv::Mat warp_abs_diff_scalar(const cv::Mat& image, const cv::Mat& reference, const Matrix3d& H_12) {
  return warp_abs_diff_impl(image, reference, H_12, false);
}

}  // namespace alight::vision
