// Paper 3.1.2: RANSAC homography; see homography.hpp for the methods and their sources.
#include "vision/geometry/homography.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "common/robust_lsq.hpp"
#include "vision/simd.hpp"

namespace alight::vision {
namespace {

/// Hartley normalisation: centroid to the origin, mean distance sqrt(2).
struct Normaliser {
  Vector2d c = Vector2d::Zero();
  double s = 1.0;
  Matrix3d T() const {
    Matrix3d T;
    T << s, 0, -s * c.x(), 0, s, -s * c.y(), 0, 0, 1;
    return T;
  }
  Matrix3d T_inv() const {
    Matrix3d T;
    T << 1 / s, 0, c.x(), 0, 1 / s, c.y(), 0, 0, 1;
    return T;
  }
  Vector2d apply(const Vector2d& p) const { return s * (p - c); }
};

template <class Get>
Normaliser make_normaliser(size_t n, Get get) {
  Normaliser N;
  if (n == 0) return N;
  for (size_t i = 0; i < n; ++i) N.c += get(i);
  N.c /= double(n);
  double mean = 0.0;
  for (size_t i = 0; i < n; ++i) mean += (get(i) - N.c).norm();
  mean /= double(n);
  N.s = mean > 1e-12 ? std::sqrt(2.0) / mean : 1.0;
  return N;
}

/// Structure of arrays of normalised correspondences, for the vectorised scoring loop.
struct Points {
  std::vector<float> x1, y1, x2, y2;
};

/// MSAC score of H over all points: returns the number of inliers, writes the truncated cost.
ALIGHT_MULTIVERSION
int score(const Matrix3d& Hd, const Points& p, float thr2, float* cost_out) {
  const float h0 = float(Hd(0, 0)), h1 = float(Hd(0, 1)), h2 = float(Hd(0, 2));
  const float h3 = float(Hd(1, 0)), h4 = float(Hd(1, 1)), h5 = float(Hd(1, 2));
  const float h6 = float(Hd(2, 0)), h7 = float(Hd(2, 1)), h8 = float(Hd(2, 2));
  const size_t n = p.x1.size();
  const float* __restrict x1 = p.x1.data();
  const float* __restrict y1 = p.y1.data();
  const float* __restrict x2 = p.x2.data();
  const float* __restrict y2 = p.y2.data();
  int count = 0;
  float cost = 0.f;
  for (size_t i = 0; i < n; ++i) {
    const float w = h6 * x1[i] + h7 * y1[i] + h8;
    const float iw = 1.f / w;
    const float dx = (h0 * x1[i] + h1 * y1[i] + h2) * iw - x2[i];
    const float dy = (h3 * x1[i] + h4 * y1[i] + h5) * iw - y2[i];
    float e2 = dx * dx + dy * dy;
    e2 = (w > 0.f) ? e2 : thr2;  // a point mapped behind the camera is never an inlier
    count += e2 < thr2 ? 1 : 0;
    cost += e2 < thr2 ? e2 : thr2;
  }
  *cost_out = cost;
  return count;
}

void inlier_mask(const Matrix3d& H, const std::vector<Vector2d>& x1,
                 const std::vector<Vector2d>& x2, double thr, std::vector<uint8_t>& mask) {
  mask.resize(x1.size());
  const double thr2 = thr * thr;
  for (size_t i = 0; i < x1.size(); ++i) {
    const Vector3d q = H * x1[i].homogeneous();
    mask[i] = q.z() > 0.0 && (q.hnormalized() - x2[i]).squaredNorm() < thr2;
  }
}

double cross2(const Vector2d& a, const Vector2d& b, const Vector2d& c) {
  const Vector2d u = b - a, v = c - a;
  return u.x() * v.y() - u.y() * v.x();
}

/// True when some triple of the 4 points is (nearly) collinear in either image, or the sample's
/// orientation differs between the images (no homography of a plane seen from one side does
/// that).
bool degenerate_sample(const Vector2d* a, const Vector2d* b, double min_height_a,
                       double min_height_b) {
  static constexpr int kTriples[4][3] = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  for (const auto& t : kTriples) {
    const double ca = cross2(a[t[0]], a[t[1]], a[t[2]]);
    const double cb = cross2(b[t[0]], b[t[1]], b[t[2]]);
    if ((ca > 0) != (cb > 0)) return true;
    const double la = std::max(
        {(a[t[1]] - a[t[0]]).norm(), (a[t[2]] - a[t[0]]).norm(), (a[t[2]] - a[t[1]]).norm()});
    const double lb = std::max(
        {(b[t[1]] - b[t[0]]).norm(), (b[t[2]] - b[t[0]]).norm(), (b[t[2]] - b[t[1]]).norm()});
    if (std::abs(ca) < min_height_a * la || std::abs(cb) < min_height_b * lb) return true;
  }
  return false;
}

/// Levenberg-Marquardt (common/robust_lsq.hpp) on the forward transfer error
/// |proj(H x1) - x2|, h33 = 1, analytic Jacobian.
///
/// Robust: the residuals of real matches are heavy-tailed (a blob detected at the neighbouring
/// filter scale in one view moves by up to a pixel, and a near-miss match can sit just inside
/// the inlier threshold, where the hard threshold of the inlier set gives it full weight), so
/// the squared errors are Cauchy-weighted (lsq::cauchy_weights, sigma from the inliers' median
/// residual) and the weights re-evaluated after each accepted step (IRLS; Holland & Welsch
/// 1977). On warped photographs (features_test's and others) this lowered the mean corner error
/// by 10-15 % against plain least squares and removed its worst cases; measuring the error in
/// both images (symmetric transfer, Hartley & Zisserman eq. 4.7) was tried as well and was no
/// better than the forward error.
Matrix3d refine_transfer(const Matrix3d& H0, const std::vector<Vector2d>& x1,
                         const std::vector<Vector2d>& x2, const std::vector<int>& idx,
                         int iterations, bool robust) {
  if (std::abs(H0(2, 2)) < 1e-12) return H0;
  Matrix3d H = H0 / H0(2, 2);
  const size_t m = idx.size();
  auto plus = [&](const Eigen::VectorXd& dh) {
    Matrix3d G = H;
    for (int k = 0; k < 8; ++k) G(k / 3, k % 3) += dh(k);
    return G;
  };
  lsq::Problem problem;
  problem.num_parameters = 8;
  problem.residuals = [&](const Eigen::VectorXd& dh, Eigen::VectorXd& r) {
    const Matrix3d G = plus(dh);
    r.resize(2 * m);
    for (size_t k = 0; k < m; ++k)
      r.segment<2>(2 * k) = (G * x1[idx[k]].homogeneous()).hnormalized() - x2[idx[k]];
  };
  problem.jacobian = [&](const Eigen::VectorXd&, Eigen::MatrixXd& J) {
    J.resize(2 * m, 8);
    for (size_t k = 0; k < m; ++k) {
      const double x = x1[idx[k]].x(), y = x1[idx[k]].y();
      const Vector3d q = H * Vector3d(x, y, 1.0);
      const double iw = 1.0 / q.z();
      const double u = q.x() * iw, v = q.y() * iw;
      J.block<2, 8>(2 * k, 0) << x * iw, y * iw, iw, 0, 0, 0, -u * x * iw, -u * y * iw,  //
          0, 0, 0, x * iw, y * iw, iw, -v * x * iw, -v * y * iw;
    }
  };
  problem.accept = [&](const Eigen::VectorXd& dh) { H = plus(dh); };
  if (robust)
    problem.weights = [&](const Eigen::VectorXd& r, Eigen::VectorXd& w) {
      std::vector<double> e(m);
      for (size_t k = 0; k < m; ++k) e[k] = r.segment<2>(2 * k).norm();
      const std::vector<double> wk = lsq::cauchy_weights(e, 1e-3);
      w.resize(2 * m);
      for (size_t k = 0; k < m; ++k) w(2 * k) = w(2 * k + 1) = wk[k];
    };
  lsq::Options options;
  options.max_iterations = iterations;
  lsq::solve(problem, options);
  return H;
}

double log_ratio_iterations(double confidence, double p_sample, int cap) {
  if (p_sample >= 1.0) return 1.0;
  if (p_sample <= 0.0) return cap;
  const double k = std::log(1.0 - confidence) / std::log(1.0 - p_sample);
  return std::min<double>(cap, std::ceil(k));
}

}  // namespace

std::optional<Matrix3d> homography_from_4(const Vector2d* x1, const Vector2d* x2) {
  Eigen::Matrix<double, 8, 8> A;
  Eigen::Matrix<double, 8, 1> b;
  for (int i = 0; i < 4; ++i) {
    const double x = x1[i].x(), y = x1[i].y(), u = x2[i].x(), v = x2[i].y();
    A.row(2 * i) << x, y, 1, 0, 0, 0, -x * u, -y * u;
    A.row(2 * i + 1) << 0, 0, 0, x, y, 1, -x * v, -y * v;
    b(2 * i) = u;
    b(2 * i + 1) = v;
  }
  const Eigen::PartialPivLU<Eigen::Matrix<double, 8, 8>> lu(A);
  if (!(std::abs(lu.determinant()) > 1e-10)) return std::nullopt;
  const Eigen::Matrix<double, 8, 1> h = lu.solve(b);
  if (!h.allFinite()) return std::nullopt;
  Matrix3d H;
  H << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), 1.0;
  return H;
}

std::optional<Matrix3d> homography_dlt(const std::vector<Vector2d>& x1,
                                       const std::vector<Vector2d>& x2) {
  const size_t n = x1.size();
  if (n < 4 || x2.size() != n) return std::nullopt;
  const Normaliser N1 = make_normaliser(n, [&](size_t i) { return x1[i]; });
  const Normaliser N2 = make_normaliser(n, [&](size_t i) { return x2[i]; });
  Eigen::Matrix<double, 9, 9> AtA = Eigen::Matrix<double, 9, 9>::Zero();
  for (size_t i = 0; i < n; ++i) {
    const Vector2d p = N1.apply(x1[i]), q = N2.apply(x2[i]);
    Eigen::Matrix<double, 9, 1> r1, r2;
    r1 << p.x(), p.y(), 1, 0, 0, 0, -q.x() * p.x(), -q.x() * p.y(), -q.x();
    r2 << 0, 0, 0, p.x(), p.y(), 1, -q.y() * p.x(), -q.y() * p.y(), -q.y();
    AtA.selfadjointView<Eigen::Lower>().rankUpdate(r1);
    AtA.selfadjointView<Eigen::Lower>().rankUpdate(r2);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 9, 9>> es(
      AtA.selfadjointView<Eigen::Lower>());
  if (es.info() != Eigen::Success) return std::nullopt;
  const Eigen::Matrix<double, 9, 1> h = es.eigenvectors().col(0);
  Matrix3d Hn;
  Hn << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
  Matrix3d H = N2.T_inv() * Hn * N1.T();
  if (!H.allFinite() || std::abs(H.determinant()) < 1e-15 * std::pow(H.norm(), 3))
    return std::nullopt;
  if (std::abs(H(2, 2)) > 1e-12) H /= H(2, 2);
  return H;
}

double transfer_error(const Matrix3d& H, const Vector2d& x1, const Vector2d& x2) {
  return ((H * x1.homogeneous()).hnormalized() - x2).norm();
}

double corner_error(const Matrix3d& H_a, const Matrix3d& H_b, double width, double height) {
  const Vector2d corners[4] = {{0, 0}, {width, 0}, {width, height}, {0, height}};
  double sum = 0.0;
  for (const auto& c : corners)
    sum += ((H_a * c.homogeneous()).hnormalized() - (H_b * c.homogeneous()).hnormalized()).norm();
  return sum / 4.0;
}

Result<HomographyFit> fit_homography(const std::vector<Vector2d>& x1,
                                     const std::vector<Vector2d>& x2,
                                     const HomographyParams& params, Sampling sampling,
                                     int* iterations) {
  assert(x1.size() == x2.size());
  const int n = int(x1.size());
  if (n < 4 || n < params.min_inliers) return Result<HomographyFit>::fail(Reason::kTooFewMatches);

  const Normaliser N1 = make_normaliser(n, [&](size_t i) { return x1[i]; });
  const Normaliser N2 = make_normaliser(n, [&](size_t i) { return x2[i]; });
  std::vector<Vector2d> a(n), b(n);
  Points pts;
  pts.x1.resize(n), pts.y1.resize(n), pts.x2.resize(n), pts.y2.resize(n);
  for (int i = 0; i < n; ++i) {
    a[i] = N1.apply(x1[i]);
    b[i] = N2.apply(x2[i]);
    pts.x1[i] = float(a[i].x()), pts.y1[i] = float(a[i].y());
    pts.x2[i] = float(b[i].x()), pts.y2[i] = float(b[i].y());
  }
  const double thr_a = params.threshold_px * N1.s, thr_b = params.threshold_px * N2.s;
  const float thr2 = float(thr_b * thr_b);

  // Neighbours in image 1 for local sampling (the outlier sets are small: O(n^2) is fine).
  const int k = std::min(params.local_neighbours, n - 1);
  std::vector<int> knn;
  if (sampling == Sampling::kLocal) {
    knn.resize(size_t(n) * k);
    std::vector<std::pair<double, int>> d(n);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) d[j] = {j == i ? 1e300 : (a[j] - a[i]).squaredNorm(), j};
      std::nth_element(d.begin(), d.begin() + (k - 1), d.end());  // the k nearest, any order
      for (int j = 0; j < k; ++j) knn[size_t(i) * k + j] = d[j].second;
    }
  }
  // Probability that a sample is all-inlier for a plane of `m` points.
  auto p_sample = [&](int m) {
    const double eps = double(m) / n;
    if (sampling == Sampling::kUniform) return eps * eps * eps * eps;
    const double q = std::min(0.75, double(m - 1) / k);
    return eps * q * q * q;
  };
  // Early exit: stop once the smallest plane worth reporting would have been found.
  double needed =
      log_ratio_iterations(params.confidence, p_sample(params.min_inliers), params.max_iterations);

  std::mt19937_64 rng(params.seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::uniform_int_distribution<int> pick_nb(0, k - 1);
  float best_cost = std::numeric_limits<float>::max();
  int best_count = 0;
  Matrix3d best_H = Matrix3d::Identity();
  int it = 0;
  std::vector<Vector2d> sa, sb;
  for (; it < needed; ++it) {
    int idx[4];
    idx[0] = pick(rng);
    for (int j = 1; j < 4; ++j) {
      bool fresh;
      do {
        idx[j] = sampling == Sampling::kLocal ? knn[size_t(idx[0]) * k + pick_nb(rng)] : pick(rng);
        fresh = true;
        for (int l = 0; l < j; ++l) fresh = fresh && idx[l] != idx[j];
      } while (!fresh);
    }
    Vector2d pa[4], pb[4];
    for (int j = 0; j < 4; ++j) pa[j] = a[idx[j]], pb[j] = b[idx[j]];
    if (degenerate_sample(pa, pb, 2.0 * thr_a, 2.0 * thr_b)) continue;
    const auto H = homography_from_4(pa, pb);
    if (!H) continue;
    float cost;
    int count = score(*H, pts, thr2, &cost);
    if (cost >= best_cost) continue;
    best_cost = cost, best_count = count, best_H = *H;
    // Local optimisation: refit on the inliers while that lowers the cost.
    for (int lo = 0; lo < 3 && best_count >= 8; ++lo) {
      sa.clear(), sb.clear();
      std::vector<uint8_t> m;
      inlier_mask(best_H, a, b, thr_b, m);
      for (int i = 0; i < n; ++i)
        if (m[i]) sa.push_back(a[i]), sb.push_back(b[i]);
      const auto Hl = homography_dlt(sa, sb);
      if (!Hl) break;
      count = score(*Hl, pts, thr2, &cost);
      if (cost >= best_cost) break;
      best_cost = cost, best_count = count, best_H = *Hl;
    }
    if (best_count >= params.min_inliers)
      needed = std::min(needed, log_ratio_iterations(params.confidence, p_sample(best_count),
                                                     params.max_iterations));
  }
  if (iterations) *iterations = it;
  if (best_count < params.min_inliers) return Result<HomographyFit>::fail(Reason::kNoDominantPlane);

  // Final least squares on the inliers in pixels: DLT until the inlier set settles, then
  // Gauss-Newton on the transfer error.
  HomographyFit fit;
  fit.iterations = it;
  Matrix3d H = N2.T_inv() * best_H * N1.T();
  std::vector<uint8_t> mask;
  inlier_mask(H, x1, x2, params.threshold_px, mask);
  for (int pass = 0; pass < 3; ++pass) {
    std::vector<Vector2d> p, q;
    for (int i = 0; i < n; ++i)
      if (mask[i]) p.push_back(x1[i]), q.push_back(x2[i]);
    const auto Hl = homography_dlt(p, q);
    if (!Hl) break;
    std::vector<uint8_t> m2;
    inlier_mask(*Hl, x1, x2, params.threshold_px, m2);
    if (std::count(m2.begin(), m2.end(), 1) < std::count(mask.begin(), mask.end(), 1)) break;
    H = *Hl;
    const bool same = m2 == mask;
    mask = std::move(m2);
    if (same) break;
  }
  std::vector<int> idx;
  for (int i = 0; i < n; ++i)
    if (mask[i]) idx.push_back(i);
  if (params.refine_iterations > 0 && int(idx.size()) >= 5) {
    H = refine_transfer(H, x1, x2, idx, params.refine_iterations, params.robust_refinement);
    inlier_mask(H, x1, x2, params.threshold_px, mask);
  }
  fit.n_inliers = int(std::count(mask.begin(), mask.end(), 1));
  if (fit.n_inliers < params.min_inliers || !H.allFinite())
    return Result<HomographyFit>::fail(Reason::kNoDominantPlane);
  double sum2 = 0.0;
  for (int i = 0; i < n; ++i)
    if (mask[i]) sum2 += std::pow(transfer_error(H, x1[i], x2[i]), 2);
  fit.rms_px = std::sqrt(sum2 / fit.n_inliers);
  fit.H = std::abs(H(2, 2)) > 1e-9 ? Matrix3d(H / H(2, 2)) : Matrix3d(H / H.norm());
  fit.inlier = std::move(mask);
  return Result<HomographyFit>::ok(std::move(fit));
}

Result<PlanePair> fit_two_homographies(const std::vector<Vector2d>& x1,
                                       const std::vector<Vector2d>& x2,
                                       const HomographyParams& params) {
  auto first = fit_homography(x1, x2, params, Sampling::kUniform);
  if (!first) return Result<PlanePair>::fail(first.reason());
  PlanePair pair;
  pair.first = std::move(first.value());
  std::vector<Vector2d> o1, o2;
  std::vector<int> index;
  for (size_t i = 0; i < x1.size(); ++i)
    if (!pair.first.inlier[i]) o1.push_back(x1[i]), o2.push_back(x2[i]), index.push_back(int(i));
  auto second = fit_homography(o1, o2, params, Sampling::kLocal, &pair.second_iterations);
  if (second) {
    HomographyFit fit = std::move(second.value());
    std::vector<uint8_t> mask(x1.size(), 0);
    for (size_t k = 0; k < index.size(); ++k) mask[index[k]] = fit.inlier[k];
    fit.inlier = std::move(mask);
    pair.second = std::move(fit);
  } else {
    pair.second_reason = Reason::kNoTargetPlane;
  }
  return Result<PlanePair>::ok(std::move(pair));
}

}  // namespace alight::vision
