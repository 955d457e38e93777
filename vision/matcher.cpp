// Paper 3.1.1: descriptor matching; see matcher.hpp.
#include "vision/matcher.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "vision/simd.hpp"

namespace alight::vision {
namespace {

/// dot[j] = sum_k a[k] * bt[k][j] for j < n: the row of a . B^T with B stored transposed.
ALIGHT_MULTIVERSION
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
  best = second = -std::numeric_limits<float>::max();
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

float distance_of(float dot) { return std::sqrt(std::max(0.f, 2.f - 2.f * dot)); }

/// Matches rows idx1 of d1 against rows idx2 of d2, appending to out (indices in d1, d2).
void match_group(const cv::Mat& d1, const cv::Mat& d2, const std::vector<int>& idx1,
                 const std::vector<int>& idx2, const MatchParams& params, std::vector<Match>& out) {
  const int n1 = int(idx1.size()), n2 = int(idx2.size()), len = d1.cols;
  if (n1 == 0 || n2 == 0) return;
  const int stride = (n2 + 7) & ~7;
  std::vector<float> bt(size_t(len) * stride, 0.f);
  for (int j = 0; j < n2; ++j) {
    const float* b = d2.ptr<float>(idx2[j]);
    for (int k = 0; k < len; ++k) bt[size_t(k) * stride + j] = b[k];
  }
  std::vector<float> dot(stride), col_best(n2, -std::numeric_limits<float>::max());
  std::vector<int> col_arg(n2, -1), row_arg(n1, -1);
  std::vector<float> row_best(n1), row_second(n1);
  for (int i = 0; i < n1; ++i) {
    dot_row(d1.ptr<float>(idx1[i]), bt.data(), len, n2, stride, dot.data());
    scan_row(dot.data(), n2, i, row_best[i], row_second[i], row_arg[i], col_best.data(),
             col_arg.data());
  }
  const float max_d = float(params.max_distance), ratio = float(params.ratio);
  for (int i = 0; i < n1; ++i) {
    const int j = row_arg[i];
    if (j < 0) continue;
    const float d = distance_of(row_best[i]);
    if (d > max_d) continue;
    if (n2 > 1 && d >= ratio * distance_of(row_second[i])) continue;
    if (params.mutual && col_arg[j] != i) continue;
    out.push_back({idx1[i], idx2[j], d});
  }
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
  std::vector<Match> out;
  if (d1.empty() || d2.empty()) return out;
  assert(d1.type() == CV_32F && d2.type() == CV_32F && d1.cols == d2.cols);
  const bool split = params.same_sign_only && signs1 && signs2;
  assert(!signs1 || int(signs1->size()) == d1.rows);
  assert(!signs2 || int(signs2->size()) == d2.rows);
  for (const int8_t sign : {int8_t(1), int8_t(-1)}) {
    std::vector<int> idx1, idx2;
    for (int i = 0; i < d1.rows; ++i)
      if (!split || (*signs1)[i] == sign) idx1.push_back(i);
    for (int j = 0; j < d2.rows; ++j)
      if (!split || (*signs2)[j] == sign) idx2.push_back(j);
    match_group(d1, d2, idx1, idx2, params, out);
    if (!split) break;
  }
  return out;
}

}  // namespace alight::vision
