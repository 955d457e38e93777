// Paper 3.2: two-plane alignment; see alignment.hpp.
#include "vision/geometry/alignment.hpp"

#include <Eigen/Dense>
#include <cassert>
#include <cmath>
#include <limits>

#include "common/robust_lsq.hpp"

namespace alight::vision {
namespace {

struct State {
  Matrix3d R;
  Vector3d t, na, nb;
};

/// R exp([w]x), t + dt, n + dn from a 12-vector (w, dt, dna, dnb).
State apply(const State& s, const Eigen::VectorXd& d) {
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

/// Transfer residuals proj(R (I - t n^T) x1) - x2 of one set [normalised units], into
/// r.segment<2>(2 (at + i)).
void set_residuals(const Matrix3d& R, const Vector3d& t, const Vector3d& n,
                   const std::vector<Vector3d>& r1, const std::vector<Vector3d>& r2,
                   Eigen::VectorXd& r, size_t at) {
  const Matrix3d H = R * (Matrix3d::Identity() - t * n.transpose());
  for (size_t i = 0; i < r1.size(); ++i)
    r.segment<2>(2 * (at + i)) = (H * r1[i]).hnormalized() - r2[i].hnormalized();
}

/// Residual of the rotation prior (zero without one).
Vector3d prior_residual(const Matrix3d& R, const std::optional<RotationPrior>& prior) {
  if (!prior) return Vector3d::Zero();
  const Eigen::AngleAxisd d(prior->R_21.transpose() * R);
  return prior->weight * d.angle() * d.axis();
}

/// The joint problem: both planes' inlier rays (normalised, z = 1) and the rotation prior.
/// Residuals: plane a's points (x, y), then plane b's, then the prior's three.
struct Joint {
  const std::vector<Vector3d>& r1a;
  const std::vector<Vector3d>& r2a;
  const std::vector<Vector3d>& r1b;
  const std::vector<Vector3d>& r2b;
  const std::optional<RotationPrior>& prior;

  size_t n_points() const { return r1a.size() + r1b.size(); }
  void residuals(const State& x, Eigen::VectorXd& r) const {
    r.resize(2 * n_points() + (prior ? 3 : 0));
    set_residuals(x.R, x.t, x.na, r1a, r2a, r, 0);
    set_residuals(x.R, x.t, x.nb, r1b, r2b, r, r1a.size());
    if (prior) r.tail<3>() = prior_residual(x.R, prior);
  }
  /// Unweighted sum of squared transfer errors of both sets.
  double transfer_cost(const State& x) const {
    Eigen::VectorXd r;
    residuals(x, r);
    return r.head(2 * n_points()).squaredNorm();
  }
  /// IRLS: Cauchy weights from each set's residuals (each plane its own scale), as in the final
  /// refinement of each homography (homography.cpp): a feature on the platform's edge or a near
  /// miss inside the RANSAC threshold must not pull the shared motion. With plain least squares
  /// the joint R21 can come out worse than either plane's own. The prior keeps weight 1.
  void weights(const Eigen::VectorXd& r, Eigen::VectorXd& w) const {
    w.setOnes(r.size());
    auto set_weights = [&](size_t at, size_t n) {
      std::vector<double> e(n);
      for (size_t i = 0; i < n; ++i) e[i] = r.segment<2>(2 * (at + i)).norm();
      const std::vector<double> wi = lsq::cauchy_weights(e, 1e-6);
      for (size_t i = 0; i < n; ++i) w(2 * (at + i)) = w(2 * (at + i) + 1) = wi[i];
    };
    set_weights(0, r1a.size());
    set_weights(r1a.size(), r1b.size());
  }
};

/// Levenberg-Marquardt (common/robust_lsq.hpp) on the joint (weighted) transfer error and the
/// rotation prior, forward-difference Jacobian through apply(); robust: the weights are
/// re-evaluated at the start and after every accepted step (IRLS). Returns the final cost.
double refine(State& s, const Joint& jp, int iterations, bool robust) {
  lsq::Problem problem;
  problem.num_parameters = 12;
  problem.residuals = [&](const Eigen::VectorXd& d, Eigen::VectorXd& r) {
    jp.residuals(apply(s, d), r);
  };
  problem.accept = [&](const Eigen::VectorXd& d) { s = apply(s, d); };
  if (robust)
    problem.weights = [&](const Eigen::VectorXd& r, Eigen::VectorXd& w) { jp.weights(r, w); };
  lsq::Options options;
  options.max_iterations = iterations;
  return lsq::solve(problem, options).final_cost;
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
  if (!any) return R::fail(Reason::kPlanesDisagree);
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
    return R::fail(Reason::kAlignedPlaneBehind);
  return R::ok(out);
}

}  // namespace alight::vision
