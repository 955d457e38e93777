// The known floor's per-match verdict (beyond paper 3.2, eq. 2 with the metric t12 of eq. 3); see
// floor_classify.hpp.
#include "vision/geometry/floor_classify.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define ALIGHT_CLASSIFY_AVX2 1
#endif

namespace alight::vision {
namespace {

// One match in the scalar loop's arithmetic (plane_carry and plane_residual).
void classify_one(const Vector3d& x1, const Vector3d& x2, const Matrix3d& R, const Vector3d& t,
                  const Vector3d& Rt, const Vector3d& n, double rho_floor, double f, double thr,
                  PerMatch* m) {
  Vector2d r;
  if (plane_residual(plane_carry(R, t, n, rho_floor, x1), x2, f, &r)) m->err_floor = r.norm();
  const Vector3d a = R * x1, b = Rt * n.dot(x1);
  const double u = x2.x(), v = x2.y();
  const Vector2d c(b.x() - u * b.z(), b.y() - v * b.z());
  const Vector2d e(a.x() - u * a.z(), a.y() - v * a.z());
  const double cc = c.squaredNorm();
  if (!(cc > 1e-18)) return;
  m->rho = c.dot(e) / cc;
  const Vector3d p = a - m->rho * b;
  if (!plane_residual(p, x2, f, &r)) return;
  m->err_rho = r.norm();
  // |d pixel / d rho| = f |c| / p_z: the rho step that moves the match by the rest of the
  // threshold.
  const double slack = std::sqrt(std::max(0.0, thr * thr - m->err_rho * m->err_rho));
  m->half_width = slack * p.z() / (f * std::sqrt(cc));
}

#ifdef ALIGHT_CLASSIFY_AVX2
// Four lanes of doubles; every operation below is the scalar loop's, in its order.
struct V3 {
  __m256d x, y, z;
};

__attribute__((target("avx2"))) inline __m256d lanes(const std::vector<Vector3d>& v, size_t i,
                                                     int k) {
  return _mm256_setr_pd(v[i][k], v[i + 1][k], v[i + 2][k], v[i + 3][k]);
}

// M w as Eigen's fixed-size product sums it (column-major): rows 0 and 1 as a packet of two,
// (M_k0 w0 + M_k1 w1) + M_k2 w2; row 2 by its unrolled reduction, M_20 w0 + (M_21 w1 + M_22 w2).
__attribute__((target("avx2"))) inline __m256d term(const Matrix3d& M, int k, int j, __m256d w) {
  return _mm256_mul_pd(_mm256_set1_pd(M(k, j)), w);
}

__attribute__((target("avx2"))) inline V3 times(const Matrix3d& M, const V3& w) {
  return {_mm256_add_pd(_mm256_add_pd(term(M, 0, 0, w.x), term(M, 0, 1, w.y)), term(M, 0, 2, w.z)),
          _mm256_add_pd(_mm256_add_pd(term(M, 1, 0, w.x), term(M, 1, 1, w.y)), term(M, 1, 2, w.z)),
          _mm256_add_pd(term(M, 2, 0, w.x), _mm256_add_pd(term(M, 2, 1, w.y), term(M, 2, 2, w.z)))};
}

// plane_residual(): the pixel residual's norm where p is in front of camera 2 and the residual
// finite, *ok set per lane.
__attribute__((target("avx2"))) inline __m256d residual_norm(const V3& p, __m256d u, __m256d v,
                                                             __m256d f, __m256d* ok) {
  const __m256d inf = _mm256_set1_pd(INFINITY);
  const __m256d sign = _mm256_set1_pd(-0.0);
  const __m256d iz = _mm256_div_pd(_mm256_set1_pd(1.0), p.z);
  const __m256d rx = _mm256_mul_pd(f, _mm256_sub_pd(_mm256_mul_pd(p.x, iz), u));
  const __m256d ry = _mm256_mul_pd(f, _mm256_sub_pd(_mm256_mul_pd(p.y, iz), v));
  *ok = _mm256_and_pd(_mm256_cmp_pd(p.z, _mm256_set1_pd(1e-9), _CMP_GT_OQ),
                      _mm256_and_pd(_mm256_cmp_pd(_mm256_andnot_pd(sign, rx), inf, _CMP_LT_OQ),
                                    _mm256_cmp_pd(_mm256_andnot_pd(sign, ry), inf, _CMP_LT_OQ)));
  return _mm256_sqrt_pd(_mm256_add_pd(_mm256_mul_pd(rx, rx), _mm256_mul_pd(ry, ry)));
}

__attribute__((target("avx2"))) void classify_avx2(const std::vector<Vector3d>& x1,
                                                   const std::vector<Vector3d>& x2,
                                                   const Matrix3d& R, const Vector3d& t,
                                                   const Vector3d& Rt, const Vector3d& n,
                                                   double rho_floor, double f_px, double thr,
                                                   std::vector<PerMatch>* out) {
  const size_t N = x1.size(), blocks = N / 4 * 4;
  const __m256d f = _mm256_set1_pd(f_px), zero = _mm256_setzero_pd();
  const __m256d big = _mm256_set1_pd(1e9), thr2 = _mm256_set1_pd(thr * thr);
  const __m256d rho_f = _mm256_set1_pd(rho_floor);
  for (size_t i = 0; i < blocks; i += 4) {
    const V3 a1{lanes(x1, i, 0), lanes(x1, i, 1), lanes(x1, i, 2)};
    const __m256d u = lanes(x2, i, 0), v = lanes(x2, i, 1);
    // n.dot(x1): (n0 x0 + n1 x1) + n2 x2.
    const __m256d nd = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd(n.x()), a1.x),
                                                   _mm256_mul_pd(_mm256_set1_pd(n.y()), a1.y)),
                                     _mm256_mul_pd(_mm256_set1_pd(n.z()), a1.z));
    // plane_carry(): R (x1 - t (rho_floor nd)).
    const __m256d s = _mm256_mul_pd(rho_f, nd);
    const V3 w{_mm256_sub_pd(a1.x, _mm256_mul_pd(_mm256_set1_pd(t.x()), s)),
               _mm256_sub_pd(a1.y, _mm256_mul_pd(_mm256_set1_pd(t.y()), s)),
               _mm256_sub_pd(a1.z, _mm256_mul_pd(_mm256_set1_pd(t.z()), s))};
    __m256d ok_floor;
    const __m256d e_floor = residual_norm(times(R, w), u, v, f, &ok_floor);
    const V3 a = times(R, a1);
    const V3 b{_mm256_mul_pd(_mm256_set1_pd(Rt.x()), nd), _mm256_mul_pd(_mm256_set1_pd(Rt.y()), nd),
               _mm256_mul_pd(_mm256_set1_pd(Rt.z()), nd)};
    const __m256d cx = _mm256_sub_pd(b.x, _mm256_mul_pd(u, b.z));
    const __m256d cy = _mm256_sub_pd(b.y, _mm256_mul_pd(v, b.z));
    const __m256d ex = _mm256_sub_pd(a.x, _mm256_mul_pd(u, a.z));
    const __m256d ey = _mm256_sub_pd(a.y, _mm256_mul_pd(v, a.z));
    const __m256d cc = _mm256_add_pd(_mm256_mul_pd(cx, cx), _mm256_mul_pd(cy, cy));
    const __m256d ok_c = _mm256_cmp_pd(cc, _mm256_set1_pd(1e-18), _CMP_GT_OQ);
    const __m256d rho =
        _mm256_div_pd(_mm256_add_pd(_mm256_mul_pd(cx, ex), _mm256_mul_pd(cy, ey)), cc);
    const V3 p{_mm256_sub_pd(a.x, _mm256_mul_pd(rho, b.x)),
               _mm256_sub_pd(a.y, _mm256_mul_pd(rho, b.y)),
               _mm256_sub_pd(a.z, _mm256_mul_pd(rho, b.z))};
    __m256d ok_p;
    const __m256d e_rho = residual_norm(p, u, v, f, &ok_p);
    ok_p = _mm256_and_pd(ok_p, ok_c);
    const __m256d slack =
        _mm256_sqrt_pd(_mm256_max_pd(_mm256_sub_pd(thr2, _mm256_mul_pd(e_rho, e_rho)), zero));
    const __m256d hw =
        _mm256_div_pd(_mm256_mul_pd(slack, p.z), _mm256_mul_pd(f, _mm256_sqrt_pd(cc)));
    alignas(32) double o_floor[4], o_rho[4], o_err[4], o_hw[4];
    _mm256_store_pd(o_floor, _mm256_blendv_pd(big, e_floor, ok_floor));
    _mm256_store_pd(o_rho, _mm256_blendv_pd(zero, rho, ok_c));
    _mm256_store_pd(o_err, _mm256_blendv_pd(big, e_rho, ok_p));
    _mm256_store_pd(o_hw, _mm256_blendv_pd(zero, hw, ok_p));
    for (int k = 0; k < 4; ++k) (*out)[i + k] = PerMatch{o_floor[k], o_rho[k], o_hw[k], o_err[k]};
  }
  for (size_t i = blocks; i < N; ++i)
    classify_one(x1[i], x2[i], R, t, Rt, n, rho_floor, f_px, thr, &(*out)[i]);
}
#endif

void classify_impl(const std::vector<Vector3d>& x1, const std::vector<Vector3d>& x2,
                   const Matrix3d& R, const Vector3d& t, const Vector3d& n, double rho_floor,
                   double f, double thr, bool allow_avx2, std::vector<PerMatch>* out) {
  assert(x1.size() == x2.size());
  out->assign(x1.size(), PerMatch{});
  const Vector3d Rt = R * t;
#ifdef ALIGHT_CLASSIFY_AVX2
  if (allow_avx2 && __builtin_cpu_supports("avx2")) {
    classify_avx2(x1, x2, R, t, Rt, n, rho_floor, f, thr, out);
    return;
  }
#endif
  (void)allow_avx2;
  for (size_t i = 0; i < x1.size(); ++i)
    classify_one(x1[i], x2[i], R, t, Rt, n, rho_floor, f, thr, &(*out)[i]);
}

}  // namespace

void classify_floor_matches(const std::vector<Vector3d>& x1, const std::vector<Vector3d>& x2,
                            const Matrix3d& R, const Vector3d& t, const Vector3d& n,
                            double rho_floor, double f, double thr, std::vector<PerMatch>* out) {
  classify_impl(x1, x2, R, t, n, rho_floor, f, thr, true, out);
}

void classify_floor_matches_scalar(const std::vector<Vector3d>& x1, const std::vector<Vector3d>& x2,
                                   const Matrix3d& R, const Vector3d& t, const Vector3d& n,
                                   double rho_floor, double f, double thr,
                                   std::vector<PerMatch>* out) {
  classify_impl(x1, x2, R, t, n, rho_floor, f, thr, false, out);
}

}  // namespace alight::vision
