#include "estimator/flow_odometry.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <random>

#include "common/median.hpp"
#include "common/robust_lsq.hpp"

namespace alight::estimator {

using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;

static_assert(static_cast<int>(FlowReason::kPlaneNotInView) + 1 == kNumFlowReasons,
              "kNumFlowReasons counts every FlowReason");

const char* to_string(FlowReason r) {
  switch (r) {
    case FlowReason::kOk:
      return "ok";
    case FlowReason::kNoPrevious:
      return "no previous frame";
    case FlowReason::kBadImage:
      return "bad image";
    case FlowReason::kBadTime:
      return "stamp not after the previous frame's";
    case FlowReason::kTimeGap:
      return "frames too far apart";
    case FlowReason::kBadRotation:
      return "rotation not finite or not a rotation";
    case FlowReason::kBadNormal:
      return "normal not finite or not unit";
    case FlowReason::kTooFewTracks:
      return "too few tracks";
    case FlowReason::kTooFewInliers:
      return "too few inliers";
    case FlowReason::kDegenerate:
      return "degenerate geometry";
    case FlowReason::kPlaneNotInView:
      return "plane not in view";
  }
  return "?";
}

namespace {

// A correspondence in the model's terms: x1 = (x, y, 1) in C1, the observed x2 (normalised) in
// C2, and a = n^T x1 < 0, so that the floor point's image in C2 is along R (x1 + a u).
struct Corr {
  Vector3d x1;
  Vector2d x2;
  double a;
};

// Reprojection in image 2 [normalised units] and d pred / d y at y = R (x1 + a u).
struct Reprojection {
  Vector2d pred;
  Eigen::Matrix<double, 2, 3> dpred_dy;
  Vector3d q;  // x1 + a u
  bool valid;
};

Reprojection reproject(const Corr& c, const Matrix3d& R, const Vector3d& u) {
  Reprojection p;
  p.q = c.x1 + c.a * u;
  const Vector3d y = R * p.q;
  // A floor point stays in front of camera 2 (positive depth); the model fails otherwise.
  p.valid = y.z() > 1e-9 && y.allFinite();
  if (!p.valid) return p;
  const double iz = 1.0 / y.z();
  p.pred = Vector2d(y.x() * iz, y.y() * iz);
  p.dpred_dy << iz, 0, -p.pred.x() * iz, 0, iz, -p.pred.y() * iz;
  return p;
}

// Squared reprojection error [normalised units^2]; infinite where the model fails.
double error2(const Corr& c, const Matrix3d& R, const Vector3d& u) {
  const Reprojection p = reproject(c, R, u);
  if (!p.valid) return std::numeric_limits<double>::infinity();
  return (p.pred - c.x2).squaredNorm();
}

// Least squares of the cross-multiplied equations (x2 e3 - e1)^T R (x1 + a u) = 0 and
// (y2 e3 - e2)^T R (x1 + a u) = 0 over `idx`; nullopt when they do not fix u.
std::optional<Vector3d> linear_solve(const std::vector<Corr>& cs, const int* idx, int n,
                                     const Matrix3d& R) {
  Matrix3d M = Matrix3d::Zero();
  Vector3d b = Vector3d::Zero();
  const Matrix3d Rt = R.transpose();
  for (int k = 0; k < n; ++k) {
    const Corr& c = cs[static_cast<size_t>(idx[k])];
    const Vector3d g1 = Rt * Vector3d(-1, 0, c.x2.x());
    const Vector3d g2 = Rt * Vector3d(0, -1, c.x2.y());
    M.noalias() += c.a * c.a * (g1 * g1.transpose() + g2 * g2.transpose());
    b -= c.a * (g1.dot(c.x1) * g1 + g2.dot(c.x1) * g2);
  }
  Eigen::SelfAdjointEigenSolver<Matrix3d> eig;
  eig.computeDirect(M);
  const Vector3d ev = eig.eigenvalues();
  if (!(ev(0) > 1e-12 * ev(2)) || !(ev(2) > 0)) return std::nullopt;
  const Vector3d u = eig.eigenvectors() * (eig.eigenvectors().transpose() * b).cwiseQuotient(ev);
  if (!u.allFinite()) return std::nullopt;
  return u;
}

// Standard deviation per axis of a 2-D Gaussian whose residuals, kept only within radius T, show
// a standard deviation of sigma_kept: E[r^2 | r < T] = 2 sigma^2 (1 - tau e^-tau / (1 - e^-tau)),
// tau = T^2 / (2 sigma^2), solved by fixed-point iteration. The inlier threshold cuts the tails
// of the noise; without this the covariance is too small once the noise nears the threshold.
double untruncated_sigma(double sigma_kept, double T) {
  if (!(sigma_kept > 0) || !(T > 0)) return sigma_kept;
  double s = sigma_kept;
  for (int i = 0; i < 30; ++i) {
    const double tau = T * T / (2 * s * s);
    if (tau > 50) break;  // no truncation to speak of
    const double kappa = 1.0 - tau * std::exp(-tau) / -std::expm1(-tau);
    const double next = std::min(3.0 * sigma_kept, sigma_kept / std::sqrt(kappa));
    if (std::abs(next - s) < 1e-6 * s) return next;
    s = next;
  }
  return s;
}

// Robust scale of 2-D residual lengths: the median length of a 2-D Gaussian is 1.1774 sigma.
double robust_sigma(const std::vector<double>& lengths, double min_sigma) {
  return lengths.empty() ? min_sigma : std::max(min_sigma, upper_median(lengths) / 1.1774);
}

// Levenberg-Marquardt with Huber weights over `idx`, from u (moved in place). Residuals in pixels
// (normalised units times the focal length), so that the loss's scale is in pixels.
void refine(const std::vector<Corr>& cs, const std::vector<int>& idx, const Matrix3d& R, double f,
            const FlowFitParams& params, Vector3d& u) {
  const int m = static_cast<int>(idx.size());
  const double min_sigma = params.min_sigma_px;
  lsq::Problem problem;
  problem.num_parameters = 3;
  problem.residuals = [&](const Eigen::VectorXd& dx, Eigen::VectorXd& r) {
    r.resize(2 * m);
    const Vector3d v = u + dx.head<3>();
    for (int k = 0; k < m; ++k) {
      const Corr& c = cs[static_cast<size_t>(idx[static_cast<size_t>(k)])];
      const Reprojection p = reproject(c, R, v);
      if (!p.valid) {
        r.segment<2>(2 * k).setConstant(std::numeric_limits<double>::quiet_NaN());
        continue;
      }
      r.segment<2>(2 * k) = f * (p.pred - c.x2);
    }
  };
  problem.jacobian = [&](const Eigen::VectorXd&, Eigen::MatrixXd& J) {
    J.resize(2 * m, 3);
    for (int k = 0; k < m; ++k) {
      const Corr& c = cs[static_cast<size_t>(idx[static_cast<size_t>(k)])];
      const Reprojection p = reproject(c, R, u);
      J.block<2, 3>(2 * k, 0) = p.valid ? Eigen::Matrix<double, 2, 3>(f * c.a * p.dpred_dy * R)
                                        : Eigen::Matrix<double, 2, 3>::Zero();
    }
  };
  problem.accept = [&](const Eigen::VectorXd& dx) { u += dx.head<3>(); };
  problem.weights = [&](const Eigen::VectorXd& r, Eigen::VectorXd& w) {
    std::vector<double> e(static_cast<size_t>(m));
    for (int k = 0; k < m; ++k) e[static_cast<size_t>(k)] = r.segment<2>(2 * k).norm();
    const double k_huber = params.huber_k * robust_sigma(e, min_sigma);
    w.resize(2 * m);
    for (int k = 0; k < m; ++k) {
      const double ek = e[static_cast<size_t>(k)];
      w.segment<2>(2 * k).setConstant(ek <= k_huber ? 1.0 : k_huber / ek);
    }
  };
  lsq::Options options;
  options.max_iterations = params.refine_iterations;
  options.relative_decrease = 1e-12;
  lsq::solve(problem, options);
}

}  // namespace

FlowFit fit_t_over_d(const std::vector<Vector3d>& rays_1, const std::vector<Vector3d>& rays_2,
                     const Matrix3d& R, const Vector3d& n_C1, double focal_px,
                     const FlowFitParams& params) {
  FlowFit fit;
  const size_t n_all = std::min(rays_1.size(), rays_2.size());
  if (!R.allFinite() || !is_rotation(R, 1e-6)) {
    fit.reason = FlowReason::kBadRotation;
    return fit;
  }
  if (!n_C1.allFinite() || std::abs(n_C1.norm() - 1.0) > 1e-3) {
    fit.reason = FlowReason::kBadNormal;
    return fit;
  }
  assert(std::isfinite(focal_px) && focal_px > 0);
  const Vector3d n = n_C1.normalized();
  const double f = focal_px;

  // Usable correspondences: finite rays in front of both cameras whose first ray meets the
  // plane at a useful incidence (a = n^T x1 < 0: the ray goes towards the floor).
  std::vector<Corr> cs;
  std::vector<int> index_of;  // cs -> input index
  cs.reserve(n_all);
  int finite = 0;
  for (size_t i = 0; i < n_all; ++i) {
    const Vector3d& r1 = rays_1[i];
    const Vector3d& r2 = rays_2[i];
    if (!r1.allFinite() || !r2.allFinite() || !(r1.z() > 0) || !(r2.z() > 0)) continue;
    ++finite;
    const Vector3d x1 = r1 / r1.z();
    const double a = n.dot(x1);
    if (-a < params.min_incidence_cos * x1.norm()) continue;
    cs.push_back({x1, r2.head<2>() / r2.z(), a});
    index_of.push_back(static_cast<int>(i));
  }
  fit.usable = static_cast<int>(cs.size());
  if (fit.usable < params.min_inliers) {
    fit.reason =
        finite >= params.min_inliers ? FlowReason::kPlaneNotInView : FlowReason::kTooFewTracks;
    return fit;
  }

  // RANSAC over 2-point samples, MSAC cost (errors in normalised units squared).
  const double thr2 = std::pow(params.inlier_threshold_px / f, 2);
  const double min_sep2 = std::pow(params.min_sample_separation_px / f, 2);
  const int nc = fit.usable;
  std::mt19937_64 rng(params.seed);
  std::uniform_int_distribution<int> pick(0, nc - 1);
  double best_cost = std::numeric_limits<double>::infinity();
  int best_count = 0;
  Vector3d best_u = Vector3d::Zero();
  bool have_best = false;
  const double log_fail = std::log(1.0 - params.ransac_confidence);
  int needed = params.ransac_max_iterations;
  auto score = [&](const Vector3d& u, int& count) {
    double cost = 0.0;
    count = 0;
    for (const Corr& c : cs) {
      const double e2 = error2(c, R, u);
      if (e2 < thr2) {
        cost += e2;
        ++count;
      } else {
        cost += thr2;
      }
    }
    return cost;
  };
  std::vector<int> lo_idx;
  for (int it = 0; it < needed && it < params.ransac_max_iterations; ++it) {
    ++fit.ransac_samples;
    int idx[2] = {pick(rng), pick(rng)};
    if (idx[0] == idx[1]) continue;
    const Corr& c0 = cs[static_cast<size_t>(idx[0])];
    const Corr& c1 = cs[static_cast<size_t>(idx[1])];
    if ((c0.x1 - c1.x1).squaredNorm() < min_sep2) continue;
    const auto u = linear_solve(cs, idx, 2, R);
    if (!u) continue;
    int count = 0;
    const double cost = score(*u, count);
    if (!(cost < best_cost)) continue;
    best_cost = cost;
    best_count = count;
    best_u = *u;
    have_best = true;
    // Local optimisation (Chum, Matas & Kittler 2003, LO-RANSAC): two points fix the vertical
    // part of t/d poorly, so a new best is refitted on all its inliers while that scores better.
    for (int lo = 0; lo < 3 && best_count >= 3; ++lo) {
      lo_idx.clear();
      for (int k = 0; k < nc; ++k)
        if (error2(cs[static_cast<size_t>(k)], R, best_u) < thr2) lo_idx.push_back(k);
      const auto v = linear_solve(cs, lo_idx.data(), static_cast<int>(lo_idx.size()), R);
      if (!v) break;
      int lo_count = 0;
      const double lo_cost = score(*v, lo_count);
      if (!(lo_cost < best_cost)) break;
      best_cost = lo_cost;
      best_count = lo_count;
      best_u = *v;
    }
    // Samples needed for an all-inlier one with the confidence asked, at this inlier ratio.
    const double w = static_cast<double>(best_count) / nc;
    const double p_fail = 1.0 - w * w;
    if (p_fail <= 0.0) break;
    if (p_fail < 1.0) {
      const double n_needed = std::ceil(log_fail / std::log(p_fail));
      if (n_needed < needed) needed = static_cast<int>(std::max(1.0, n_needed));
    }
  }
  const int min_count =
      std::max(params.min_inliers, static_cast<int>(std::ceil(params.min_inlier_fraction * nc)));
  if (!have_best) {
    fit.reason = FlowReason::kDegenerate;
    return fit;
  }
  if (best_count < min_count) {
    fit.reason = FlowReason::kTooFewInliers;
    return fit;
  }

  // Robust refinement on the inliers; inliers chosen again at the refined u, refined again when
  // they changed (at most three rounds).
  Vector3d u = best_u;
  std::vector<int> inl;
  auto select = [&](std::vector<int>& out) {
    out.clear();
    for (int k = 0; k < nc; ++k)
      if (error2(cs[static_cast<size_t>(k)], R, u) < thr2) out.push_back(k);
  };
  select(inl);
  for (int round = 0; round < 3; ++round) {
    if (static_cast<int>(inl.size()) < min_count) break;
    refine(cs, inl, R, f, params, u);
    std::vector<int> again;
    select(again);
    const bool same = again == inl;
    inl.swap(again);
    if (same) break;
  }
  if (!u.allFinite()) {
    fit.reason = FlowReason::kDegenerate;
    return fit;
  }
  const int m = static_cast<int>(inl.size());
  if (m < min_count) {
    fit.reason = FlowReason::kTooFewInliers;
    return fit;
  }

  // Covariance and sensitivities of the M-estimate, which solves sum_i Ju_i^T psi(r_i) = 0 with
  // Huber's psi(r) = r min(1, k / |r|) on the 2-D residual (Huber, "Robust Statistics", 1981,
  // sec. 7.6): cov = E|psi|^2 / E[psi']^2 (Ju^T Ju)^-1, psi' the derivative per axis; the plain
  // sigma^2 (J^T W J)^-1 of the last reweighted step is a third too small under Gaussian noise.
  // Sensitivities by the implicit function theorem on the same equation: du = -H^-1 B dtheta,
  // H = sum Ju^T psi'(r) Ju, B = sum Ju^T psi'(r) Jtheta.
  std::vector<double> e(static_cast<size_t>(m));
  std::vector<Eigen::Matrix<double, 2, 3>> Ju(static_cast<size_t>(m)), Jt(Ju.size()), Jn(Ju.size());
  std::vector<Vector2d> r(Ju.size());
  const Matrix3d P_n = Matrix3d::Identity() - n * n.transpose();
  for (int k = 0; k < m; ++k) {
    const auto kk = static_cast<size_t>(k);
    const Corr& c = cs[static_cast<size_t>(inl[kk])];
    const Reprojection p = reproject(c, R, u);
    assert(p.valid);  // an inlier has a finite error
    r[kk] = f * (p.pred - c.x2);
    e[kk] = r[kk].norm();
    const Eigen::Matrix<double, 2, 3> D = f * p.dpred_dy * R;
    Ju[kk] = c.a * D;
    Jt[kk] = -D * skew(p.q);                    // R Exp(theta) q = R q - R [q]x theta
    Jn[kk] = D * u * (c.x1.transpose() * P_n);  // a = n^T x1, n moved in its tangent plane
  }
  const double k_huber = params.huber_k * robust_sigma(e, params.min_sigma_px);
  Matrix3d JtJ = Matrix3d::Zero(), H = Matrix3d::Zero(), Bt = Matrix3d::Zero(),
           Bn = Matrix3d::Zero();
  double psi2 = 0.0, dpsi = 0.0, r2 = 0.0;
  for (size_t k = 0; k < e.size(); ++k) {
    Eigen::Matrix2d dpsi_dr = Eigen::Matrix2d::Identity();
    if (e[k] > k_huber) {
      const Vector2d rh = r[k] / e[k];
      dpsi_dr = k_huber / e[k] * (Eigen::Matrix2d::Identity() - rh * rh.transpose());
      psi2 += k_huber * k_huber;
    } else {
      psi2 += e[k] * e[k];
    }
    dpsi += 0.5 * dpsi_dr.trace();
    JtJ.noalias() += Ju[k].transpose() * Ju[k];
    H.noalias() += Ju[k].transpose() * dpsi_dr * Ju[k];
    Bt.noalias() += Ju[k].transpose() * dpsi_dr * Jt[k];
    Bn.noalias() += Ju[k].transpose() * dpsi_dr * Jn[k];
    r2 += e[k] * e[k];
  }
  Eigen::SelfAdjointEigenSolver<Matrix3d> eig;
  eig.computeDirect(JtJ);
  const Vector3d ev = eig.eigenvalues();
  fit.condition = ev(0) > 0 ? ev(2) / ev(0) : std::numeric_limits<double>::infinity();
  const Eigen::LDLT<Matrix3d> H_ldlt(H);
  if (!(fit.condition <= params.max_condition) || H_ldlt.info() != Eigen::Success || !(dpsi > 0)) {
    fit.reason = FlowReason::kDegenerate;
    return fit;
  }
  const Matrix3d JtJ_inv =
      eig.eigenvectors() * ev.cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
  const double dof = std::max(1, 2 * m - 3);
  const double mean_dpsi = dpsi / m;
  const double sigma_kept = std::sqrt(r2 / dof);
  const double truncation =
      untruncated_sigma(sigma_kept, params.inlier_threshold_px) / std::max(sigma_kept, 1e-300);
  fit.sigma_px = std::max(params.min_sigma_px, truncation * std::sqrt(psi2 / dof) / mean_dpsi);
  fit.t_over_d_C1 = u;
  const double correlated = std::max(1.0, static_cast<double>(m) / params.max_independent_points);
  fit.cov = correlated * fit.sigma_px * fit.sigma_px * JtJ_inv;
  fit.cov = 0.5 * (fit.cov + fit.cov.transpose()).eval();
  fit.J_rotation = -H_ldlt.solve(Bt);
  fit.J_normal = -H_ldlt.solve(Bn);
  fit.residual_rms_px = std::sqrt(r2 / m);
  fit.inliers = m;
  fit.inlier.assign(n_all, 0);
  for (int k : inl) fit.inlier[static_cast<size_t>(index_of[static_cast<size_t>(k)])] = 1;
  fit.reason = FlowReason::kOk;
  return fit;
}

std::optional<Vector2d> predict_pixel(const CameraModel& camera, const Vector3d& ray_1,
                                      const Matrix3d& R_C2C1, const Vector3d& n_C1,
                                      const Vector3d& t_over_d_C1) {
  if (!(ray_1.z() > 0)) return std::nullopt;
  const Vector3d x1 = ray_1 / ray_1.z();
  return camera.project(R_C2C1 * (x1 + n_C1.dot(x1) * t_over_d_C1));
}

// --- Front end ---------------------------------------------------------------------------------

std::optional<FlowMotion> second_motion(const std::vector<Vector3d>& rays_1,
                                        const std::vector<Vector3d>& rays_2,
                                        const std::vector<uint8_t>& inlier, const Matrix3d& R_C2C1,
                                        const Vector3d& n_C1, double focal_px,
                                        const FlowFitParams& params,
                                        std::vector<uint8_t>* second_inlier) {
  assert(rays_1.size() == rays_2.size() && inlier.size() == rays_1.size());
  if (second_inlier) second_inlier->assign(rays_1.size(), 0);
  std::vector<Vector3d> out_1, out_2;
  std::vector<size_t> from;  // each left-out correspondence's index among all
  for (size_t k = 0; k < rays_1.size(); ++k)
    if (!inlier[k]) out_1.push_back(rays_1[k]), out_2.push_back(rays_2[k]), from.push_back(k);
  if (static_cast<int>(out_1.size()) < params.min_inliers) return std::nullopt;
  const FlowFit fit = fit_t_over_d(out_1, out_2, R_C2C1, n_C1, focal_px, params);
  if (fit.reason != FlowReason::kOk) return std::nullopt;
  if (second_inlier)
    for (size_t j = 0; j < from.size(); ++j) (*second_inlier)[from[j]] = fit.inlier[j];
  FlowMotion m;
  m.t_over_d_C1 = fit.t_over_d_C1;
  m.cov = fit.cov;
  m.inliers = fit.inliers;
  m.J_rotation = fit.J_rotation;
  m.J_normal = fit.J_normal;
  return m;
}

FlowOdometry::FlowOdometry(const FlowFrontParams& params, const CameraModel& camera)
    : params_(params), camera_(camera) {
  params_.validate();
  camera_.validate();
  const auto& t = params_.track;
  level_scale_ = static_cast<double>(1 << t.downsample);
  level_size_ = cv::Size(camera_.width, camera_.height);
  for (int i = 0; i < t.downsample; ++i)
    level_size_ = cv::Size((level_size_.width + 1) / 2, (level_size_.height + 1) / 2);
  window_ = cv::Size(t.window_px, t.window_px);
  lk_criteria_ = cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, t.lk_iterations,
                                  t.lk_epsilon);
}

void FlowOdometry::reset() {
  have_previous_ = false;
  previous_pyramid_.clear();
  points_.clear();
  rays_.clear();
  last_t_over_d_.reset();
  last_dt_s_ = 0.0;
}

std::vector<Vector2d> FlowOdometry::feature_pixels() const {
  std::vector<Vector2d> out;
  out.reserve(points_.size());
  for (const auto& p : points_) out.emplace_back(p.x * level_scale_, p.y * level_scale_);
  return out;
}

std::optional<double> gain_compensation(double previous_mean, double current_mean) {
  if (!(previous_mean >= kMinMeanForGain && current_mean >= kMinMeanForGain)) return std::nullopt;
  const double scale = previous_mean / current_mean;
  if (std::abs(scale - 1.0) <= kGainTolerance) return std::nullopt;
  return scale;
}

FlowResult FlowOdometry::finish(FlowResult r) {
  ++counts_[static_cast<size_t>(r.reason)];
  r.features = static_cast<int>(points_.size());
  return r;
}

int FlowOdometry::cell_of(const cv::Point2f& p) const {
  const auto& t = params_.track;
  const int cx =
      std::clamp(static_cast<int>(p.x * t.grid_cols / level_size_.width), 0, t.grid_cols - 1);
  const int cy =
      std::clamp(static_cast<int>(p.y * t.grid_rows / level_size_.height), 0, t.grid_rows - 1);
  return cy * t.grid_cols + cx;
}

std::vector<int> FlowOdometry::tracks_per_cell() const {
  std::vector<int> in_cell(static_cast<size_t>(params_.track.grid_cols * params_.track.grid_rows));
  for (const auto& p : points_) ++in_cell[static_cast<size_t>(cell_of(p))];
  return in_cell;
}

cv::Rect FlowOdometry::empty_cells_box(const std::vector<int>& in_cell) const {
  const auto& t = params_.track;
  cv::Rect box;
  for (int cy = 0; cy < t.grid_rows; ++cy)
    for (int cx = 0; cx < t.grid_cols; ++cx) {
      if (in_cell[static_cast<size_t>(cy * t.grid_cols + cx)] > 0) continue;
      const int x0 = cx * level_size_.width / t.grid_cols;
      const int y0 = cy * level_size_.height / t.grid_rows;
      const cv::Rect cell(x0, y0, (cx + 1) * level_size_.width / t.grid_cols - x0,
                          (cy + 1) * level_size_.height / t.grid_rows - y0);
      box = box.area() > 0 ? (box | cell) : cell;
    }
  return box;
}

void FlowOdometry::detect(int already, FlowResult& r, const cv::Rect& region,
                          std::vector<int> in_cell) {
  const auto& t = params_.track;
  const int want = t.max_features - already;
  if (want <= 0) return;
  const cv::Mat& image = previous_pyramid_[0];  // the frame being stored (see add_frame)
  const double s = level_scale_;
  const int border = static_cast<int>(std::ceil(t.border_px / s));
  const cv::Rect inner =
      cv::Rect(border, border, level_size_.width - 2 * border, level_size_.height - 2 * border) &
      region;
  if (inner.width <= 0 || inner.height <= 0) return;
  // Only the region is searched (its corners' quality against its own strongest: a sparse
  // floor's corners are not measured against a textured top's elsewhere in the view).
  cv::Mat mask(inner.size(), CV_8U, cv::Scalar(255));
  const double min_dist = t.min_distance_px / s;
  for (const auto& p : points_)
    cv::circle(mask, cv::Point(cvRound(p.x) - inner.x, cvRound(p.y) - inner.y),
               static_cast<int>(std::ceil(min_dist)), cv::Scalar(0), cv::FILLED);
  std::vector<cv::Point2f> corners;
  std::vector<float> quality;
  cv::goodFeaturesToTrack(image(inner), corners, 4 * t.max_features, t.quality_level, min_dist,
                          mask, quality, 3, 3, false, 0.04);
  for (auto& c : corners)
    c += cv::Point2f(static_cast<float>(inner.x), static_cast<float>(inner.y));

  // Spread over the grid: first up to `cap` per cell (counting the surviving tracks), strongest
  // first, then the strongest of the rest.
  const int cells = t.grid_cols * t.grid_rows;
  const int cap = (t.max_features + cells - 1) / cells;
  std::vector<uint8_t> taken(corners.size(), 0);
  int added = 0;
  for (int pass = 0; pass < 2 && added < want; ++pass) {
    for (size_t i = 0; i < corners.size() && added < want; ++i) {
      if (taken[i] || quality[i] < t.min_quality) continue;
      const int c = cell_of(corners[i]);
      if (pass == 0 && in_cell[static_cast<size_t>(c)] >= cap) continue;
      taken[i] = 1;
      ++in_cell[static_cast<size_t>(c)];
      points_.push_back(corners[i]);
      rays_.push_back(camera_.ray(Vector2d(corners[i].x * s, corners[i].y * s)));
      ++added;
    }
  }
  r.detected = added;
}

FlowResult FlowOdometry::add_frame(const cv::Mat& gray, int64_t utime, const Matrix3d& R_C2C1,
                                   const Vector3d& n_C1) {
  FlowResult r;
  const auto& t = params_.track;
  if (gray.empty() || gray.type() != CV_8UC1 || gray.cols != camera_.width ||
      gray.rows != camera_.height) {
    reset();
    r.reason = FlowReason::kBadImage;
    return finish(r);
  }
  if (have_previous_ && utime <= previous_utime_) {
    reset();
    r.reason = FlowReason::kBadTime;
    return finish(r);
  }

  cv::Mat level = gray;
  for (int i = 0; i < t.downsample; ++i) cv::pyrDown(level, level);
  std::vector<cv::Mat> pyramid;
  // Copied (not a view of the caller's buffer), with derivatives: reused as the previous frame.
  const int max_level =
      cv::buildOpticalFlowPyramid(level, pyramid, window_, t.pyramid_levels, true,
                                  cv::BORDER_REFLECT_101, cv::BORDER_CONSTANT, false);
  const double level_mean = cv::mean(level)[0];

  const double dt_s = have_previous_ ? static_cast<double>(utime - previous_utime_) * 1e-6 : 0.0;
  const bool rotation_ok = R_C2C1.allFinite() && is_rotation(R_C2C1, 1e-6);
  const bool normal_ok = n_C1.allFinite() && std::abs(n_C1.norm() - 1.0) <= 1e-3;
  std::optional<Vector3d> t_over_d;

  if (!have_previous_) {
    r.reason = FlowReason::kNoPrevious;
    points_.clear();
    rays_.clear();
  } else if (dt_s > params_.max_gap_s) {
    r.reason = FlowReason::kTimeGap;
    points_.clear();
    rays_.clear();
  } else if (!points_.empty()) {
    // Where each feature should be: rotation, plus the last t/d scaled to this interval.
    const double s = level_scale_;
    std::vector<cv::Point2f> next(points_.size()), back(points_.size());
    Vector3d u_pred = Vector3d::Zero();
    if (last_t_over_d_ && last_dt_s_ > 0) u_pred = *last_t_over_d_ * (dt_s / last_dt_s_);
    for (size_t i = 0; i < points_.size(); ++i) {
      next[i] = points_[i];
      if (t.predict && rotation_ok && normal_ok) {
        const auto px = predict_pixel(camera_, rays_[i], R_C2C1, n_C1.normalized(), u_pred);
        if (px && px->allFinite())
          next[i] = cv::Point2f(static_cast<float>(px->x() / s), static_cast<float>(px->y() / s));
      }
    }
    // This frame as the previous one's brightness would show it (the sensor's gain step).
    std::vector<cv::Mat> matched;
    if (previous_mean_ > 0) r.gain = level_mean / previous_mean_;
    if (const auto scale = gain_compensation(previous_mean_, level_mean)) {
      cv::Mat scaled;
      level.convertTo(scaled, CV_8U, *scale);
      cv::buildOpticalFlowPyramid(scaled, matched, window_, t.pyramid_levels, true,
                                  cv::BORDER_REFLECT_101, cv::BORDER_CONSTANT, false);
    }
    const std::vector<cv::Mat>& current = matched.empty() ? pyramid : matched;
    std::vector<uint8_t> ok_fwd, ok_bwd;
    std::vector<float> err;
    cv::calcOpticalFlowPyrLK(previous_pyramid_, current, points_, next, ok_fwd, err, window_,
                             max_level, lk_criteria_, cv::OPTFLOW_USE_INITIAL_FLOW);
    // Back from where it was found, started at the same displacement the forward pass assumed.
    for (size_t i = 0; i < points_.size(); ++i) back[i] = points_[i];
    cv::calcOpticalFlowPyrLK(current, previous_pyramid_, next, back, ok_bwd, err, window_,
                             max_level, lk_criteria_, cv::OPTFLOW_USE_INITIAL_FLOW);
    const double lo = t.border_px / s;
    const double hi_x = level_size_.width - 1 - t.border_px / s;
    const double hi_y = level_size_.height - 1 - t.border_px / s;
    std::vector<cv::Point2f> kept_points;
    std::vector<Vector3d> rays_1, rays_2;
    for (size_t i = 0; i < points_.size(); ++i) {
      if (!ok_fwd[i] || !ok_bwd[i]) continue;
      const cv::Point2f& q = next[i];
      if (!(q.x >= lo && q.y >= lo && q.x <= hi_x && q.y <= hi_y)) continue;
      const double fb = std::hypot(back[i].x - points_[i].x, back[i].y - points_[i].y) * s;
      if (!(fb <= t.max_fb_error_px)) continue;
      kept_points.push_back(q);
      rays_1.push_back(rays_[i]);
      rays_2.push_back(camera_.ray(Vector2d(q.x * s, q.y * s)));
    }
    r.tracked = static_cast<int>(kept_points.size());

    std::vector<uint8_t> inlier;
    if (!rotation_ok) {
      r.reason = FlowReason::kBadRotation;
    } else if (!normal_ok) {
      r.reason = FlowReason::kBadNormal;
    } else {
      const FlowFit fit =
          fit_t_over_d(rays_1, rays_2, R_C2C1, n_C1.normalized(), camera_.fx, params_.fit);
      r.reason = fit.reason;
      if (fit.reason == FlowReason::kOk) {
        FlowSample sample;
        sample.utime_from = previous_utime_;
        sample.utime_to = utime;
        sample.t_over_d_C1 = fit.t_over_d_C1;
        sample.cov = fit.cov;
        sample.inliers = fit.inliers;
        sample.J_rotation = fit.J_rotation;
        sample.J_normal = fit.J_normal;
        sample.residual_rms_px = fit.residual_rms_px;
        std::vector<uint8_t> second_inlier;
        if (auto other = second_motion(rays_1, rays_2, fit.inlier, R_C2C1, n_C1.normalized(),
                                       camera_.fx, params_.fit, &second_inlier))
          sample.others.push_back(*other);
        r.sample = sample;
        t_over_d = fit.t_over_d_C1;
        inlier = fit.inlier;
        // The second motion's points stay tracked too: a textured platform moving under the
        // camera outnumbers the floor's points, and were they dropped with the outliers the floor
        // would be seen only in the frame after each detection, the estimate left with the
        // platform's motion.
        for (size_t k = 0; k < inlier.size(); ++k) inlier[k] |= second_inlier[k];
      }
    }
    // Badly tracked points and those of neither motion (a still box's sides) leave.
    points_.clear();
    rays_.clear();
    for (size_t k = 0; k < kept_points.size(); ++k) {
      if (!inlier.empty() && !inlier[k]) continue;
      points_.push_back(kept_points[k]);
      rays_.push_back(rays_2[k]);
    }
  } else {
    r.reason = FlowReason::kTooFewTracks;
  }

  previous_pyramid_ = std::move(pyramid);
  previous_mean_ = level_mean;
  previous_utime_ = utime;
  have_previous_ = true;
  last_t_over_d_ = t_over_d;
  last_dt_s_ = dt_s;
  const int kept = static_cast<int>(points_.size());
  const std::vector<int> in_cell = tracks_per_cell();
  const auto empty = static_cast<double>(std::count(in_cell.begin(), in_cell.end(), 0));
  if (kept < t.min_tracks)
    detect(kept, r, cv::Rect(cv::Point(0, 0), level_size_), in_cell);
  else if (empty > kMaxEmptyCellShare * static_cast<double>(in_cell.size()))
    detect(kept, r, empty_cells_box(in_cell), in_cell);
  return finish(r);
}

}  // namespace alight::estimator
