#pragma once
// Refinement of the target estimate (paper 3.4.1 "Refinement of Estimate", eqs. 7-9).
//
// The estimate after n waypoints X_V,i is their sample mean X^_n; it is final when
//   n >= n_min (eq. 7),  |horizontal part of X^_n - X^_n-1| <= eps_horz (eq. 8),
//   |vertical part of X^_n - X^_n-1| <= eps_vert (eq. 9).
// Eq. 8 is printed as |[1 1 0](X^_n - X^_n-1)|, which literally sums the x and y changes; we read
// it as the horizontal (x, y) norm, which is what "horizontal change" means and does not let
// opposite x and y changes cancel.
//
// Outliers (the paper: "measurements are subject to noise and outliers") are gated by the squared
// Mahalanobis distance (P. C. Mahalanobis, "On the generalised distance in statistics", 1936) d^2 =
// (X - mu)^T (S + s0^2 I)^-1 (X - mu) against the sample mean mu and sample covariance S of the
// accepted waypoints, with an isotropic floor s0 so that a few identical early waypoints do not
// make the gate infinitely tight; d^2 > gate_chi2 (chi^2 with 3 degrees of freedom) rejects. The
// gate starts at gate_min_n waypoints. Because an outlier among the first few waypoints would
// inflate S and open the gate, every accepted waypoint is followed by a leave-one-out pass: each
// stored waypoint is tested against the mean and covariance of the others, and the worst one beyond
// the gate is removed (repeated while one is). If max_consecutive_rejections waypoints in a row are
// rejected, the estimate itself was seeded by outliers (or the target moved): it restarts from the
// newest waypoint.

#include <random>
#include <vector>

#include "autonomy/params.hpp"
#include "common/geometry.hpp"

namespace alight::autonomy {

class RefinementEstimator {
 public:
  enum class Verdict { kAccepted, kRejected, kRestarted };

  explicit RefinementEstimator(const RefinementParams& params) : params_(params) {}

  /// Adds one waypoint measurement X_V,i [m].
  Verdict add(const Vector3d& X_W);
  void reset();

  int n() const { return static_cast<int>(samples_.size()); }
  int n_rejected() const { return n_rejected_; }
  /// X^_n, the sample mean (zero when n = 0).
  Vector3d mean() const;
  /// Sample covariance (divisor n - 1; zero when n < 2).
  Matrix3d covariance() const;
  /// Eqs. 7-9 on the change of the mean caused by the last accepted waypoint.
  bool converged() const;
  /// X^_n - X^_n-1 of the last accepted waypoint.
  const Vector3d& last_change() const { return last_change_; }
  /// Squared Mahalanobis distance of X from the accepted waypoints (gate statistic).
  double mahalanobis2(const Vector3d& X_W) const;
  const std::vector<Vector3d>& samples() const { return samples_; }

 private:
  static Vector3d mean_of(const std::vector<Vector3d>& s, int skip);
  static Matrix3d cov_of(const std::vector<Vector3d>& s, const Vector3d& mu, int skip);
  void prune_outliers();

  RefinementParams params_;
  std::vector<Vector3d> samples_;
  int n_rejected_ = 0;
  int consecutive_rejections_ = 0;
  bool have_change_ = false;
  Vector3d last_change_ = Vector3d::Zero();
};

/// Vantage points of the refinement phase: positions drawn from the bivariate normal N(mu, Sigma)
/// of the waypoints so far (paper 3.4.1), Sigma widened by an isotropic floor so that the camera
/// keeps moving (the reconstruction needs baseline), draws farther than cutoff_m from mu redrawn.
class VantageSampler {
 public:
  VantageSampler(const RefinementParams& params, uint64_t seed) : params_(params), rng_(seed) {}

  /// A 2-D draw around mu_2 with covariance Sigma_2 (prior_sigma when n < 2).
  Vector2d draw(const Vector2d& mu_2, const Eigen::Matrix2d& Sigma_2, int n);

 private:
  RefinementParams params_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

}  // namespace alight::autonomy
