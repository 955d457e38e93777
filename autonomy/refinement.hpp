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
//
// Without motion capture the waypoints are measured in the onboard estimate's frame, which drifts:
// each waypoint carries the frame's position covariance when it was measured, and the growth of
// that covariance between waypoints is the frame's drift. The mean is then the wrong estimate of
// where the target lies in the frame now (it lags the drift by half the refinement); `filter()`
// is the Kalman filter (R. E. Kalman, 1960) of a target that walks with the frame: prediction by
// the covariance's growth, update by each waypoint with the waypoints' own noise R, read from the
// differences of consecutive waypoints less the drift between them. With no drift (motion capture)
// it is the mean itself. Eqs. 7-9 and the gate stay on the mean: they judge whether the views
// agree.
//
// Beyond the paper, a view of part of the target measured as the whole: vision takes a block of
// an opening's cells for the opening where a smooth room behind one side shows no parallax, or
// the band of a top's features for the top; such a view's centre lies up to half the missing
// extent off the true one, and its dwell can repeat it at every frame. Each waypoint carries the
// size its dwell measured; the estimate is formed from the waypoints whose size is the
// target's (the median of every waypoint's), within what lets the centre lie no farther off
// than the gate's floor sigma. The others are set aside, not dropped: the median is read again
// at every waypoint, so which waypoints count follows the many (views set aside count again once
// views of their size outnumber the others, and the reverse).

#include <limits>
#include <optional>
#include <random>
#include <vector>

#include "autonomy/params.hpp"
#include "common/geometry.hpp"

namespace alight::autonomy {

/// A target's position in the (possibly drifting) frame and its covariance [m, m^2].
struct TargetFilter {
  Vector3d x = Vector3d::Zero();
  Matrix3d P = Matrix3d::Zero();
};

/// Each coordinate's median (the upper of the middle two for an even count) of non-empty points:
/// a waypoint from a dwell's targets, robust to a stray frame among few.
Vector3d componentwise_median(const std::vector<Vector3d>& points);
Vector2d componentwise_median_2d(const std::vector<Vector2d>& points);

/// How far a view's centre may lie from the target's when it measured the target smaller than
/// the whole (whole_m, measured_m: size_m's two sides): a view that saw part of it has its centre
/// up to half the missing extent off. 0 when either is unmeasured (non-finite) [m].
double partial_view_slack_m(const Vector2d& whole_m, const Vector2d& measured_m);

/// The frame's drift between two of its position covariances: the positive part of the growth
/// (the covariance may also shrink, a height fix; only growth is drift) [m^2].
Matrix3d frame_drift(const Matrix3d& from, const Matrix3d& to);

class RefinementEstimator {
 public:
  static constexpr double kUnmeasured = std::numeric_limits<double>::quiet_NaN();
  enum class Verdict { kAccepted, kRejected, kRestarted, kSetAside };

  explicit RefinementEstimator(const RefinementParams& params) : params_(params) {}

  /// Adds one waypoint measurement X_V,i [m], measured in a frame whose position covariance was
  /// frame_cov [m^2] (the onboard estimate's; zero on motion capture, whose frame does not drift),
  /// of a target its view measured size_m [m] (non-finite: unmeasured, taken as whole).
  /// kSetAside: kept, but its size shows a view of part of the target; no change is judged by it
  /// (eqs. 8-9 wait for the next whole waypoint).
  Verdict add(const Vector3d& X_W, const Matrix3d& frame_cov = Matrix3d::Zero(),
              const Vector2d& size_m = Vector2d::Constant(kUnmeasured));
  void reset();

  /// The waypoints the estimate is formed from: whole views, within the gate.
  int n() const { return static_cast<int>(samples_.size()); }
  int n_rejected() const { return n_rejected_; }
  /// Waypoints kept but set aside as views of part of the target.
  int n_set_aside() const { return static_cast<int>(views_.size()) - n(); }
  /// X^_n, the sample mean (zero when n = 0).
  Vector3d mean() const;
  /// Sample covariance (divisor n - 1; zero when n < 2).
  Matrix3d covariance() const;
  /// Where the target lies in the frame now, with its covariance: the filter over the waypoints
  /// with the frame's drift between them; x = mean() and P = R / n when the frame did not drift
  /// (zero when n = 0).
  TargetFilter filter() const;
  /// The waypoints' own noise R [m^2]: half the spread of consecutive differences, less the drift
  /// between them, never below the gate's floor (nor below it when n < 2).
  Matrix3d waypoint_noise() const;
  /// Eqs. 7-9 on the change of the mean caused by the last accepted waypoint.
  bool converged() const;
  /// X^_n - X^_n-1 of the last accepted waypoint.
  const Vector3d& last_change() const { return last_change_; }
  /// Squared Mahalanobis distance of X from the accepted waypoints (gate statistic).
  double mahalanobis2(const Vector3d& X_W) const;
  const std::vector<Vector3d>& samples() const { return samples_; }

 private:
  struct View {
    Vector3d X_W;
    Matrix3d frame_cov;
    Vector2d size_m;
  };
  static Vector3d mean_of(const std::vector<Vector3d>& s, int skip);
  static Matrix3d cov_of(const std::vector<Vector3d>& s, const Vector3d& mu, int skip);
  /// Whether a view that measured size_m saw the whole of a target of size target_m: its centre
  /// no more than the gate's floor sigma off for what it missed (unmeasured: whole).
  bool whole(const Vector2d& size_m, const Vector2d& target_m) const;
  /// The componentwise median of the kept views' measured sizes and with_size_m (non-finite
  /// ones left out; non-finite when none is measured).
  Vector2d target_size_m(const Vector2d& with_size_m) const;
  /// Rebuilds whole_, samples_ and frame_covs_ from views_ against the target's size now.
  void sort_views();
  void prune_outliers();

  RefinementParams params_;
  std::vector<View> views_;           // every waypoint kept, whole or set aside, in order
  std::vector<int> whole_;            // views_' indices of the whole ones, in order
  std::vector<Vector3d> samples_;     // their positions ...
  std::vector<Matrix3d> frame_covs_;  // ... and the frame's position covariance at each
  int n_rejected_ = 0;
  int consecutive_rejections_ = 0;
  bool have_change_ = false;
  Vector3d last_change_ = Vector3d::Zero();
};

/// The final estimate carried through the approach in a drifting frame (no motion capture): the
/// frame goes on drifting while the vehicle flies over the target and descends, so the filter of
/// the refinement goes on too, on waypoints formed as in the refinement (the median of the found
/// targets over a dwell), predicted by the frame's drift, each gated by its innovation's squared
/// Mahalanobis distance (gate_chi2). Contract: add() only targets vision found and autonomy's
/// disagreement gate passed; the estimate moves only by what the waypoints and the stated drift
/// explain.
class ApproachAnchor {
 public:
  ApproachAnchor(const TargetFilter& start, const Matrix3d& R, const Matrix3d& frame_cov,
                 double dwell_s, double gate_chi2);

  /// One found target at utime [us] in the frame whose position covariance is frame_cov; slack_m
  /// is how far a view that measured the target smaller than the refinement did may have put its
  /// centre off (partial_view_slack_m). Low over a top, vision finds parts of it: a view whose
  /// slack exceeds the waypoints' own horizontal noise is not taken. Returns the new estimate
  /// when the target closed a dwell whose waypoint passed the gate.
  std::optional<Vector3d> add(const Vector3d& p_W, double slack_m, int64_t utime,
                              const Matrix3d& frame_cov);

  const TargetFilter& filter() const { return f_; }
  int n_updates() const { return n_updates_; }
  int n_refused() const { return n_refused_; }
  int n_partial() const { return n_partial_; }

 private:
  TargetFilter f_;
  Matrix3d R_;
  double noise_h_m_;    // R's largest horizontal standard deviation: a partial view's bound
  Matrix3d frame_cov_;  // at the last update
  double dwell_s_;
  double gate_chi2_;
  std::vector<Vector3d> window_;
  int64_t window_start_utime_ = 0;
  int n_updates_ = 0;
  int n_refused_ = 0;
  int n_partial_ = 0;
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
