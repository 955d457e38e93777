// Paper 3.1.1: descriptor matching; see matcher.hpp.
#include "vision/frontend/matcher.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define ALIGHT_MATCHER_AVX2 1
#endif

namespace alight::vision {
namespace {

constexpr float kLowest = -std::numeric_limits<float>::max();

/// dot[j] = sum_k a[k] * bt[k][j] for j < n: the row of a . B^T with B stored transposed.
void dot_row(const float* __restrict a, const float* __restrict bt, int len, int n, int stride,
             float* __restrict dot) {
  for (int j = 0; j < n; ++j) dot[j] = 0.f;
  for (int k = 0; k < len; ++k) {
    const float ak = a[k];
    const float* __restrict b = bt + size_t(k) * stride;
    for (int j = 0; j < n; ++j) dot[j] += ak * b[j];
  }
}

/// Best and second-best (largest dot) of a row, and the running best of each column.
void scan_row(const float* dot, int n, int row, float& best, float& second, int& best_j,
              float* col_best, int* col_arg) {
  best = second = kLowest;
  best_j = -1;
  for (int j = 0; j < n; ++j) {
    const float v = dot[j];
    if (v > best) {
      second = best, best = v, best_j = j;
    } else if (v > second) {
      second = v;
    }
    if (v > col_best[j]) col_best[j] = v, col_arg[j] = row;
  }
}

/// The product of the rows idx1 of d1 with the columns of bt, scanned row by row in order.
struct Scan {
  std::vector<float> col_best, row_best, row_second;
  std::vector<int> col_arg, row_arg;
};

void scan_scalar(const cv::Mat& d1, const std::vector<int>& idx1, const float* bt, int n2,
                 int stride, Scan& s) {
  std::vector<float> dot(stride);
  for (size_t i = 0; i < idx1.size(); ++i) {
    dot_row(d1.ptr<float>(idx1[i]), bt, d1.cols, n2, stride, dot.data());
    scan_row(dot.data(), n2, int(i), s.row_best[i], s.row_second[i], s.row_arg[i],
             s.col_best.data(), s.col_arg.data());
  }
}

#ifdef ALIGHT_MATCHER_AVX2
constexpr int kRows = 4;   // rows of d1 per register tile (the code below names four)
constexpr int kCols = 16;  // columns of bt per register tile (two vectors)

// dot_row and scan_row, four rows at a time, 16 columns at a time: each column vector of bt is
// loaded once for four rows and the sums stay in registers. Every sum is still
// ((0 + a0 b0) + a1 b1) + ... in that order with separate multiply and add (no FMA: this target
// does not enable it), so the products equal dot_row's bit for bit; the scan takes the rows in
// order and keeps, per lane, the first largest and the second largest, so its results equal
// scan_row's too (ties: the lowest column, as the scalar scan's strict comparisons give).
__attribute__((target("avx2"))) void scan_avx2(const cv::Mat& d1, const std::vector<int>& idx1,
                                               const float* bt, int n2, int stride, Scan& s) {
  const int n1 = int(idx1.size()), len = d1.cols;
  const __m256 lowest = _mm256_set1_ps(kLowest);
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  for (int i0 = 0; i0 < n1; i0 += kRows) {
    const int rows = std::min(kRows, n1 - i0);
    const float* a[kRows];
    for (int r = 0; r < kRows; ++r) a[r] = d1.ptr<float>(idx1[i0 + std::min(r, rows - 1)]);
    __m256 best[kRows], second[kRows];
    __m256i arg[kRows];
    for (int r = 0; r < kRows; ++r)
      best[r] = lowest, second[r] = lowest, arg[r] = _mm256_set1_epi32(-1);
    for (int j0 = 0; j0 < stride; j0 += kCols) {
      // Eight named sums (an array indexed below would live on the stack, not in registers).
      __m256 s00 = _mm256_setzero_ps(), s01 = s00, s10 = s00, s11 = s00, s20 = s00, s21 = s00,
             s30 = s00, s31 = s00;
      const float* b = bt + j0;
      for (int k = 0; k < len; ++k, b += stride) {
        const __m256 b0 = _mm256_load_ps(b), b1 = _mm256_load_ps(b + 8);
        const __m256 a0 = _mm256_broadcast_ss(a[0] + k), a1 = _mm256_broadcast_ss(a[1] + k);
        const __m256 a2 = _mm256_broadcast_ss(a[2] + k), a3 = _mm256_broadcast_ss(a[3] + k);
        s00 = _mm256_add_ps(s00, _mm256_mul_ps(a0, b0));
        s01 = _mm256_add_ps(s01, _mm256_mul_ps(a0, b1));
        s10 = _mm256_add_ps(s10, _mm256_mul_ps(a1, b0));
        s11 = _mm256_add_ps(s11, _mm256_mul_ps(a1, b1));
        s20 = _mm256_add_ps(s20, _mm256_mul_ps(a2, b0));
        s21 = _mm256_add_ps(s21, _mm256_mul_ps(a2, b1));
        s30 = _mm256_add_ps(s30, _mm256_mul_ps(a3, b0));
        s31 = _mm256_add_ps(s31, _mm256_mul_ps(a3, b1));
      }
      alignas(32) float dot[kRows][kCols];
      _mm256_store_ps(dot[0], s00), _mm256_store_ps(dot[0] + 8, s01);
      _mm256_store_ps(dot[1], s10), _mm256_store_ps(dot[1] + 8, s11);
      _mm256_store_ps(dot[2], s20), _mm256_store_ps(dot[2] + 8, s21);
      _mm256_store_ps(dot[3], s30), _mm256_store_ps(dot[3] + 8, s31);
      for (int h = 0; h < 2; ++h) {
        const int j = j0 + 8 * h;
        if (j >= n2) break;
        const __m256i jj = _mm256_add_epi32(lane, _mm256_set1_epi32(j));
        // Padding columns (j >= n2) never win.
        const __m256 valid = _mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_set1_epi32(n2), jj));
        __m256 cb = _mm256_loadu_ps(&s.col_best[j]);
        __m256i ca = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(&s.col_arg[j]));
        for (int r = 0; r < rows; ++r) {
          const __m256 v = _mm256_blendv_ps(lowest, _mm256_load_ps(dot[r] + 8 * h), valid);
          const __m256 gt = _mm256_cmp_ps(v, best[r], _CMP_GT_OQ);
          second[r] = _mm256_blendv_ps(_mm256_max_ps(v, second[r]), best[r], gt);
          best[r] = _mm256_blendv_ps(best[r], v, gt);
          arg[r] = _mm256_castps_si256(
              _mm256_blendv_ps(_mm256_castsi256_ps(arg[r]), _mm256_castsi256_ps(jj), gt));
          const __m256 cgt = _mm256_cmp_ps(v, cb, _CMP_GT_OQ);
          cb = _mm256_blendv_ps(cb, v, cgt);
          ca = _mm256_castps_si256(_mm256_blendv_ps(
              _mm256_castsi256_ps(ca), _mm256_castsi256_ps(_mm256_set1_epi32(i0 + r)), cgt));
        }
        // col_best/col_arg have room for whole vectors (sized to stride).
        _mm256_storeu_ps(&s.col_best[j], cb);
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(&s.col_arg[j]), ca);
      }
    }
    // Lanes to row: the largest, at its lowest column; the second largest of what remains.
    for (int r = 0; r < rows; ++r) {
      alignas(32) float lb[8], ls[8];
      alignas(32) int la[8];
      _mm256_store_ps(lb, best[r]);
      _mm256_store_ps(ls, second[r]);
      _mm256_store_si256(reinterpret_cast<__m256i*>(la), arg[r]);
      int w = -1;
      for (int l = 0; l < 8; ++l)
        if (la[l] >= 0 && (w < 0 || lb[l] > lb[w] || (lb[l] == lb[w] && la[l] < la[w]))) w = l;
      float sec = kLowest;
      for (int l = 0; l < 8; ++l) {
        sec = std::max(sec, ls[l]);
        if (l != w) sec = std::max(sec, lb[l]);
      }
      const int i = i0 + r;
      s.row_arg[i] = w < 0 ? -1 : la[w];
      s.row_best[i] = w < 0 ? kLowest : lb[w];
      s.row_second[i] = sec;
    }
  }
}
#endif

float distance_of(float dot) { return std::sqrt(std::max(0.f, 2.f - 2.f * dot)); }

/// Matches rows idx1 of d1 against rows idx2 of d2, appending to out (indices in d1, d2).
void match_group(const cv::Mat& d1, const cv::Mat& d2, const std::vector<int>& idx1,
                 const std::vector<int>& idx2, const MatchParams& params, bool avx2,
                 std::vector<Match>& out) {
  const int n1 = int(idx1.size()), n2 = int(idx2.size()), len = d1.cols;
  if (n1 == 0 || n2 == 0) return;
  const int stride = (n2 + 15) & ~15;
  // 32-byte aligned rows for the vector loads (stride is a multiple of 16 floats). Only the
  // padding columns (j >= n2) are cleared, not the whole block (clearing it cost as much as
  // filling it): they are multiplied but never chosen, and zeros keep stray denormals or NaNs
  // out of the arithmetic.
  const std::unique_ptr<float[]> bt_store(new float[size_t(len) * stride + 8]);
  const size_t shift = (32 - reinterpret_cast<uintptr_t>(bt_store.get()) % 32) % 32 / 4;
  float* bt = bt_store.get() + shift;
  for (int k = 0; k < len; ++k)
    std::fill(bt + size_t(k) * stride + n2, bt + size_t(k + 1) * stride, 0.f);
  for (int j = 0; j < n2; ++j) {
    const float* b = d2.ptr<float>(idx2[j]);
    for (int k = 0; k < len; ++k) bt[size_t(k) * stride + j] = b[k];
  }
  Scan s;
  s.col_best.assign(stride, kLowest);
  s.col_arg.assign(stride, -1);
  s.row_arg.assign(n1, -1);
  s.row_best.assign(n1, 0.f);
  s.row_second.assign(n1, 0.f);
#ifdef ALIGHT_MATCHER_AVX2
  if (avx2) {
    scan_avx2(d1, idx1, bt, n2, stride, s);
  } else {
    scan_scalar(d1, idx1, bt, n2, stride, s);
  }
#else
  (void)avx2;
  scan_scalar(d1, idx1, bt, n2, stride, s);
#endif
  const float max_d = float(params.max_distance), ratio = float(params.ratio);
  for (int i = 0; i < n1; ++i) {
    const int j = s.row_arg[i];
    if (j < 0) continue;
    const float d = distance_of(s.row_best[i]);
    if (d > max_d) continue;
    if (n2 > 1 && d >= ratio * distance_of(s.row_second[i])) continue;
    if (params.mutual && s.col_arg[j] != i) continue;
    out.push_back({idx1[i], idx2[j], d});
  }
}

std::vector<Match> match_impl(const cv::Mat& d1, const cv::Mat& d2, const MatchParams& params,
                              const std::vector<int8_t>* signs1, const std::vector<int8_t>* signs2,
                              bool allow_avx2) {
  std::vector<Match> out;
  if (d1.empty() || d2.empty()) return out;
  assert(d1.type() == CV_32F && d2.type() == CV_32F && d1.cols == d2.cols);
  const bool split = params.same_sign_only && signs1 && signs2;
  assert(!signs1 || int(signs1->size()) == d1.rows);
  assert(!signs2 || int(signs2->size()) == d2.rows);
  bool avx2 = false;
#ifdef ALIGHT_MATCHER_AVX2
  avx2 = allow_avx2 && __builtin_cpu_supports("avx2");
#endif
  (void)allow_avx2;
  for (const int8_t sign : {int8_t(1), int8_t(-1)}) {
    std::vector<int> idx1, idx2;
    for (int i = 0; i < d1.rows; ++i)
      if (!split || (*signs1)[i] == sign) idx1.push_back(i);
    for (int j = 0; j < d2.rows; ++j)
      if (!split || (*signs2)[j] == sign) idx2.push_back(j);
    match_group(d1, d2, idx1, idx2, params, avx2, out);
    if (!split) break;
  }
  return out;
}

}  // namespace

std::vector<int8_t> response_signs(const std::vector<Keypoint>& kps) {
  std::vector<int8_t> s(kps.size());
  for (size_t i = 0; i < kps.size(); ++i) s[i] = kps[i].response >= 0 ? 1 : -1;
  return s;
}

std::vector<Match> match_descriptors(const cv::Mat& d1, const cv::Mat& d2,
                                     const MatchParams& params, const std::vector<int8_t>* signs1,
                                     const std::vector<int8_t>* signs2) {
  return match_impl(d1, d2, params, signs1, signs2, true);
}

std::vector<Match> match_descriptors_scalar(const cv::Mat& d1, const cv::Mat& d2,
                                            const MatchParams& params,
                                            const std::vector<int8_t>* signs1,
                                            const std::vector<int8_t>* signs2) {
  return match_impl(d1, d2, params, signs1, signs2, false);
}

}  // namespace alight::vision
