// Paper 3.2: two-plane alignment; see alignment.hpp.
#include "vision/alignment.hpp"

#include <Eigen/Dense>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>

#include "vision/homography.hpp"

namespace alight::vision {
namespace {

using Vec12 = Eigen::Matrix<double, 12, 1>;

struct State {
  Matrix3d R;
  Vector3d t, na, nb;
};

/// R exp([w]x), t + dt, n + dn from a 12-vector (w, dt, dna, dnb).
State apply(const State& s, const Vec12& d) {
  State o = s;
  const Vector3d w = d.segment<3>(0);
  const double angle = w.norm();
  if (angle > 0) o.R = s.R * Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
  o.t = s.t + d.segment<3>(3);
  o.na = s.na + d.segment<3>(6);
  o.nb = s.nb + d.segment<3>(9);
  // Gauge: |t| = 1 (t n^T is all the data sees).
  const double tn = o.t.norm();
  if (tn > 1e-12) o.t /= tn, o.na *= tn, o.nb *= tn;
  return o;
}

/// Transfer errors |proj(R (I - t n^T) x1) - x2| of one set [normalised units].
std::vector<double> set_errors(const Matrix3d& R, const Vector3d& t, const Vector3d& n,
                               const std::vector<Vector3d>& r1, const std::vector<Vector3d>& r2) {
  const Matrix3d H = R * (Matrix3d::Identity() - t * n.transpose());
  std::vector<double> e(r1.size());
  for (size_t i = 0; i < r1.size(); ++i)
    e[i] = ((H * r1[i]).hnormalized() - r2[i].hnormalized()).norm();
  return e;
}

/// Residual of the rotation prior (zero without one).
Vector3d prior_residual(const Matrix3d& R, const std::optional<RotationPrior>& prior) {
  if (!prior) return Vector3d::Zero();
  const Eigen::AngleAxisd d(prior->R_21.transpose() * R);
  return prior->weight * d.angle() * d.axis();
}

/// The joint problem: both planes' inlier rays (normalised, z = 1), per-point weights of their
/// squared transfer errors (1 until reweight()), and the rotation prior.
struct Joint {
  const std::vector<Vector3d>& r1a;
  const std::vector<Vector3d>& r2a;
  const std::vector<Vector3d>& r1b;
  const std::vector<Vector3d>& r2b;
  const std::optional<RotationPrior>& prior;
  std::vector<double> wa = std::vector<double>(r1a.size(), 1.0);
  std::vector<double> wb = std::vector<double>(r1b.size(), 1.0);

  /// Sum of w_i e_i^2 (w empty: weight 1).
  static double sum_sq(const std::vector<double>& e, const std::vector<double>& w = {}) {
    double c = 0;
    for (size_t i = 0; i < e.size(); ++i) c += (w.empty() ? 1.0 : w[i]) * e[i] * e[i];
    return c;
  }
  /// Unweighted sum of squared transfer errors of both sets.
  double transfer_cost(const State& x) const {
    return sum_sq(set_errors(x.R, x.t, x.na, r1a, r2a)) +
           sum_sq(set_errors(x.R, x.t, x.nb, r1b, r2b));
  }
  /// What the refinement minimises: weighted transfer errors and the prior.
  double cost(const State& x) const {
    return sum_sq(set_errors(x.R, x.t, x.na, r1a, r2a), wa) +
           sum_sq(set_errors(x.R, x.t, x.nb, r1b, r2b), wb) +
           prior_residual(x.R, prior).squaredNorm();
  }
  /// IRLS: Cauchy weights from each set's residuals at x (each plane its own scale), as in the
  /// final refinement of each homography (homography.cpp): a feature on the platform's edge or a
  /// near miss inside the RANSAC threshold must not pull the shared motion. With plain least
  /// squares the joint R21 came out worse than either plane's own (rendered seed 6: 0.19 deg
  /// against 0.05 deg each).
  void reweight(const State& x) {
    wa = cauchy_weights(set_errors(x.R, x.t, x.na, r1a, r2a), 1e-6);
    wb = cauchy_weights(set_errors(x.R, x.t, x.nb, r1b, r2b), 1e-6);
  }
};

/// Levenberg-Marquardt on the joint (weighted) transfer error and the rotation prior; robust:
/// the weights are re-evaluated at the start and after every accepted step (IRLS). Returns the
/// final cost.
double refine(State& s, Joint& jp, int iterations, bool robust) {
  if (robust) jp.reweight(s);
  double cost = jp.cost(s);
  double lambda = 1e-4;
  for (int it = 0; it < iterations; ++it) {
    // Gauss-Newton normal equations from forward-difference Jacobians, point by point.
    Eigen::Matrix<double, 12, 12> JtJ = Eigen::Matrix<double, 12, 12>::Zero();
    Vec12 Jtr = Vec12::Zero();
    const double h = 1e-7;
    std::array<State, 12> shifted;
    for (int k = 0; k < 12; ++k) {
      shifted[k] = s;
      // Without the gauge renormalisation, so each column is a clean partial derivative.
      if (k < 3)
        shifted[k].R = s.R * Eigen::AngleAxisd(h, Vector3d::Unit(k)).toRotationMatrix();
      else if (k < 6)
        shifted[k].t(k - 3) += h;
      else if (k < 9)
        shifted[k].na(k - 6) += h;
      else
        shifted[k].nb(k - 9) += h;
    }
    auto accumulate = [&](const std::vector<Vector3d>& r1, const std::vector<Vector3d>& r2,
                          const std::vector<double>& w, bool plane_a) {
      auto H_of = [&](const State& x) {
        return Matrix3d(x.R * (Matrix3d::Identity() - x.t * (plane_a ? x.na : x.nb).transpose()));
      };
      const Matrix3d H0 = H_of(s);
      std::array<Matrix3d, 12> Hk;
      for (int k = 0; k < 12; ++k) Hk[k] = H_of(shifted[k]);
      for (size_t i = 0; i < r1.size(); ++i) {
        const Vector2d p0 = (H0 * r1[i]).hnormalized();
        const Vector2d res = p0 - r2[i].hnormalized();
        Eigen::Matrix<double, 2, 12> J;
        for (int k = 0; k < 12; ++k) J.col(k) = ((Hk[k] * r1[i]).hnormalized() - p0) / h;
        JtJ.noalias() += w[i] * J.transpose() * J;
        Jtr.noalias() += w[i] * J.transpose() * res;
      }
    };
    accumulate(jp.r1a, jp.r2a, jp.wa, true);
    accumulate(jp.r1b, jp.r2b, jp.wb, false);
    if (jp.prior) {
      const Vector3d r0 = prior_residual(s.R, jp.prior);
      Eigen::Matrix<double, 3, 12> J = Eigen::Matrix<double, 3, 12>::Zero();
      for (int k = 0; k < 3; ++k) J.col(k) = (prior_residual(shifted[k].R, jp.prior) - r0) / h;
      JtJ.noalias() += J.transpose() * J;
      Jtr.noalias() += J.transpose() * r0;
    }
    bool improved = false;
    while (lambda < 1e6) {
      Eigen::Matrix<double, 12, 12> A = JtJ;
      A.diagonal() += lambda * (JtJ.diagonal().array() + 1e-12).matrix();
      const Vec12 d = A.ldlt().solve(-Jtr);
      if (!d.allFinite()) break;
      const State n = apply(s, d);
      const double c = jp.cost(n);
      if (c < cost) {
        const bool converged = cost - c < 1e-10 * cost;
        s = n, cost = c, lambda = std::max(1e-9, lambda * 0.1), improved = !converged;
        break;
      }
      lambda *= 10;
    }
    if (!improved) break;
    if (robust) {
      jp.reweight(s);
      cost = jp.cost(s);
    }
  }
  return cost;
}

}  // namespace

std::optional<RotationPrior> rotation_prior(const Matrix3d& R_21_mocap, const AlignParams& params,
                                            double focal_px) {
  assert(focal_px > 0);
  if (params.rotation_prior_sigma_deg <= 0) return std::nullopt;
  const double sigma_rad = params.rotation_prior_sigma_deg * M_PI / 180.0;
  return RotationPrior{R_21_mocap, params.feature_sigma_px / focal_px / sigma_rad};
}

Result<TwoPlaneMotion> align_two_planes(const Matrix3d& H_a, const std::vector<Vector3d>& rays_1a,
                                        const std::vector<Vector3d>& rays_2a, const Matrix3d& H_b,
                                        const std::vector<Vector3d>& rays_1b,
                                        const std::vector<Vector3d>& rays_2b,
                                        const AlignParams& params,
                                        const DecompositionParams& dparams,
                                        const std::optional<RotationPrior>& prior) {
  using R = Result<TwoPlaneMotion>;
  const auto all_a = decompose_homography(H_a, rays_1a, dparams);
  const auto all_b = decompose_homography(H_b, rays_1b, dparams);
  if (all_a.empty() || all_b.empty()) return R::fail(Reason::kSmallBaseline);
  const auto ca = positive_depth(all_a, rays_1a, rays_2a, dparams);
  const auto cb = positive_depth(all_b, rays_1b, rays_2b, dparams);
  if (ca.empty() || cb.empty()) return R::fail(Reason::kDecompositionFailed);

  constexpr double kDeg = M_PI / 180.0;
  const double max_r = params.max_rotation_disagreement_deg * kDeg;
  const double max_t = params.max_translation_disagreement_deg * kDeg;
  Joint jp{rays_1a, rays_2a, rays_1b, rays_2b, prior};
  // Pairs of candidates whose motions agree within the limits. Two parallel planes (a floor and
  // a platform top) have false solutions whose translations agree (both along the normal), so
  // agreement of the separate decompositions alone does not decide: the pair whose common
  // motion explains both point sets best does, after a few plain refinement steps.
  TwoPlaneMotion out;
  State s;
  double cost = std::numeric_limits<double>::max();
  bool any = false;
  for (const auto& a : ca)
    for (const auto& b : cb) {
      const double dr = rotation_angle(a.R_21, b.R_21), dt = direction_angle(a.t_12, b.t_12);
      if (dr > max_r || dt > max_t) continue;
      State x;
      x.R = nearest_rotation(a.R_21 + b.R_21);  // mean motion, each plane keeps its own n~
      x.t = (a.t_12 + b.t_12).normalized();
      x.na = a.n_1, x.nb = b.n_1;
      const State x0 = x;
      const double c = refine(x, jp, std::min(3, params.max_iterations), false);
      if (c < cost) {
        s = x, cost = c, any = true;
        out.rotation_disagreement_rad = dr, out.translation_disagreement_rad = dt;
        out.rms_before = std::sqrt(jp.transfer_cost(x0) / double(rays_1a.size() + rays_1b.size()));
      }
    }
  if (!any) return R::fail(Reason::kDecompositionFailed);
  const size_t n_points = rays_1a.size() + rays_1b.size();
  refine(s, jp, params.max_iterations, params.robust);
  out.R_21 = nearest_rotation(s.R);
  out.t_12 = s.t.normalized();
  out.n_a = s.na, out.n_b = s.nb;
  out.rms_after = std::sqrt(jp.transfer_cost(s) / double(std::max<size_t>(1, n_points)));
  out.used_rotation_prior = prior.has_value();
  // The refined planes must still lie in front of both cameras.
  if (positive_depth({out.plane_a()}, rays_1a, rays_2a, dparams).empty() ||
      positive_depth({out.plane_b()}, rays_1b, rays_2b, dparams).empty())
    return R::fail(Reason::kDecompositionFailed);
  return R::ok(out);
}

}  // namespace alight::vision
