#include "autonomy/refinement.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cassert>

#include "common/median.hpp"

namespace alight::autonomy {

Vector3d RefinementEstimator::mean_of(const std::vector<Vector3d>& s, int skip) {
  Vector3d sum = Vector3d::Zero();
  int n = 0;
  for (int i = 0; i < static_cast<int>(s.size()); ++i) {
    if (i == skip) continue;
    sum += s[i];
    ++n;
  }
  return n > 0 ? Vector3d(sum / n) : Vector3d::Zero();
}

Matrix3d RefinementEstimator::cov_of(const std::vector<Vector3d>& s, const Vector3d& mu, int skip) {
  Matrix3d C = Matrix3d::Zero();
  int n = 0;
  for (int i = 0; i < static_cast<int>(s.size()); ++i) {
    if (i == skip) continue;
    const Vector3d d = s[i] - mu;
    C += d * d.transpose();
    ++n;
  }
  return n > 1 ? Matrix3d(C / (n - 1)) : Matrix3d::Zero();
}

Vector3d RefinementEstimator::mean() const { return mean_of(samples_, -1); }
Matrix3d RefinementEstimator::covariance() const { return cov_of(samples_, mean(), -1); }

double RefinementEstimator::mahalanobis2(const Vector3d& X_W) const {
  const Vector3d mu = mean();
  const Matrix3d S =
      covariance() + params_.gate_floor_sigma_m * params_.gate_floor_sigma_m * Matrix3d::Identity();
  const Vector3d d = X_W - mu;
  return d.dot(S.ldlt().solve(d));
}

void RefinementEstimator::reset() {
  views_.clear();
  whole_.clear();
  samples_.clear();
  frame_covs_.clear();
  consecutive_rejections_ = 0;
  have_change_ = false;
  last_change_.setZero();
}

void RefinementEstimator::prune_outliers() {
  const double floor2 = params_.gate_floor_sigma_m * params_.gate_floor_sigma_m;
  while (n() > params_.gate_min_n) {
    int worst = -1;
    double worst_d2 = params_.gate_chi2;
    for (int i = 0; i < n(); ++i) {
      const Vector3d mu = mean_of(samples_, i);
      const Matrix3d S = cov_of(samples_, mu, i) + floor2 * Matrix3d::Identity();
      const Vector3d d = samples_[i] - mu;
      const double d2 = d.dot(S.ldlt().solve(d));
      if (d2 > worst_d2) {
        worst_d2 = d2;
        worst = i;
      }
    }
    if (worst < 0) return;
    views_.erase(views_.begin() + whole_[worst]);
    sort_views();  // one size fewer: the target's may move
    ++n_rejected_;
  }
}

Vector2d RefinementEstimator::target_size_m(const Vector2d& with_size_m) const {
  std::vector<Vector2d> sizes;
  for (const View& v : views_)
    if (v.size_m.allFinite()) sizes.push_back(v.size_m);
  if (with_size_m.allFinite()) sizes.push_back(with_size_m);
  return sizes.empty() ? Vector2d::Constant(kUnmeasured) : componentwise_median_2d(sizes);
}

bool RefinementEstimator::whole(const Vector2d& size_m, const Vector2d& target_m) const {
  return partial_view_slack_m(target_m, size_m) <= params_.gate_floor_sigma_m;
}

void RefinementEstimator::sort_views() {
  const Vector2d target = target_size_m(Vector2d::Constant(kUnmeasured));
  whole_.clear();
  samples_.clear();
  frame_covs_.clear();
  for (int i = 0; i < static_cast<int>(views_.size()); ++i) {
    if (!whole(views_[i].size_m, target)) continue;
    whole_.push_back(i);
    samples_.push_back(views_[i].X_W);
    frame_covs_.push_back(views_[i].frame_cov);
  }
}

RefinementEstimator::Verdict RefinementEstimator::add(const Vector3d& X_W,
                                                      const Matrix3d& frame_cov,
                                                      const Vector2d& size_m) {
  assert(X_W.allFinite() && frame_cov.allFinite());
  if (!whole(size_m, target_size_m(size_m))) {
    views_.push_back({X_W, frame_cov, size_m});
    sort_views();
    have_change_ = false;
    return Verdict::kSetAside;
  }
  if (n() >= params_.gate_min_n && mahalanobis2(X_W) > params_.gate_chi2) {
    ++n_rejected_;
    if (++consecutive_rejections_ < params_.max_consecutive_rejections) return Verdict::kRejected;
    reset();
    views_.push_back({X_W, frame_cov, size_m});
    sort_views();
    return Verdict::kRestarted;
  }
  consecutive_rejections_ = 0;
  const Vector3d before = mean();
  const bool had = n() > 0;
  views_.push_back({X_W, frame_cov, size_m});
  sort_views();
  if (n() > params_.gate_min_n) prune_outliers();
  last_change_ = mean() - before;
  have_change_ = had;
  return Verdict::kAccepted;
}

Vector3d componentwise_median(const std::vector<Vector3d>& points) {
  assert(!points.empty());
  Vector3d m;
  std::vector<double> v(points.size());
  for (int k = 0; k < 3; ++k) {
    for (size_t i = 0; i < points.size(); ++i) v[i] = points[i][k];
    m[k] = upper_median(v);
  }
  return m;
}

Vector2d componentwise_median_2d(const std::vector<Vector2d>& points) {
  assert(!points.empty());
  std::vector<Vector3d> p3;
  p3.reserve(points.size());
  for (const Vector2d& p : points) p3.emplace_back(p.x(), p.y(), 0.0);
  return componentwise_median(p3).head<2>();
}

double partial_view_slack_m(const Vector2d& whole_m, const Vector2d& measured_m) {
  if (!whole_m.allFinite() || !measured_m.allFinite()) return 0.0;
  return 0.5 * (whole_m - measured_m).cwiseMax(0.0).norm();
}

namespace {

// The symmetric S (its lower triangle) with every eigenvalue raised to at least floor.
Matrix3d eigenvalues_at_least(const Matrix3d& S, double floor) {
  const Eigen::SelfAdjointEigenSolver<Matrix3d> es(S);
  const Vector3d lambda = es.eigenvalues().cwiseMax(floor);
  return es.eigenvectors() * lambda.asDiagonal() * es.eigenvectors().transpose();
}

// The Kalman update of f (P already predicted) by z with noise R.
void kalman_update(TargetFilter& f, const Vector3d& z, const Matrix3d& R) {
  const Matrix3d K = (f.P + R).ldlt().solve(f.P.transpose()).transpose();  // P (P + R)^-1
  f.x += K * (z - f.x);
  f.P = (Matrix3d::Identity() - K) * f.P;
  f.P = 0.5 * (f.P + f.P.transpose());
}

}  // namespace

Matrix3d frame_drift(const Matrix3d& from, const Matrix3d& to) {
  return eigenvalues_at_least(0.5 * ((to - from) + (to - from).transpose()), 0.0);
}

Matrix3d RefinementEstimator::waypoint_noise() const {
  const double floor2 = params_.gate_floor_sigma_m * params_.gate_floor_sigma_m;
  Matrix3d R = Matrix3d::Zero();
  for (int k = 1; k < n(); ++k) {
    const Vector3d d = samples_[k] - samples_[k - 1];
    R += d * d.transpose() - frame_drift(frame_covs_[k - 1], frame_covs_[k]);
  }
  if (n() > 1) R /= 2.0 * (n() - 1);
  return eigenvalues_at_least(R, floor2);
}

TargetFilter RefinementEstimator::filter() const {
  if (n() == 0) return {};
  std::vector<Matrix3d> drifts(n(), Matrix3d::Zero());  // drifts[k]: from sample k - 1 to k
  bool drifted = false;
  for (int k = 1; k < n(); ++k) {
    drifts[k] = frame_drift(frame_covs_[k - 1], frame_covs_[k]);
    drifted |= !drifts[k].isZero(0.0);
  }
  const Matrix3d R = waypoint_noise();
  if (!drifted) return {mean(), R / n()};  // the paper's estimate, bit for bit
  TargetFilter f{samples_[0], R};
  for (int k = 1; k < n(); ++k) {
    f.P += drifts[k];
    kalman_update(f, samples_[k], R);
  }
  // The drift after the last waypoint would widen P but cannot move x (the walk has zero mean).
  return f;
}

ApproachAnchor::ApproachAnchor(const TargetFilter& start, const Matrix3d& R,
                               const Matrix3d& frame_cov, double dwell_s, double gate_chi2)
    : f_(start),
      R_(R),
      noise_h_m_(std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(R.topLeftCorner<2, 2>())
                               .eigenvalues()
                               .maxCoeff())),
      frame_cov_(frame_cov),
      dwell_s_(dwell_s),
      gate_chi2_(gate_chi2) {}

std::optional<Vector3d> ApproachAnchor::add(const Vector3d& p_W, double slack_m, int64_t utime,
                                            const Matrix3d& frame_cov) {
  assert(p_W.allFinite() && frame_cov.allFinite());
  if (!(slack_m <= noise_h_m_)) {
    ++n_partial_;
    return std::nullopt;
  }
  if (window_.empty()) window_start_utime_ = utime;
  window_.push_back(p_W);
  if (static_cast<double>(utime - window_start_utime_) * 1e-6 < dwell_s_) return std::nullopt;
  const Vector3d z = componentwise_median(window_);  // the dwell's waypoint, as a vantage's
  window_.clear();
  const Matrix3d P = f_.P + frame_drift(frame_cov_, frame_cov);
  const Vector3d nu = z - f_.x;
  if (nu.dot((P + R_).ldlt().solve(nu)) > gate_chi2_) {
    ++n_refused_;
    return std::nullopt;
  }
  f_.P = P;
  kalman_update(f_, z, R_);
  frame_cov_ = frame_cov;
  ++n_updates_;
  return f_.x;
}

bool RefinementEstimator::converged() const {
  return have_change_ && n() >= params_.n_min &&                 // eq. 7
         last_change_.head<2>().norm() <= params_.eps_horz_m &&  // eq. 8
         std::abs(last_change_.z()) <= params_.eps_vert_m;       // eq. 9
}

Vector2d VantageSampler::draw(const Vector2d& mu_2, const Eigen::Matrix2d& Sigma_2, int n) {
  const double floor2 = params_.vantage_sigma_floor_m * params_.vantage_sigma_floor_m;
  const double prior2 = params_.prior_sigma_m * params_.prior_sigma_m;
  const Eigen::Matrix2d S =
      (n < 2 ? Eigen::Matrix2d(prior2 * Eigen::Matrix2d::Identity()) : Sigma_2) +
      floor2 * Eigen::Matrix2d::Identity();
  const Eigen::Matrix2d L = S.llt().matrixL();
  for (int attempt = 0; attempt < 100; ++attempt) {
    const Vector2d z(normal_(rng_), normal_(rng_));
    const Vector2d x = mu_2 + L * z;
    if ((x - mu_2).norm() <= params_.cutoff_m) return x;
  }
  return mu_2;  // only reachable with a cutoff far inside the distribution
}

}  // namespace alight::autonomy
