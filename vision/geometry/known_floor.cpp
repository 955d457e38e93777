// Landing planes from the known motion and the known floor (see known_floor.hpp).
#include "vision/geometry/known_floor.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/geometry.hpp"
#include "vision/geometry/convex_hull.hpp"

namespace alight::vision {
namespace {

Matrix3d skew(const Vector3d& v) {
  Matrix3d S;
  S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return S;
}

Matrix3d exp_so3(const Vector3d& w) {
  const double a = w.norm();
  if (a < 1e-12) return Matrix3d::Identity() + skew(w);
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

// The point x1 of a plane of inverse distance rho, carried into camera 2 (unnormalised).
Vector3d carry(const Matrix3d& R, const Vector3d& t, const Vector3d& n, double rho,
               const Vector3d& x1) {
  return R * (x1 - t * (rho * n.dot(x1)));
}

// Pixel residual of p against the ray x2, and its Jacobian on p; false behind camera 2.
bool residual(const Vector3d& p, const Vector3d& x2, double f, Vector2d* r,
              Eigen::Matrix<double, 2, 3>* J = nullptr) {
  if (!(p.z() > 1e-9)) return false;
  const double iz = 1.0 / p.z();
  *r = f * (p.head<2>() * iz - x2.head<2>());
  if (J) *J << f * iz, 0, -f * p.x() * iz * iz, 0, f * iz, -f * p.y() * iz * iz;
  return std::isfinite(r->x()) && std::isfinite(r->y());
}

// The median over the matches in `mask` of the angle between where the planes at inverse
// distances rho_a and rho_b carry x1 (seen from camera 2): a rotation error w shifts a ray by w
// and, off the axis, its normalised coordinates by w (1 + |x|^2), hence the division.
double median_parallax_angle(const std::vector<Vector3d>& x1, const std::vector<Vector3d>& x2,
                             const Matrix3d& R, const Vector3d& t, const Vector3d& n, double rho_a,
                             double rho_b, const std::vector<uint8_t>& mask) {
  std::vector<double> angle;
  for (size_t i = 0; i < x1.size(); ++i) {
    if (!mask[i]) continue;
    const Vector3d a = carry(R, t, n, rho_a, x1[i]), b = carry(R, t, n, rho_b, x1[i]);
    if (!(a.z() > 1e-9) || !(b.z() > 1e-9)) continue;
    const double off_axis = 1.0 + x2[i].head<2>().squaredNorm();
    angle.push_back((a.head<2>() / a.z() - b.head<2>() / b.z()).norm() / off_axis);
  }
  if (angle.empty()) return 0.0;
  auto mid = angle.begin() + static_cast<std::ptrdiff_t>(angle.size() / 2);
  std::nth_element(angle.begin(), mid, angle.end());
  return *mid;
}

struct PerMatch {
  double err_floor = 1e9;                         // transfer error under the floor [px]
  double rho = 0, half_width = 0, err_rho = 1e9;  // best inverse distance, its tolerance
};

// Each match under rotation R: its floor error, its own best rho (1-D least squares of the
// cross-multiplied equations) and the rho interval that keeps it within threshold_px.
void classify(const std::vector<Vector3d>& x1, const std::vector<Vector3d>& x2, const Matrix3d& R,
              const Vector3d& t, const Vector3d& n, double rho_floor, double f, double thr,
              std::vector<PerMatch>* out) {
  out->assign(x1.size(), PerMatch{});
  const Vector3d Rt = R * t;
  for (size_t i = 0; i < x1.size(); ++i) {
    PerMatch& m = (*out)[i];
    Vector2d r;
    if (residual(carry(R, t, n, rho_floor, x1[i]), x2[i], f, &r)) m.err_floor = r.norm();
    const Vector3d a = R * x1[i], b = Rt * n.dot(x1[i]);
    const double u = x2[i].x(), v = x2[i].y();
    const Vector2d c(b.x() - u * b.z(), b.y() - v * b.z());
    const Vector2d e(a.x() - u * a.z(), a.y() - v * a.z());
    const double cc = c.squaredNorm();
    if (!(cc > 1e-18)) continue;
    m.rho = c.dot(e) / cc;
    const Vector3d p = a - m.rho * b;
    if (!residual(p, x2[i], f, &r)) continue;
    m.err_rho = r.norm();
    // |d pixel / d rho| = f |c| / p_z: the rho step that moves the match by the rest of the
    // threshold.
    const double slack = std::sqrt(std::max(0.0, thr * thr - m.err_rho * m.err_rho));
    m.half_width = slack * p.z() / (f * std::sqrt(cc));
  }
}

struct TopMode {
  int count = 0;
  double rho = 0;
};

// The rho in [lo, hi] inside the most intervals of the top candidates (sweep over the sorted
// interval ends; ties: the smaller rho, the farther plane).
TopMode top_mode(const std::vector<PerMatch>& m, double lo, double hi, double max_half_width,
                 double thr) {
  std::vector<std::pair<double, int>> ev;
  for (size_t i = 0; i < m.size(); ++i) {
    // Off the floor by twice the threshold: a top within the floor's noise band is the floor
    // split by what is left of the rotation error, no platform.
    if (m[i].err_floor < 2 * thr || m[i].err_rho > thr || m[i].half_width > max_half_width)
      continue;
    if (m[i].rho < lo || m[i].rho > hi) continue;
    ev.emplace_back(m[i].rho - m[i].half_width, +1);
    ev.emplace_back(m[i].rho + m[i].half_width, -1);
  }
  // Starts before ends at the same value: touching intervals overlap.
  std::sort(ev.begin(), ev.end(), [](const auto& a, const auto& b) {
    return a.first < b.first || (a.first == b.first && a.second > b.second);
  });
  TopMode best;
  int k = 0;
  for (size_t j = 0; j < ev.size(); ++j) {
    k += ev[j].second;
    if (k > best.count) {
      best.count = k;
      // The middle of the overlap: from this start to the next end.
      const double next = j + 1 < ev.size() ? ev[j + 1].first : ev[j].first;
      best.rho = 0.5 * (ev[j].first + next);
    }
  }
  return best;
}

// The image region (camera 2, normalised coordinates) that a top hides: the convex hull of its
// matches. A random mismatch joins a top far from it only by falling within the threshold of
// the top's one inverse distance along its epipolar line (a few px of hundreds), so the hull is
// the top's outline within its feature spacing. (Matches tracked a few px wrong along their
// parallax do share one inverse distance by chance, scattered over the view, landing_none_photo
// 9501: their hull then holds floor matches, which count against them below.)
std::vector<cv::Point2f> top_hull(const std::vector<Vector2d>& top_px) {
  std::vector<cv::Point2f> pts, hull;
  for (const auto& q : top_px)
    pts.emplace_back(static_cast<float>(q.x()), static_cast<float>(q.y()));
  if (pts.size() >= 3) cv::convexHull(pts, hull);
  return hull;
}

// q inside the hull by more than margin; fewer than 3 corners hide nothing.
bool hides(const ConvexHullDepth& hull, const Vector2d& q, double margin) {
  return hull.inside_by(static_cast<float>(q.x()), static_cast<float>(q.y()), margin);
}

// The unit normal of the matches in `mask` with the plane free (n1~ = n1 / d1, 3 unknowns,
// linear given R21 and t12): x2 ~ a - g s with a = R x1, g = R t, s = n1~^T x1.
std::optional<Vector3d> free_normal(const std::vector<Vector3d>& x1,
                                    const std::vector<Vector3d>& x2, const Matrix3d& R,
                                    const Vector3d& t, const std::vector<uint8_t>& mask) {
  const Vector3d g = R * t;
  Matrix3d AtA = Matrix3d::Zero();
  Vector3d Atb = Vector3d::Zero();
  for (size_t i = 0; i < x1.size(); ++i) {
    if (!mask[i]) continue;
    const Vector3d a = R * x1[i];
    const double u = x2[i].x(), v = x2[i].y();
    const double rows[2][2] = {{g.x() - u * g.z(), a.x() - u * a.z()},
                               {g.y() - v * g.z(), a.y() - v * a.z()}};
    for (const auto& row : rows) {
      const Vector3d Ak = row[0] * x1[i];
      AtA += Ak * Ak.transpose();
      Atb += Ak * row[1];
    }
  }
  const Vector3d n_free = AtA.ldlt().solve(Atb);
  if (!n_free.allFinite() || !(n_free.norm() > 0)) return std::nullopt;
  return n_free.normalized();
}

// What both fits take from the floor: its inverse distance and the range of a top's.
struct TopRange {
  double rho_f = 0, rho_lo = 0, rho_hi = 0, max_half_width = 0;
};

// The inputs both fits refuse (Reason::kOk: none).
Reason refused(size_t n1, size_t n2, const KnownMotion& motion, double f, double thr) {
  if (n1 != n2 || !(f > 0) || !(thr > 0)) return Reason::kTooFewMatches;
  if (!(motion.t_12_m.norm() > 1e-6)) return Reason::kSmallBaseline;
  return Reason::kOk;
}

TopRange top_range(const KnownPlane& floor, const LandingParams& params) {
  TopRange r;
  r.rho_f = 1.0 / floor.d_1_m;
  // A top between min_height_m and max_height_m above the floor (at most 5 cm below camera 1).
  r.rho_lo = 1.0 / std::max(0.05, floor.d_1_m - params.min_height_m);
  r.rho_hi = 1.0 / std::max(0.05, floor.d_1_m - params.max_height_m);
  // A match whose rho is more uncertain than a tenth of the floor's (near the epipole, little
  // parallax) would join any top: it joins none.
  r.max_half_width = 0.1 * r.rho_f;
  return r;
}

// The top's free normal within max_normal_angle_deg of the floor's.
bool level(const Vector3d& n_free, const Vector3d& n, const LandingParams& params) {
  return std::acos(std::clamp(n_free.dot(n), -1.0, 1.0)) <=
         params.max_normal_angle_deg * M_PI / 180.0;
}

}  // namespace

std::optional<KnownPlane> known_floor(const PoseSample& pose_1, const CameraMount& mount,
                                      double floor_z_m) {
  const Isometry3d X_WC1 = camera_in_world(pose_1.X_WB(), mount.X_BC());
  const double d = X_WC1.translation().z() - floor_z_m;
  if (!(d > 1e-3) || !std::isfinite(d)) return std::nullopt;
  KnownPlane p;
  p.n_1 = X_WC1.linear().transpose() * -Vector3d::UnitZ();  // down: from the camera to the floor
  p.d_1_m = d;
  return p;
}

Matrix3d plane_homography(const KnownMotion& m, const Vector3d& n_1, double rho_per_m) {
  return m.R_21 * (Matrix3d::Identity() - m.t_12_m * (rho_per_m * n_1).transpose());
}

Result<KnownFloorPlanes> fit_known_floor_planes(const std::vector<Vector3d>& x1,
                                                const std::vector<Vector3d>& x2,
                                                const KnownMotion& motion, const KnownPlane& floor,
                                                double f, const LandingParams& params, double thr) {
  using R_ = Result<KnownFloorPlanes>;
  const size_t N = x1.size();
  if (const Reason r = refused(N, x2.size(), motion, f, thr); r != Reason::kOk) return R_::fail(r);
  if (static_cast<int>(N) < params.min_floor_inliers + params.min_platform_inliers)
    return R_::fail(Reason::kTooFewMatches);
  const Vector3d& n = floor.n_1;
  const Vector3d& t = motion.t_12_m;
  const auto [rho_f, rho_lo, rho_hi, max_half_width] = top_range(floor, params);
  const double max_w = params.max_rotation_correction_deg * M_PI / 180.0;

  // Floor matches (is_floor) hidden by the top whose matches in image 2 are top_px.
  const double margin = thr / f;
  const auto hidden_floor = [&](const std::vector<Vector2d>& top_px, const auto& is_floor) {
    const ConvexHullDepth hull(top_hull(top_px));
    int n = 0;
    if (hull.empty()) return n;
    for (size_t i = 0; i < N; ++i) n += is_floor(i) && hides(hull, x2[i].head<2>(), margin);
    return n;
  };

  std::vector<PerMatch> pm;
  const auto score = [&](const Matrix3d& R, TopMode* top, int* explained) {
    classify(x1, x2, R, t, n, rho_f, f, thr, &pm);
    int nf = 0;
    for (size_t i = 0; i < N; ++i) nf += pm[i].err_floor <= thr;
    *top = top_mode(pm, rho_lo, rho_hi, max_half_width, thr);
    // The top's rho is chosen among matches off the floor by twice the threshold (a top in the
    // floor's noise band is the floor split by what is left of the rotation error), but every
    // other match within the threshold of that top is explained by it. Counting only the first
    // lost a top of little parallax (a low platform, a short baseline: much of it inside the
    // band) to the hypothesis that takes the top for the floor, whose correction absorbs the
    // parallax and whose floor then explains all of the top: over flat tiles the top holds 20
    // times the floor's matches (landing_tiles seed 8001, target lost in approach).
    int nt = 0;
    std::vector<Vector2d> top_px;
    const auto on_top = [&](size_t i) {
      return pm[i].err_rho <= thr && std::abs(pm[i].rho - top->rho) <= pm[i].half_width;
    };
    if (top->count > 0)
      for (size_t i = 0; i < N; ++i)
        if (pm[i].err_floor > thr && on_top(i)) {
          ++nt;
          top_px.push_back(x2[i].head<2>());
        }
    // A top is opaque: the floor is seen around it, never through it. Floor matches inside the
    // top's region that its plane does not explain contradict the pair and count for neither;
    // a pair whose floor is seen in fewer than min_floor_inliers places outside its top is no
    // pair, only its floor counts. Over a bare floor (landing_none_photo) the hypothesis that
    // took a few chance matches for the floor, all amid the real floor, made the whole floor a
    // level "top" a few centimetres up under a small rotation correction, and outscored the
    // truth by those few matches.
    const int hidden =
        hidden_floor(top_px, [&](size_t i) { return pm[i].err_floor <= thr && !on_top(i); });
    if (top->count > 0 && nf - hidden < params.min_floor_inliers) {
      *top = TopMode{};
      *explained = nf;
    } else {
      *explained = nf - hidden + std::max(nt, top->count);
    }
    return nf;
  };

  // 1-2. One hypothesis per match taken for floor. Only a match within the largest correction
  // (plus the threshold) of the uncorrected floor can be floor; of those at most
  // kMaxHypotheses, evenly spread in match order (every floor match gives nearly the same
  // correction, so a few of them are as good as all).
  std::vector<size_t> hyp;
  {
    std::vector<PerMatch> pm0;
    classify(x1, x2, motion.R_21, t, n, rho_f, f, thr, &pm0);
    for (size_t i = 0; i < N; ++i)
      if (pm0[i].err_floor <= thr + f * max_w) hyp.push_back(i);
    constexpr size_t kMaxHypotheses = 96;
    if (hyp.size() > kMaxHypotheses) {
      std::vector<size_t> spread;
      for (size_t k = 0; k < kMaxHypotheses; ++k)
        spread.push_back(hyp[k * hyp.size() / kMaxHypotheses]);
      hyp = std::move(spread);
    }
  }
  int best_score = -1, best_floor = 0;
  Vector3d best_w = Vector3d::Zero();
  TopMode best_top;
  for (const size_t h : hyp) {
    Vector3d w = Vector3d::Zero();
    bool ok = true;
    for (int it = 0; it < 2 && ok; ++it) {
      const Matrix3d R = exp_so3(w) * motion.R_21;
      const Vector3d p = carry(R, t, n, rho_f, x1[h]);
      Vector2d r;
      Eigen::Matrix<double, 2, 3> Jp;
      if (!residual(p, x2[h], f, &r, &Jp)) {
        ok = false;
        break;
      }
      const Eigen::Matrix<double, 2, 3> J = Jp * -skew(p);  // left perturbation of R
      const Eigen::Matrix2d JJt = J * J.transpose();
      if (!(std::abs(JJt.determinant()) > 1e-12)) {
        ok = false;
        break;
      }
      w += -J.transpose() * JJt.inverse() * r;
    }
    if (!ok || !(w.norm() <= max_w)) continue;
    TopMode top;
    int s = 0;
    const int nf = score(exp_so3(w) * motion.R_21, &top, &s);
    if (s > best_score || (s == best_score && w.norm() < best_w.norm())) {
      best_score = s;
      best_floor = nf;
      best_w = w;
      best_top = top;
    }
  }
  if (best_score < 0 || best_floor < params.min_floor_inliers)
    return R_::fail(Reason::kNoDominantPlane);
  if (best_top.count < params.min_platform_inliers) return R_::fail(Reason::kNoTargetPlane);

  // 3. Gauss-Newton on (omega, rho_top) over both inlier sets, reclassifying after each step.
  Vector3d w = best_w;
  double rho_t = best_top.rho;
  std::vector<uint8_t> fl(N), tp(N), tp_fit(N);
  const auto reclassify = [&] {
    const Matrix3d R = exp_so3(w) * motion.R_21;
    int nf = 0, nt = 0;
    for (size_t i = 0; i < N; ++i) {
      Vector2d rf, rt;
      const double ef = residual(carry(R, t, n, rho_f, x1[i]), x2[i], f, &rf) ? rf.norm() : 1e9;
      const double et = residual(carry(R, t, n, rho_t, x1[i]), x2[i], f, &rt) ? rt.norm() : 1e9;
      fl[i] = ef <= thr && ef <= et;
      // The fit takes every match of the top; the reported top only those off the floor's band.
      // Fitting to the band-cut set biased rho and the correction towards the cut's side each
      // step, until the top ended in the floor (a low top over a short baseline).
      tp_fit[i] = !fl[i] && et <= thr;
      tp[i] = tp_fit[i] && ef >= 2 * thr;
      nf += fl[i];
      nt += tp[i];
    }
    return std::make_pair(nf, nt);
  };
  auto counts = reclassify();
  for (int it = 0; it < 4; ++it) {
    const Matrix3d R = exp_so3(w) * motion.R_21;
    Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
    Eigen::Vector4d g = Eigen::Vector4d::Zero();
    for (size_t i = 0; i < N; ++i) {
      if (!fl[i] && !tp_fit[i]) continue;
      const double rho = fl[i] ? rho_f : rho_t;
      const Vector3d p = carry(R, t, n, rho, x1[i]);
      Vector2d r;
      Eigen::Matrix<double, 2, 3> Jp;
      if (!residual(p, x2[i], f, &r, &Jp)) continue;
      Eigen::Matrix<double, 2, 4> J = Eigen::Matrix<double, 2, 4>::Zero();
      J.leftCols<3>() = Jp * -skew(p);
      if (tp_fit[i]) J.col(3) = Jp * (R * t * -n.dot(x1[i]));
      A += J.transpose() * J;
      g += J.transpose() * r;
    }
    A.diagonal() += Eigen::Vector4d::Constant(1e-9);
    const Eigen::Vector4d d = A.ldlt().solve(-g);
    if (!d.allFinite()) break;
    w += d.head<3>();
    rho_t += d(3);
    counts = reclassify();
    if (d.head<3>().norm() < 1e-7 && std::abs(d(3)) < 1e-7 * rho_t) break;
  }
  if (!(w.norm() <= max_w) || !(rho_t > rho_f) || !std::isfinite(rho_t))
    return R_::fail(Reason::kNoTargetPlane);
  if (counts.first < params.min_floor_inliers) return R_::fail(Reason::kNoDominantPlane);
  if (counts.second < params.min_platform_inliers) return R_::fail(Reason::kNoTargetPlane);
  {
    // The refined pair's floor is seen around its top too (the hypotheses' rule, after the fit).
    const Matrix3d R = exp_so3(w) * motion.R_21;
    std::vector<Vector2d> top_px;
    for (size_t i = 0; i < N; ++i)
      if (tp_fit[i]) top_px.push_back(x2[i].head<2>());
    const int hidden = hidden_floor(top_px, [&](size_t i) {
      if (!fl[i]) return false;
      Vector2d rt;
      return !residual(carry(R, t, n, rho_t, x1[i]), x2[i], f, &rt) || rt.norm() > thr;
    });
    if (counts.first - hidden < params.min_floor_inliers) return R_::fail(Reason::kNoTargetPlane);
  }

  KnownFloorPlanes out;
  out.motion = {exp_so3(w) * motion.R_21, t};
  out.rotation_correction_rad = w.norm();
  out.n_1 = n;
  out.rho_floor = rho_f;
  out.rho_top = rho_t;
  out.floor = fl;
  out.top = tp;
  out.n_floor = counts.first;
  out.n_top = counts.second;

  const auto n_free = free_normal(x1, x2, out.motion.R_21, t, tp);
  if (!n_free) return R_::fail(Reason::kNoTargetPlane);
  out.n_top_free_1 = *n_free;
  if (!level(out.n_top_free_1, n, params)) return R_::fail(Reason::kNoTargetPlane);
  return R_::ok(std::move(out));
}

Result<KnownFloorPlanes> fit_known_top_alone(const std::vector<Vector3d>& x1,
                                             const std::vector<Vector3d>& x2,
                                             const KnownMotion& motion, const KnownPlane& floor,
                                             double f, const LandingParams& params, double thr) {
  using R_ = Result<KnownFloorPlanes>;
  const size_t N = x1.size();
  if (const Reason r = refused(N, x2.size(), motion, f, thr); r != Reason::kOk) return R_::fail(r);
  if (!(params.top_alone_min_share > 0) || static_cast<int>(N) < params.min_platform_inliers)
    return R_::fail(Reason::kNoTargetPlane);
  const Vector3d& n = floor.n_1;
  const Vector3d& t = motion.t_12_m;
  const auto [rho_f, rho_lo, rho_hi, max_half_width] = top_range(floor, params);
  std::vector<PerMatch> pm;
  classify(x1, x2, motion.R_21, t, n, rho_f, f, thr, &pm);
  const TopMode mode = top_mode(pm, rho_lo, rho_hi, max_half_width, thr);
  if (mode.count == 0) return R_::fail(Reason::kNoTargetPlane);

  KnownFloorPlanes out;
  out.motion = motion;
  out.n_1 = n;
  out.rho_floor = rho_f;
  out.rho_top = mode.rho;
  out.floor.assign(N, 0);
  out.top.assign(N, 0);
  // The share is of the matches whose rho says where they are: near the epipole (the
  // descent's focus of expansion, amid the top) a match fits any plane.
  int informative = 0, on_mode = 0;
  for (size_t i = 0; i < N; ++i) {
    out.floor[i] = pm[i].err_floor <= thr;
    out.n_floor += out.floor[i];
    if (pm[i].err_rho > thr || pm[i].half_width > max_half_width) continue;
    ++informative;
    if (std::abs(pm[i].rho - mode.rho) > pm[i].half_width) continue;
    ++on_mode;
    // As the pair's reported top: off the floor's band.
    out.top[i] = !out.floor[i] && pm[i].err_floor >= 2 * thr;
    out.n_top += out.top[i];
  }
  if (out.n_top < params.min_platform_inliers ||
      on_mode < params.top_alone_min_share * static_cast<double>(informative))
    return R_::fail(Reason::kNoTargetPlane);
  // The floor seen: a floor match off the top's transfer by twice the threshold (the top's own
  // rule against the floor's band: near the epipole a match fits both), anywhere. A top is
  // opaque, so a floor inside its hull contradicts it: over a bare floor whose matches are
  // mostly tracked a few px long of their parallax, the long ones made a "top" 4-5 cm up over
  // the whole view and the exact ones, amid them, its "floor" (landing_none_photo 9505).
  int floor_seen = 0;
  for (size_t i = 0; i < N; ++i) {
    Vector2d r;
    floor_seen +=
        out.floor[i] &&
        (!residual(carry(motion.R_21, t, n, mode.rho, x1[i]), x2[i], f, &r) || r.norm() > 2 * thr);
  }
  // Seen in a few places (a tile's corners beside a top that fills the view), the floor does not
  // contradict a top that holds ten times its matches; the pair then fails for want of them
  // (its rotation correction rests on the floor).
  constexpr int kTopPerFloor = 10;
  if (floor_seen >= params.min_floor_inliers && kTopPerFloor * floor_seen > on_mode)
    return R_::fail(Reason::kNoTargetPlane);
  // With little floor in sight to compare, a bias of the whole view's parallax (a pose a few
  // milliseconds off its image, features dragged by blur) is the rival of a plane: it scales
  // every match's inverse distance alike. The top must stand off the floor by more than such a
  // bias: its inverse distance top_alone_min_rise above the floor's.
  if (mode.rho < (1.0 + params.top_alone_min_rise) * rho_f) return R_::fail(Reason::kNoTargetPlane);
  // And with no floor to correct motion capture's rotation by, its error is the other rival: the
  // top's parallax against the floor where its matches are, as an angle, must exceed the
  // largest correction the pair would make: over a short baseline a fraction of a degree makes a
  // bland floor a tall "top". Where its matches are: along the optical axis (the climb after
  // take-off, the descent) a plane's parallax grows from nothing at the epipole, so baseline
  // times the inverse distances' difference, the parallax across the axis, overstates it and
  // passed a photographed floor seen climbing for a top (landing_none_photo 9776).
  if (median_parallax_angle(x1, x2, motion.R_21, t, n, mode.rho, rho_f, out.top) <
      params.max_rotation_correction_deg * M_PI / 180.0)
    return R_::fail(Reason::kNoTargetPlane);
  const auto n_free = free_normal(x1, x2, motion.R_21, t, out.top);
  if (!n_free || !level(*n_free, n, params)) return R_::fail(Reason::kNoTargetPlane);
  out.n_top_free_1 = *n_free;
  return R_::ok(std::move(out));
}

}  // namespace alight::vision
