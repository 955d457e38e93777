// The moving top's RANSAC inlier count (see similarity_inliers.hpp).
#include "vision/landing/similarity_inliers.hpp"

#include <cassert>
#include <cmath>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#endif

namespace alight::vision {

SimilarityCandidates::SimilarityCandidates(const std::vector<Vector2d>& p1,
                                           const std::vector<Vector2d>& p2,
                                           const std::vector<double>& tol_m)
    : size_(p1.size()) {
  assert(p2.size() == p1.size() && tol_m.size() == p1.size());
  const size_t padded = (size_ + 3) / 4 * 4;
  for (auto* v : {&p1x_, &p1y_, &p2x_, &p2y_}) v->assign(padded, 0.0);
  tol_.assign(padded, -1.0);  // a distance is never below -1: padding fits nothing
  for (size_t k = 0; k < size_; ++k) {
    p1x_[k] = p1[k].x(), p1y_[k] = p1[k].y();
    p2x_[k] = p2[k].x(), p2y_[k] = p2[k].y();
    tol_[k] = tol_m[k];
  }
}

namespace {

// Whether candidate k fits S (c, sn: S's rotation), in Similarity2::apply's arithmetic.
bool fits(const Similarity2& S, double c, double sn, const double* p1x, const double* p1y,
          const double* p2x, const double* p2y, const double* tol, size_t k) {
  const double qx = S.s * (c * p1x[k] - sn * p1y[k]) + S.t.x();
  const double qy = S.s * (sn * p1x[k] + c * p1y[k]) + S.t.y();
  const double dx = qx - p2x[k], dy = qy - p2y[k];
  return std::sqrt(dx * dx + dy * dy) <= tol[k];
}

#if defined(__x86_64__) && defined(__GNUC__)
// fits() for candidates k..k+3 (the same operations in the same order): a bit per candidate.
__attribute__((target("avx2"))) int fits4(const Similarity2& S, double c, double sn,
                                          const double* p1x, const double* p1y, const double* p2x,
                                          const double* p2y, const double* tol, size_t k) {
  const __m256d vc = _mm256_set1_pd(c), vs = _mm256_set1_pd(sn), s = _mm256_set1_pd(S.s);
  const __m256d x = _mm256_loadu_pd(p1x + k), y = _mm256_loadu_pd(p1y + k);
  const __m256d qx =
      _mm256_add_pd(_mm256_mul_pd(s, _mm256_sub_pd(_mm256_mul_pd(vc, x), _mm256_mul_pd(vs, y))),
                    _mm256_set1_pd(S.t.x()));
  const __m256d qy =
      _mm256_add_pd(_mm256_mul_pd(s, _mm256_add_pd(_mm256_mul_pd(vs, x), _mm256_mul_pd(vc, y))),
                    _mm256_set1_pd(S.t.y()));
  const __m256d dx = _mm256_sub_pd(qx, _mm256_loadu_pd(p2x + k));
  const __m256d dy = _mm256_sub_pd(qy, _mm256_loadu_pd(p2y + k));
  const __m256d d = _mm256_sqrt_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)));
  return _mm256_movemask_pd(_mm256_cmp_pd(d, _mm256_loadu_pd(tol + k), _CMP_LE_OQ));
}
#endif

}  // namespace

size_t similarity_inliers_scalar(const Similarity2& S, const SimilarityCandidates& L,
                                 std::vector<size_t>* in) {
  const double c = std::cos(S.theta), sn = std::sin(S.theta);
  if (in) in->clear();
  size_t n = 0;
  for (size_t k = 0; k < L.size_; ++k) {
    if (!fits(S, c, sn, L.p1x_.data(), L.p1y_.data(), L.p2x_.data(), L.p2y_.data(), L.tol_.data(),
              k))
      continue;
    ++n;
    if (in) in->push_back(k);
  }
  return n;
}

size_t similarity_inliers(const Similarity2& S, const SimilarityCandidates& L,
                          std::vector<size_t>* in) {
#if defined(__x86_64__) && defined(__GNUC__)
  if (__builtin_cpu_supports("avx2")) {
    const double c = std::cos(S.theta), sn = std::sin(S.theta);
    if (in) in->clear();
    size_t n = 0;
    for (size_t k = 0; k < L.tol_.size(); k += 4) {
      const int bits = fits4(S, c, sn, L.p1x_.data(), L.p1y_.data(), L.p2x_.data(), L.p2y_.data(),
                             L.tol_.data(), k);
      for (int j = 0; j < 4; ++j) {
        if (!(bits >> j & 1)) continue;
        ++n;
        if (in) in->push_back(k + size_t(j));
      }
    }
    return n;
  }
#endif
  return similarity_inliers_scalar(S, L, in);
}

}  // namespace alight::vision
