#include "estimator/flow_odometry.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <random>

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
// C2, and a = n^T x1 < 0, so that the floor point's image in C2 is along R (x1 + a u). A point on
// a line (an edge without a corner) is found again only across the line: m is the line's unit
// normal in image 2 and only the error along m counts (one equation); m is zero for a corner
// (two equations).
struct Corr {
  Vector3d x1;
  Vector2d x2;
  double a;
  Vector2d m = Vector2d::Zero();
  bool line() const { return m.x() != 0.0 || m.y() != 0.0; }
  int equations() const { return line() ? 1 : 2; }
  // The part of an image-2 error the correspondence observes.
  Vector2d observed(const Vector2d& d) const { return line() ? Vector2d(m * m.dot(d)) : d; }
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
  return c.observed(p.pred - c.x2).squaredNorm();
}

// Least squares of the cross-multiplied equations (x2 e3 - e1)^T R (x1 + a u) = 0 and
// (y2 e3 - e2)^T R (x1 + a u) = 0 over `idx` (for a line their combination along m); nullopt
// when they do not fix u.
std::optional<Vector3d> linear_solve(const std::vector<Corr>& cs, const int* idx, int n,
                                     const Matrix3d& R) {
  Matrix3d M = Matrix3d::Zero();
  Vector3d b = Vector3d::Zero();
  const Matrix3d Rt = R.transpose();
  for (int k = 0; k < n; ++k) {
    const Corr& c = cs[static_cast<size_t>(idx[k])];
    const Vector3d g1 = Rt * Vector3d(-1, 0, c.x2.x());
    const Vector3d g2 = Rt * Vector3d(0, -1, c.x2.y());
    if (c.line()) {
      const Vector3d g = c.m.x() * g1 + c.m.y() * g2;
      M.noalias() += c.a * c.a * g * g.transpose();
      b -= c.a * g.dot(c.x1) * g;
      continue;
    }
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

double median_of(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// Robust scale of residual lengths: the median length of a 2-D Gaussian is 1.1774 sigma, of a
// 1-D one (a line's error across it) 0.6745 sigma; a line's length is scaled to a corner's first.
constexpr double kLineToPointMedian = 1.1774 / 0.6745;
double robust_sigma(const std::vector<double>& lengths, double min_sigma) {
  return std::max(min_sigma, median_of(lengths) / 1.1774);
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
      r.segment<2>(2 * k) = f * c.observed(p.pred - c.x2);
    }
  };
  problem.jacobian = [&](const Eigen::VectorXd&, Eigen::MatrixXd& J) {
    J.resize(2 * m, 3);
    for (int k = 0; k < m; ++k) {
      const Corr& c = cs[static_cast<size_t>(idx[static_cast<size_t>(k)])];
      const Reprojection p = reproject(c, R, u);
      Eigen::Matrix<double, 2, 3> Jk = Eigen::Matrix<double, 2, 3>::Zero();
      if (p.valid) {
        Jk = f * c.a * p.dpred_dy * R;
        if (c.line()) Jk = (c.m * (c.m.transpose() * Jk)).eval();
      }
      J.block<2, 3>(2 * k, 0) = Jk;
    }
  };
  problem.accept = [&](const Eigen::VectorXd& dx) { u += dx.head<3>(); };
  problem.weights = [&](const Eigen::VectorXd& r, Eigen::VectorXd& w) {
    std::vector<double> e(static_cast<size_t>(m)), scaled(e.size());
    for (int k = 0; k < m; ++k) {
      const auto kk = static_cast<size_t>(k);
      e[kk] = r.segment<2>(2 * k).norm();
      scaled[kk] = cs[static_cast<size_t>(idx[kk])].line() ? kLineToPointMedian * e[kk] : e[kk];
    }
    const double k_huber = params.huber_k * robust_sigma(scaled, min_sigma);
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

// Points on one line: normals within 3 kSameLineRad, and each within kSameLinePx (a grout line's
// two edges) of the other's line plus kSameLineRad of their distance (a normal from a 3x3
// structure tensor scatters by a few hundredths of a radian).
constexpr double kSameLineRad = 0.05;
constexpr double kSameLinePx = 4.0;

// How many of the inliers' equations count as independent for the covariance. Nearby corners
// share their errors: at most max_points corners' worth. The points on one line share its
// profile's error (its rendering or printing, its blur): a straight line's points fix at most two
// quantities of its motion (its offset and its turn), so each line counts two equations however
// many points lie on it. Lines are told apart greedily by normal and offset in image 2.
double independent_equations(const std::vector<Corr>& cs, const std::vector<int>& inl, double f,
                             int max_points) {
  int corner_eq = 0, line_eq = 0;
  std::vector<const Corr*> lines;  // one point per line found
  for (int k : inl) {
    const Corr& c = cs[static_cast<size_t>(k)];
    if (!c.line()) {
      corner_eq += 2;
      continue;
    }
    ++line_eq;
    const bool known = std::any_of(lines.begin(), lines.end(), [&](const Corr* l) {
      const Vector2d d = c.x2 - l->x2;
      return std::abs(l->m.dot(c.m)) >= std::cos(3 * kSameLineRad) &&
             std::abs(l->m.dot(d)) * f <= kSameLinePx + kSameLineRad * d.norm() * f;
    });
    if (!known) lines.push_back(&c);
  }
  const double independent =
      std::min(corner_eq, 2 * max_points) + std::min(line_eq, 2 * static_cast<int>(lines.size()));
  return std::max(independent, 1.0);
}

}  // namespace

FlowFit fit_t_over_d(const std::vector<Vector3d>& rays_1, const std::vector<Vector3d>& rays_2,
                     const Matrix3d& R, const Vector3d& n_C1, double focal_px,
                     const FlowFitParams& params) {
  return fit_t_over_d(rays_1, rays_2, {}, R, n_C1, focal_px, params);
}

FlowFit fit_t_over_d(const std::vector<Vector3d>& rays_1, const std::vector<Vector3d>& rays_2,
                     const std::vector<Vector2d>& normals_2, const Matrix3d& R,
                     const Vector3d& n_C1, double focal_px, const FlowFitParams& params) {
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
  // Counts below are of equations (a corner two, a line one): min_inliers corners' worth.
  std::vector<Corr> cs;
  std::vector<int> index_of;  // cs -> input index
  cs.reserve(n_all);
  int finite = 0, usable_eq = 0;
  for (size_t i = 0; i < n_all; ++i) {
    const Vector3d& r1 = rays_1[i];
    const Vector3d& r2 = rays_2[i];
    if (!r1.allFinite() || !r2.allFinite() || !(r1.z() > 0) || !(r2.z() > 0)) continue;
    Vector2d m = Vector2d::Zero();
    if (i < normals_2.size()) {
      const Vector2d& g = normals_2[i];
      if (!g.allFinite()) continue;
      if (g.norm() > 0) m = g.normalized();
    }
    const int eq = m.norm() > 0 ? 1 : 2;
    finite += eq;
    const Vector3d x1 = r1 / r1.z();
    const double a = n.dot(x1);
    if (-a < params.min_incidence_cos * x1.norm()) continue;
    cs.push_back({x1, r2.head<2>() / r2.z(), a, m});
    index_of.push_back(static_cast<int>(i));
    usable_eq += eq;
  }
  fit.usable = static_cast<int>(cs.size());
  const int min_eq = 2 * params.min_inliers;
  if (usable_eq < min_eq) {
    fit.reason = finite >= min_eq ? FlowReason::kPlaneNotInView : FlowReason::kTooFewTracks;
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
  // MSAC's cost per equation: a corner's error is two equations' worth, a line's one.
  auto score = [&](const Vector3d& u, int& count) {
    double cost = 0.0;
    count = 0;
    for (const Corr& c : cs) {
      const double e2 = error2(c, R, u);
      if (e2 < thr2) {
        cost += e2;
        count += c.equations();
      } else {
        cost += 0.5 * c.equations() * thr2;
      }
    }
    return cost;
  };
  const bool any_line = std::any_of(cs.begin(), cs.end(), [](const Corr& c) { return c.line(); });
  std::vector<int> lo_idx;
  for (int it = 0; it < needed && it < params.ransac_max_iterations; ++it) {
    ++fit.ransac_samples;
    // Two corners fix u (four equations); with lines a third point, for at least three.
    int idx[3] = {pick(rng), pick(rng), 0};
    int size = 2;
    if (cs[static_cast<size_t>(idx[0])].line() || cs[static_cast<size_t>(idx[1])].line()) {
      idx[2] = pick(rng);
      size = 3;
    }
    bool spread = true;
    for (int i = 0; i < size && spread; ++i)
      for (int j = i + 1; j < size && spread; ++j)
        spread = idx[i] != idx[j] &&
                 (cs[static_cast<size_t>(idx[i])].x1 - cs[static_cast<size_t>(idx[j])].x1)
                         .squaredNorm() >= min_sep2;
    if (!spread) continue;
    const auto u = linear_solve(cs, idx, size, R);
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
    for (int lo = 0; lo < 3 && best_count >= 6; ++lo) {
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
    const double w = static_cast<double>(best_count) / usable_eq;
    const double p_fail = 1.0 - (any_line ? w * w * w : w * w);
    if (p_fail <= 0.0) break;
    if (p_fail < 1.0) {
      const double n_needed = std::ceil(log_fail / std::log(p_fail));
      if (n_needed < needed) needed = static_cast<int>(std::max(1.0, n_needed));
    }
  }
  const int min_count =
      std::max(min_eq, static_cast<int>(std::ceil(params.min_inlier_fraction * usable_eq)));
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
  auto equations = [&](const std::vector<int>& idx) {
    int eq = 0;
    for (int k : idx) eq += cs[static_cast<size_t>(k)].equations();
    return eq;
  };
  select(inl);
  for (int round = 0; round < 3; ++round) {
    if (equations(inl) < min_count) break;
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
  const int m_eq = equations(inl);
  if (m_eq < min_count) {
    fit.reason = FlowReason::kTooFewInliers;
    return fit;
  }

  // Covariance and sensitivities of the M-estimate, which solves sum_i Ju_i^T psi(r_i) = 0 with
  // Huber's psi(r) = r min(1, k / |r|) on the 2-D residual (Huber, "Robust Statistics", 1981,
  // sec. 7.6): cov = E|psi|^2 / E[psi']^2 (Ju^T Ju)^-1, psi' the derivative per axis; the plain
  // sigma^2 (J^T W J)^-1 of the last reweighted step is a third too small under Gaussian noise.
  // Sensitivities by the implicit function theorem on the same equation: du = -H^-1 B dtheta,
  // H = sum Ju^T psi'(r) Ju, B = sum Ju^T psi'(r) Jtheta.
  std::vector<double> e(static_cast<size_t>(m)), scaled(e.size());
  std::vector<uint8_t> is_line(e.size());
  std::vector<Eigen::Matrix<double, 2, 3>> Ju(static_cast<size_t>(m)), Jt(Ju.size()), Jn(Ju.size());
  std::vector<Vector2d> r(Ju.size());
  const Matrix3d P_n = Matrix3d::Identity() - n * n.transpose();
  for (int k = 0; k < m; ++k) {
    const auto kk = static_cast<size_t>(k);
    const Corr& c = cs[static_cast<size_t>(inl[kk])];
    const Reprojection p = reproject(c, R, u);
    assert(p.valid);  // an inlier has a finite error
    r[kk] = f * c.observed(p.pred - c.x2);
    e[kk] = r[kk].norm();
    is_line[kk] = c.line();
    scaled[kk] = c.line() ? kLineToPointMedian * e[kk] : e[kk];
    const Eigen::Matrix2d P = c.line() ? Eigen::Matrix2d(c.m * c.m.transpose())
                                       : Eigen::Matrix2d(Eigen::Matrix2d::Identity());
    const Eigen::Matrix<double, 2, 3> D = P * f * p.dpred_dy * R;
    Ju[kk] = c.a * D;
    Jt[kk] = -D * skew(p.q);                    // R Exp(theta) q = R q - R [q]x theta
    Jn[kk] = D * u * (c.x1.transpose() * P_n);  // a = n^T x1, n moved in its tangent plane
  }
  const double k_huber = params.huber_k * robust_sigma(scaled, params.min_sigma_px);
  Matrix3d JtJ = Matrix3d::Zero(), H = Matrix3d::Zero(), Bt = Matrix3d::Zero(),
           Bn = Matrix3d::Zero();
  // Per equation: a line's psi is the 1-D Huber's along its normal (derivative 1 or 0).
  double psi2 = 0.0, dpsi = 0.0, r2 = 0.0;
  for (size_t k = 0; k < e.size(); ++k) {
    const Vector2d mk = is_line[k] ? Vector2d(cs[static_cast<size_t>(inl[k])].m) : Vector2d::Zero();
    Eigen::Matrix2d dpsi_dr = is_line[k] ? Eigen::Matrix2d(mk * mk.transpose())
                                         : Eigen::Matrix2d(Eigen::Matrix2d::Identity());
    if (e[k] > k_huber) {
      const Vector2d rh = r[k] / e[k];
      dpsi_dr = is_line[k] ? Eigen::Matrix2d::Zero().eval()
                           : Eigen::Matrix2d(k_huber / e[k] *
                                             (Eigen::Matrix2d::Identity() - rh * rh.transpose()));
      psi2 += k_huber * k_huber;
    } else {
      psi2 += e[k] * e[k];
    }
    dpsi += dpsi_dr.trace();
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
  const double dof = std::max(1, m_eq - 3);
  const double mean_dpsi = dpsi / m_eq;
  const double sigma_kept = std::sqrt(r2 / dof);
  const double truncation =
      untruncated_sigma(sigma_kept, params.inlier_threshold_px) / std::max(sigma_kept, 1e-300);
  fit.sigma_px = std::max(params.min_sigma_px, truncation * std::sqrt(psi2 / dof) / mean_dpsi);
  fit.t_over_d_C1 = u;
  const double correlated =
      static_cast<double>(m_eq) / independent_equations(cs, inl, f, params.max_independent_points);
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

FlowOdometry::FlowOdometry(const FlowFrontParams& params, const CameraModel& camera)
    : params_(params), camera_(camera) {
  params_.validate();
  camera_.validate();
  const auto& t = params_.track;
  set_level(t.downsample);
  window_ = cv::Size(t.window_px, t.window_px);
  lk_criteria_ = cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, t.lk_iterations,
                                  t.lk_epsilon);
}

void FlowOdometry::set_level(int level) {
  assert(level >= 0 && level <= params_.track.downsample);
  level_ = level;
  level_scale_ = static_cast<double>(1 << level);
  level_size_ = cv::Size(camera_.width, camera_.height);
  for (int i = 0; i < level; ++i)
    level_size_ = cv::Size((level_size_.width + 1) / 2, (level_size_.height + 1) / 2);
}

std::vector<cv::Mat> FlowOdometry::pyramid_of(const cv::Mat& gray, int* max_level) const {
  cv::Mat level = gray;
  for (int i = 0; i < level_; ++i) cv::pyrDown(level, level);
  std::vector<cv::Mat> pyramid;
  // Copied (not a view of the caller's buffer), with derivatives: reused as the previous frame.
  const int top =
      cv::buildOpticalFlowPyramid(level, pyramid, window_, params_.track.pyramid_levels, true,
                                  cv::BORDER_REFLECT_101, cv::BORDER_CONSTANT, false);
  if (max_level) *max_level = top;
  return pyramid;
}

void FlowOdometry::reset() {
  have_previous_ = false;
  previous_pyramid_.clear();
  points_.clear();
  rays_.clear();
  line_px_.clear();
  line_normal_px_.clear();
  line_rays_.clear();
  last_t_over_d_.reset();
  last_dt_s_ = 0.0;
}

std::vector<Vector2d> FlowOdometry::feature_pixels() const {
  std::vector<Vector2d> out;
  out.reserve(points_.size());
  for (const auto& p : points_) out.emplace_back(p.x * level_scale_, p.y * level_scale_);
  return out;
}

FlowResult FlowOdometry::finish(FlowResult r) {
  ++counts_[static_cast<size_t>(r.reason)];
  r.features = static_cast<int>(points_.size());
  return r;
}

namespace {

// The detection's mask at a level of `size` whose pixels are `scale` full-resolution pixels: the
// image less its border; empty when the border leaves nothing.
cv::Mat border_mask(cv::Size size, double scale, double border_px) {
  const int border = static_cast<int>(std::ceil(border_px / scale));
  const cv::Rect inner(border, border, size.width - 2 * border, size.height - 2 * border);
  if (inner.width <= 0 || inner.height <= 0) return {};
  cv::Mat mask(size, CV_8U, cv::Scalar(0));
  mask(inner).setTo(255);
  return mask;
}

}  // namespace

void FlowOdometry::detect(int already, FlowResult& r) {
  const auto& t = params_.track;
  const int want = t.max_features - already;
  if (want <= 0) return;
  const cv::Mat& image = previous_pyramid_[0];  // the frame being stored (see add_frame)
  const double s = level_scale_;
  cv::Mat mask = border_mask(level_size_, s, t.border_px);
  if (mask.empty()) return;
  const double min_dist = t.min_distance_px / s;
  for (const auto& p : points_)
    cv::circle(mask, cv::Point(cvRound(p.x), cvRound(p.y)), static_cast<int>(std::ceil(min_dist)),
               cv::Scalar(0), cv::FILLED);
  std::vector<cv::Point2f> corners;
  std::vector<float> quality;
  cv::goodFeaturesToTrack(image, corners, 4 * t.max_features, t.quality_level, min_dist, mask,
                          quality, 3, 3, false, 0.04);

  // Spread over the grid: first up to `cap` per cell (counting the surviving tracks), strongest
  // first, then the strongest of the rest.
  const int cells = t.grid_cols * t.grid_rows;
  const int cap = (t.max_features + cells - 1) / cells;
  auto cell_of = [&](const cv::Point2f& p) {
    const int cx =
        std::clamp(static_cast<int>(p.x * t.grid_cols / level_size_.width), 0, t.grid_cols - 1);
    const int cy =
        std::clamp(static_cast<int>(p.y * t.grid_rows / level_size_.height), 0, t.grid_rows - 1);
    return cy * t.grid_cols + cx;
  };
  std::vector<int> in_cell(static_cast<size_t>(cells), 0);
  for (const auto& p : points_) ++in_cell[static_cast<size_t>(cell_of(p))];
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
  r.detected += added;
}

// A floor offers too few corners at the tracking level when a detection leaves fewer than twice
// the fit's min_inliers features: with tracks lost between frames and outliers, its pairs would
// be refused for too few tracks or inliers.
int FlowOdometry::few_corners() const {
  return std::min(2 * params_.fit.min_inliers, params_.track.max_features / 2);
}

namespace {

// Points on lines: the oriented patch compared across a line, and the search's reach.
constexpr int kLineHalfAcross = 4;  // samples each side of the point across the line: its profile
constexpr int kLineHalfAlong = 3;   // and along it, averaging the sensor noise
// Reach of the search across the line from the predicted position [full-resolution px]: a pair's
// motion at 1.5 m/s from 1.5 m at 30 Hz unpredicted (the first pair after a reset): f v / (h rate).
constexpr int kLineSearchPx = 24;
// The best match must cost less than this fraction of any other minimum of the search at least
// kLineAliasPx away: a parallel line within reach (planks, narrow tiles) makes the match
// ambiguous and the point is dropped.
constexpr double kLineUnique = 0.5;
constexpr int kLineAliasPx = 3;

// Bilinear sample of a mono8 image; false outside it.
bool sample(const cv::Mat& img, double x, double y, double& v) {
  if (!(x >= 0 && y >= 0 && x < img.cols - 1 && y < img.rows - 1)) return false;
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double fx = x - x0, fy = y - y0;
  const uint8_t* r0 = img.ptr<uint8_t>(y0);
  const uint8_t* r1 = img.ptr<uint8_t>(y0 + 1);
  v = (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
  return true;
}

// The patch across and along a line at p (normal nrm, unit), shifted across by `from`..`to`
// samples: rows along the line, columns across it. False where it leaves the image.
bool line_strip(const cv::Mat& img, const Vector2d& p, const Vector2d& nrm, int from, int to,
                std::vector<double>& out) {
  const Vector2d tan(-nrm.y(), nrm.x());
  const int cols = to - from + 1;
  out.resize(static_cast<size_t>((2 * kLineHalfAlong + 1) * cols));
  size_t i = 0;
  for (int k = -kLineHalfAlong; k <= kLineHalfAlong; ++k)
    for (int j = from; j <= to; ++j) {
      const Vector2d q = p + k * tan + j * nrm;
      if (!sample(img, q.x(), q.y(), out[i++])) return false;
    }
  return true;
}

// Zero-mean sum of squared differences of the reference patch (2 kLineHalfAcross + 1 columns)
// against the strip's window starting at column `at` (columns `cols` wide).
double zssd(const std::vector<double>& ref, const std::vector<double>& strip, int cols, int at) {
  constexpr int w = 2 * kLineHalfAcross + 1;
  constexpr int rows = 2 * kLineHalfAlong + 1;
  double mr = 0, ms = 0;
  for (int k = 0; k < rows; ++k)
    for (int j = 0; j < w; ++j) {
      mr += ref[static_cast<size_t>(k * w + j)];
      ms += strip[static_cast<size_t>(k * cols + at + j)];
    }
  mr /= rows * w;
  ms /= rows * w;
  double c = 0;
  for (int k = 0; k < rows; ++k)
    for (int j = 0; j < w; ++j) {
      const double d = (strip[static_cast<size_t>(k * cols + at + j)] - ms) -
                       (ref[static_cast<size_t>(k * w + j)] - mr);
      c += d * d;
    }
  return c;
}

// The shift across the line (in samples, sub-sample by a parabola) where `img` at p0 + s nrm best
// matches `ref`, within +-reach; nullopt at the reach's end, flat or ambiguous.
std::optional<double> search_across(const cv::Mat& img, const Vector2d& p0, const Vector2d& nrm,
                                    const std::vector<double>& ref, int reach) {
  std::vector<double> strip;
  if (!line_strip(img, p0, nrm, -reach - kLineHalfAcross, reach + kLineHalfAcross, strip))
    return std::nullopt;
  const int cols = 2 * (reach + kLineHalfAcross) + 1;
  std::vector<double> cost(static_cast<size_t>(2 * reach + 1));
  for (int s = 0; s <= 2 * reach; ++s) cost[static_cast<size_t>(s)] = zssd(ref, strip, cols, s);
  const auto best = std::min_element(cost.begin(), cost.end()) - cost.begin();
  if (best == 0 || best == 2 * reach) return std::nullopt;
  for (int s = 1; s < 2 * reach; ++s) {
    const auto ss = static_cast<size_t>(s);
    const bool minimum = cost[ss] <= cost[ss - 1] && cost[ss] <= cost[ss + 1];
    if (minimum && std::abs(s - best) >= kLineAliasPx &&
        !(cost[static_cast<size_t>(best)] < kLineUnique * cost[ss]))
      return std::nullopt;
  }
  const double cm = cost[static_cast<size_t>(best - 1)], c0 = cost[static_cast<size_t>(best)],
               cp = cost[static_cast<size_t>(best + 1)];
  const double curvature = cm - 2 * c0 + cp;
  if (!(curvature > 0)) return std::nullopt;
  return static_cast<double>(best - reach) + 0.5 * (cm - cp) / curvature;
}

}  // namespace

// Stage: points on the floor's lines of the stored frame (the tracking level), where too few
// corners are. Contract: afterwards line_* hold at most `want` points (what the corners leave of
// max_features), each on a strong edge (larger structure-tensor eigenvalue at least quality_level
// of the image's best and min_quality: the corners' thresholds), the largest across its line among
// its neighbours there, no two closer than min_distance_px nor closer to a corner, spread over the
// grid as the corners are.
void FlowOdometry::detect_lines(int want) {
  line_px_.clear();
  line_normal_px_.clear();
  line_rays_.clear();
  const auto& t = params_.track;
  const double s = level_scale_;
  const cv::Mat& image = previous_pyramid_[0];  // the tracking level
  if (want <= 0 || image.empty()) return;
  cv::Mat eig;  // per pixel: lambda1, lambda2, its eigenvector (x1, y1), the other's
  cv::cornerEigenValsAndVecs(image, eig, 3, 3);
  const int border =
      static_cast<int>(std::ceil(t.border_px / s)) + kLineHalfAcross + kLineHalfAlong;
  struct Candidate {
    float lambda;
    int x, y;
  };
  std::vector<Candidate> cand;
  float best = 0;
  for (int y = border; y < image.rows - border; ++y) {
    const cv::Vec6f* row = eig.ptr<cv::Vec6f>(y);
    for (int x = border; x < image.cols - border; ++x) {
      const cv::Vec6f& e = row[x];
      if (!(e[0] >= t.min_quality)) continue;
      best = std::max(best, e[0]);
      // Largest across the line: not smaller than the neighbours along the gradient.
      const int dx = static_cast<int>(std::lround(e[2])), dy = static_cast<int>(std::lround(e[3]));
      if (e[0] < eig.at<cv::Vec6f>(y + dy, x + dx)[0] ||
          e[0] < eig.at<cv::Vec6f>(y - dy, x - dx)[0])
        continue;
      cand.push_back({e[0], x, y});
    }
  }
  const float floor_lambda = static_cast<float>(t.quality_level) * best;
  std::sort(cand.begin(), cand.end(), [](const Candidate& a, const Candidate& b) {
    return a.lambda > b.lambda ||
           (a.lambda == b.lambda && (a.y < b.y || (a.y == b.y && a.x < b.x)));
  });
  cv::Mat mask(image.size(), CV_8U, cv::Scalar(255));
  const int min_dist = static_cast<int>(std::ceil(t.min_distance_px / s));
  for (const auto& p : points_)
    cv::circle(mask, cv::Point(cvRound(p.x), cvRound(p.y)), min_dist, cv::Scalar(0), cv::FILLED);
  const int cells = t.grid_cols * t.grid_rows;
  const int cap = (want + cells - 1) / cells;
  std::vector<int> in_cell(static_cast<size_t>(cells), 0);
  std::vector<uint8_t> taken(cand.size(), 0);
  for (int pass = 0; pass < 2 && static_cast<int>(line_px_.size()) < want; ++pass) {
    for (size_t i = 0; i < cand.size() && static_cast<int>(line_px_.size()) < want; ++i) {
      const Candidate& c = cand[i];
      if (c.lambda < floor_lambda) break;
      if (taken[i] || !mask.at<uint8_t>(c.y, c.x)) continue;
      const int cell = std::min(c.y * t.grid_rows / image.rows, t.grid_rows - 1) * t.grid_cols +
                       std::min(c.x * t.grid_cols / image.cols, t.grid_cols - 1);
      if (pass == 0 && in_cell[static_cast<size_t>(cell)] >= cap) continue;
      taken[i] = 1;
      ++in_cell[static_cast<size_t>(cell)];
      cv::circle(mask, cv::Point(c.x, c.y), min_dist, cv::Scalar(0), cv::FILLED);
      const cv::Vec6f& e = eig.at<cv::Vec6f>(c.y, c.x);
      const Vector2d px(c.x, c.y);
      line_px_.push_back(px);
      line_normal_px_.push_back(Vector2d(e[2], e[3]).normalized());
      line_rays_.push_back(camera_.ray(px * s));
    }
  }
}

// Stage: the previous frame's points on lines found again in image_2 (the tracking level). For each
// found, appends its ray in both images and the line's unit normal at the second in normalised
// image-2 coordinates. Found: the best match across the line within kLineSearchPx of the
// predicted position, unique and not at the search's end, and the search back from there into
// the first image lands within max_fb_error_px of where the point was.
void FlowOdometry::track_lines(const cv::Mat& image_2, const Matrix3d& R_C2C1, const Vector3d& n_C1,
                               const Vector3d& u_pred, std::vector<Vector3d>& rays_1,
                               std::vector<Vector3d>& rays_2,
                               std::vector<Vector2d>& normals_2) const {
  const cv::Mat& image_1 = previous_pyramid_[0];
  const double s = level_scale_;
  const int reach = static_cast<int>(std::ceil(kLineSearchPx / s));
  std::vector<double> ref, back_ref;
  for (size_t i = 0; i < line_px_.size(); ++i) {
    const Vector2d& p1 = line_px_[i];
    const Vector2d& nrm = line_normal_px_[i];
    const auto pred_px = predict_pixel(camera_, line_rays_[i], R_C2C1, n_C1, u_pred);
    if (!pred_px || !pred_px->allFinite()) continue;
    const Vector2d pred = *pred_px / s;
    if (!line_strip(image_1, p1, nrm, -kLineHalfAcross, kLineHalfAcross, ref)) continue;
    const auto shift = search_across(image_2, pred, nrm, ref, reach);
    if (!shift) continue;
    const Vector2d p2 = pred + *shift * nrm;
    if (!line_strip(image_2, p2, nrm, -kLineHalfAcross, kLineHalfAcross, back_ref)) continue;
    const auto back = search_across(image_1, p1, nrm, back_ref, kLineAliasPx + 1);
    if (!back || !(std::abs(*back) <= params_.track.max_fb_error_px)) continue;
    const Vector3d a = camera_.ray(p2 * s), b = camera_.ray(p2 * s + Vector2d(-nrm.y(), nrm.x()));
    const Vector2d tangent = b.head<2>() / b.z() - a.head<2>() / a.z();
    if (!a.allFinite() || !(tangent.norm() > 0)) continue;
    rays_1.push_back(line_rays_[i]);
    rays_2.push_back(a);
    normals_2.push_back(Vector2d(-tangent.y(), tangent.x()).normalized());
  }
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

  int max_level = 0;
  std::vector<cv::Mat> pyramid = pyramid_of(gray, &max_level);

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
  } else if (!points_.empty() || !line_px_.empty()) {
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
    std::vector<uint8_t> ok_fwd, ok_bwd;
    std::vector<float> err;
    if (!points_.empty()) {
      cv::calcOpticalFlowPyrLK(previous_pyramid_, pyramid, points_, next, ok_fwd, err, window_,
                               max_level, lk_criteria_, cv::OPTFLOW_USE_INITIAL_FLOW);
      // Back from where it was found, started at the same displacement the forward pass assumed.
      for (size_t i = 0; i < points_.size(); ++i) back[i] = points_[i];
      cv::calcOpticalFlowPyrLK(pyramid, previous_pyramid_, next, back, ok_bwd, err, window_,
                               max_level, lk_criteria_, cv::OPTFLOW_USE_INITIAL_FLOW);
    }
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
    std::vector<Vector2d> normals_2;
    if (!line_px_.empty() && rotation_ok && normal_ok) {
      normals_2.assign(rays_1.size(), Vector2d::Zero());
      track_lines(pyramid[0], R_C2C1, n_C1.normalized(), u_pred, rays_1, rays_2, normals_2);
      r.lines = static_cast<int>(rays_1.size() - kept_points.size());
    }
    r.tracked = static_cast<int>(rays_1.size());

    std::vector<uint8_t> inlier;
    if (!rotation_ok) {
      r.reason = FlowReason::kBadRotation;
    } else if (!normal_ok) {
      r.reason = FlowReason::kBadNormal;
    } else {
      const FlowFit fit = fit_t_over_d(rays_1, rays_2, normals_2, R_C2C1, n_C1.normalized(),
                                       camera_.fx, params_.fit);
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
        r.sample = sample;
        t_over_d = fit.t_over_d_C1;
        inlier = fit.inlier;
      }
    }
    // Off-floor and badly tracked points leave with the fit's outliers.
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
  previous_utime_ = utime;
  have_previous_ = true;
  last_t_over_d_ = t_over_d;
  last_dt_s_ = dt_s;
  if (static_cast<int>(points_.size()) < t.min_tracks) {
    detect(static_cast<int>(points_.size()), r);
  }
  const int corners = static_cast<int>(points_.size());
  if (corners < few_corners()) {
    detect_lines(t.max_features - corners);
  } else {
    line_px_.clear();
    line_normal_px_.clear();
    line_rays_.clear();
  }
  return finish(r);
}

}  // namespace alight::estimator
