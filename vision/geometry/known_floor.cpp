// Landing planes from the known motion and the known floor (beyond paper 3.2; eq. 2 with the
// metric t12 of eq. 3; see known_floor.hpp).
#include "vision/geometry/known_floor.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/geometry.hpp"
#include "common/median.hpp"
#include "vision/geometry/convex_hull.hpp"
#include "vision/geometry/floor_classify.hpp"

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

// The median over the matches in `mask` of the angle between where the planes at inverse
// distances rho_a and rho_b carry x1 (seen from camera 2): a rotation error w shifts a ray by w
// and, off the axis, its normalised coordinates by w (1 + |x|^2), hence the division.
double median_parallax_angle(const std::vector<Vector3d>& x1, const std::vector<Vector3d>& x2,
                             const Matrix3d& R, const Vector3d& t, const Vector3d& n, double rho_a,
                             double rho_b, const std::vector<uint8_t>& mask) {
  std::vector<double> angle;
  for (size_t i = 0; i < x1.size(); ++i) {
    if (!mask[i]) continue;
    const Vector3d a = plane_carry(R, t, n, rho_a, x1[i]), b = plane_carry(R, t, n, rho_b, x1[i]);
    if (!(a.z() > 1e-9) || !(b.z() > 1e-9)) continue;
    const double off_axis = 1.0 + x2[i].head<2>().squaredNorm();
    angle.push_back((a.head<2>() / a.z() - b.head<2>() / b.z()).norm() / off_axis);
  }
  return angle.empty() ? 0.0 : upper_median(angle);
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

// What every step of the pair's fit shares: the matches' rays, the known floor (normal n, the
// top's range of inverse distances) and motion, the focal length and threshold.
struct PairFit {
  const std::vector<Vector3d>& x1;
  const std::vector<Vector3d>& x2;
  const KnownMotion& motion;
  const Vector3d& n;
  TopRange range;
  double f, thr;
  double max_w;  // the largest rotation correction [rad]
  const LandingParams& params;
  size_t size() const { return x1.size(); }
  const Vector3d& t() const { return motion.t_12_m; }
};

// How many matches that is_floor(i) calls floor lie inside the hull of the top's matches (their
// pixels in image 2, top_px) by more than the threshold: floor a top cannot hide.
template <class IsFloor>
int hidden_floor(const PairFit& p, const std::vector<Vector2d>& top_px, const IsFloor& is_floor) {
  const double margin = p.thr / p.f;
  const ConvexHullDepth hull(top_hull(top_px));
  int n = 0;
  if (hull.empty()) return n;
  for (size_t i = 0; i < p.size(); ++i) n += is_floor(i) && hides(hull, p.x2[i].head<2>(), margin);
  return n;
}

// One rotation correction's verdict (step 2 of known_floor.hpp).
struct Hypothesis {
  int score = -1;   // matches explained: the floor's seen around the top plus the top's
  int n_floor = 0;  // floor inliers
  TopMode top;      // the top's inverse distance and its share (count 0: no pair)
  Vector3d w = Vector3d::Zero();
};

// The floor's inliers under rotation R, and the top's inverse distance that most other matches
// share. The top's rho is chosen among matches off the floor by twice the threshold (a top in
// the floor's noise band is the floor split by what is left of the rotation error), but every
// other match within the threshold of that top is explained by it: counting only the first lost
// a top of little parallax (a low platform, a short baseline: much of it inside the band) to the
// hypothesis that takes the top for the floor, whose correction absorbs the parallax and whose
// floor then explains all of the top. A top is opaque: the floor is seen around it, never
// through it, so floor matches inside the top's hull that its plane does not explain count for
// neither; where the floor is then seen in fewer than min_floor_inliers places outside the top,
// the pair is no pair and only its floor counts (a few chance matches taken for the floor amid a
// bare floor otherwise make the whole floor a level "top" a few centimetres up).
Hypothesis score_rotation(const PairFit& p, const Matrix3d& R, std::vector<PerMatch>* pm_out) {
  std::vector<PerMatch>& pm = *pm_out;
  classify_floor_matches(p.x1, p.x2, R, p.t(), p.n, p.range.rho_f, p.f, p.thr, &pm);
  Hypothesis h;
  for (size_t i = 0; i < p.size(); ++i) h.n_floor += pm[i].err_floor <= p.thr;
  h.top = top_mode(pm, p.range.rho_lo, p.range.rho_hi, p.range.max_half_width, p.thr);
  int nt = 0;
  std::vector<Vector2d> top_px;
  const auto on_top = [&](size_t i) {
    return pm[i].err_rho <= p.thr && std::abs(pm[i].rho - h.top.rho) <= pm[i].half_width;
  };
  if (h.top.count > 0)
    for (size_t i = 0; i < p.size(); ++i)
      if (pm[i].err_floor > p.thr && on_top(i)) {
        ++nt;
        top_px.push_back(p.x2[i].head<2>());
      }
  const int hidden =
      hidden_floor(p, top_px, [&](size_t i) { return pm[i].err_floor <= p.thr && !on_top(i); });
  if (h.top.count > 0 && h.n_floor - hidden < p.params.min_floor_inliers) {
    h.top = TopMode{};
    h.score = h.n_floor;
  } else {
    h.score = h.n_floor - hidden + std::max(nt, h.top.count);
  }
  return h;
}

// Step 1's candidates: only a match within the largest correction (plus the threshold) of the
// uncorrected floor can be floor; of those at most kMaxHypotheses, evenly spread in match order
// (every floor match gives nearly the same correction, so a few of them are as good as all).
std::vector<size_t> floor_candidates(const PairFit& p) {
  std::vector<size_t> hyp;
  std::vector<PerMatch> pm0;
  classify_floor_matches(p.x1, p.x2, p.motion.R_21, p.t(), p.n, p.range.rho_f, p.f, p.thr, &pm0);
  for (size_t i = 0; i < p.size(); ++i)
    if (pm0[i].err_floor <= p.thr + p.f * p.max_w) hyp.push_back(i);
  constexpr size_t kMaxHypotheses = 96;
  if (hyp.size() > kMaxHypotheses) {
    std::vector<size_t> spread;
    for (size_t k = 0; k < kMaxHypotheses; ++k)
      spread.push_back(hyp[k * hyp.size() / kMaxHypotheses]);
    hyp = std::move(spread);
  }
  return hyp;
}

// The rotation correction that puts match h on the floor (two Gauss-Newton steps on its two
// equations, minimum norm: the roll about the optical axis stays at motion capture's); nullopt
// where it is degenerate or beyond max_w.
std::optional<Vector3d> correction_for(const PairFit& p, size_t h) {
  Vector3d w = Vector3d::Zero();
  for (int it = 0; it < 2; ++it) {
    const Matrix3d R = exp_so3(w) * p.motion.R_21;
    const Vector3d q = plane_carry(R, p.t(), p.n, p.range.rho_f, p.x1[h]);
    Vector2d r;
    Eigen::Matrix<double, 2, 3> Jp;
    if (!plane_residual(q, p.x2[h], p.f, &r, &Jp)) return std::nullopt;
    const Eigen::Matrix<double, 2, 3> J = Jp * -skew(q);  // left perturbation of R
    const Eigen::Matrix2d JJt = J * J.transpose();
    if (!(std::abs(JJt.determinant()) > 1e-12)) return std::nullopt;
    w += -J.transpose() * JJt.inverse() * r;
  }
  if (!(w.norm() <= p.max_w)) return std::nullopt;
  return w;
}

// Steps 1-2: the best scoring correction over the candidates (ties: the smaller correction;
// exhaustive and in match order, so deterministic). score -1: no candidate.
Hypothesis best_hypothesis(const PairFit& p) {
  Hypothesis best;
  std::vector<PerMatch> pm;
  for (const size_t h : floor_candidates(p)) {
    const auto w = correction_for(p, h);
    if (!w) continue;
    Hypothesis s = score_rotation(p, exp_so3(*w) * p.motion.R_21, &pm);
    if (s.score > best.score || (s.score == best.score && w->norm() < best.w.norm())) {
      s.w = *w;
      best = s;
    }
  }
  return best;
}

// The pair after step 3: the correction, the top's inverse distance and the matches of both.
struct RefinedPair {
  Vector3d w;
  double rho_t;
  std::vector<uint8_t> fl, tp, tp_fit;  // floor; top reported (off the floor's band); top fitted
  int n_floor = 0, n_top = 0;
};

// Each match to the floor or the top under the pair's current correction and rho_t. The fit
// takes every match of the top; the reported top only those off the floor's band: fitting to
// the band-cut set biased rho and the correction towards the cut's side each step, until the
// top ended in the floor (a low top over a short baseline).
void reclassify(const PairFit& p, RefinedPair* q) {
  const Matrix3d R = exp_so3(q->w) * p.motion.R_21;
  q->n_floor = q->n_top = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    Vector2d rf, rt;
    const double ef =
        plane_residual(plane_carry(R, p.t(), p.n, p.range.rho_f, p.x1[i]), p.x2[i], p.f, &rf)
            ? rf.norm()
            : 1e9;
    const double et =
        plane_residual(plane_carry(R, p.t(), p.n, q->rho_t, p.x1[i]), p.x2[i], p.f, &rt) ? rt.norm()
                                                                                         : 1e9;
    q->fl[i] = ef <= p.thr && ef <= et;
    q->tp_fit[i] = !q->fl[i] && et <= p.thr;
    q->tp[i] = q->tp_fit[i] && ef >= 2 * p.thr;
    q->n_floor += q->fl[i];
    q->n_top += q->tp[i];
  }
}

// Step 3: Gauss-Newton on (omega, rho_top) over both inlier sets from the best hypothesis, the
// matches reclassified after each step.
RefinedPair refine(const PairFit& p, const Hypothesis& best) {
  RefinedPair q{best.w, best.top.rho, std::vector<uint8_t>(p.size()),
                std::vector<uint8_t>(p.size()), std::vector<uint8_t>(p.size())};
  reclassify(p, &q);
  for (int it = 0; it < 4; ++it) {
    const Matrix3d R = exp_so3(q.w) * p.motion.R_21;
    Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
    Eigen::Vector4d g = Eigen::Vector4d::Zero();
    for (size_t i = 0; i < p.size(); ++i) {
      if (!q.fl[i] && !q.tp_fit[i]) continue;
      const double rho = q.fl[i] ? p.range.rho_f : q.rho_t;
      const Vector3d x = plane_carry(R, p.t(), p.n, rho, p.x1[i]);
      Vector2d r;
      Eigen::Matrix<double, 2, 3> Jp;
      if (!plane_residual(x, p.x2[i], p.f, &r, &Jp)) continue;
      Eigen::Matrix<double, 2, 4> J = Eigen::Matrix<double, 2, 4>::Zero();
      J.leftCols<3>() = Jp * -skew(x);
      if (q.tp_fit[i]) J.col(3) = Jp * (R * p.t() * -p.n.dot(p.x1[i]));
      A += J.transpose() * J;
      g += J.transpose() * r;
    }
    A.diagonal() += Eigen::Vector4d::Constant(1e-9);
    const Eigen::Vector4d d = A.ldlt().solve(-g);
    if (!d.allFinite()) break;
    q.w += d.head<3>();
    q.rho_t += d(3);
    reclassify(p, &q);
    if (d.head<3>().norm() < 1e-7 && std::abs(d(3)) < 1e-7 * q.rho_t) break;
  }
  return q;
}

// The refined pair's refusals, in order: the fit left its bounds (a correction beyond max_w, a
// top not above the floor), too few floor or top inliers, or its floor not seen around its top
// (the hypotheses' rule, after the fit).
Reason refined_pair_refusal(const PairFit& p, const RefinedPair& q) {
  if (!(q.w.norm() <= p.max_w) || !(q.rho_t > p.range.rho_f) || !std::isfinite(q.rho_t))
    return Reason::kTopFitDiverged;
  if (q.n_floor < p.params.min_floor_inliers) return Reason::kNoDominantPlane;
  if (q.n_top < p.params.min_platform_inliers) return Reason::kTopMatchesFew;
  const Matrix3d R = exp_so3(q.w) * p.motion.R_21;
  std::vector<Vector2d> top_px;
  for (size_t i = 0; i < p.size(); ++i)
    if (q.tp_fit[i]) top_px.push_back(p.x2[i].head<2>());
  const int hidden = hidden_floor(p, top_px, [&](size_t i) {
    if (!q.fl[i]) return false;
    Vector2d rt;
    return !plane_residual(plane_carry(R, p.t(), p.n, q.rho_t, p.x1[i]), p.x2[i], p.f, &rt) ||
           rt.norm() > p.thr;
  });
  if (q.n_floor - hidden < p.params.min_floor_inliers) return Reason::kNoFloorAroundTop;
  return Reason::kOk;
}

// The top's free normal (a 3-DOF fit of n1 / d1 given the motion) against the floor's: a chance
// set of matches at one rho is no plane. A normal the matches do not determine (a degenerate
// fit) is not shown parallel either.
Reason top_normal_refusal(const std::vector<Vector3d>& x1, const std::vector<Vector3d>& x2,
                          const Matrix3d& R_21, const Vector3d& t, const std::vector<uint8_t>& top,
                          const Vector3d& n, const LandingParams& params, Vector3d* n_free) {
  const auto free = free_normal(x1, x2, R_21, t, top);
  if (!free) return Reason::kTopNotParallel;
  *n_free = *free;
  return level(*free, n, params) ? Reason::kOk : Reason::kTopNotParallel;
}

// The top alone at the inverse distance `mode`: the known floor's matches, the top's (those on
// the mode and off the floor's band, as the pair reports its top), and how many of the matches
// whose rho says where they are (near the epipole, the descent's focus of expansion amid the
// top, a match fits any plane) share the mode.
struct TopAlone {
  KnownFloorPlanes planes;
  int informative = 0, on_mode = 0;
};
TopAlone top_alone_of(const std::vector<PerMatch>& pm, const KnownMotion& motion,
                      const KnownPlane& floor, const TopRange& range, const TopMode& mode,
                      double thr) {
  const size_t N = pm.size();
  TopAlone a;
  KnownFloorPlanes& out = a.planes;
  out.motion = motion;
  out.n_1 = floor.n_1;
  out.rho_floor = range.rho_f;
  out.rho_top = mode.rho;
  out.floor.assign(N, 0);
  out.top.assign(N, 0);
  for (size_t i = 0; i < N; ++i) {
    out.floor[i] = pm[i].err_floor <= thr;
    out.n_floor += out.floor[i];
    if (pm[i].err_rho > thr || pm[i].half_width > range.max_half_width) continue;
    ++a.informative;
    if (std::abs(pm[i].rho - mode.rho) > pm[i].half_width) continue;
    ++a.on_mode;
    out.top[i] = !out.floor[i] && pm[i].err_floor >= 2 * thr;
    out.n_top += out.top[i];
  }
  return a;
}

// Where the floor is seen beside a top alone: its matches off the top's transfer by twice the
// threshold (the top's own rule against the floor's band: near the epipole a match fits both),
// anywhere. A top is opaque, so a floor inside its hull contradicts it: over a bare floor whose
// matches are mostly tracked a few px long of their parallax, the long ones make a "top" a few
// centimetres up over the whole view and the exact ones, amid them, its "floor".
int floor_seen_beside(const std::vector<Vector3d>& x1, const std::vector<Vector3d>& x2,
                      const KnownFloorPlanes& alone, double f, double thr) {
  int seen = 0;
  for (size_t i = 0; i < x1.size(); ++i) {
    Vector2d r;
    seen += alone.floor[i] && (!plane_residual(plane_carry(alone.motion.R_21, alone.motion.t_12_m,
                                                           alone.n_1, alone.rho_top, x1[i]),
                                               x2[i], f, &r) ||
                               r.norm() > 2 * thr);
  }
  return seen;
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
  const PairFit p{x1,
                  x2,
                  motion,
                  floor.n_1,
                  top_range(floor, params),
                  f,
                  thr,
                  params.max_rotation_correction_deg * M_PI / 180.0,
                  params};
  const Hypothesis best = best_hypothesis(p);
  if (best.score < 0 || best.n_floor < params.min_floor_inliers)
    return R_::fail(Reason::kNoDominantPlane);
  if (best.top.count < params.min_platform_inliers)
    return R_::fail(best.top.count == 0 ? Reason::kNoTopHeight : Reason::kTopMatchesFew);
  const RefinedPair q = refine(p, best);
  if (const Reason r = refined_pair_refusal(p, q); r != Reason::kOk) return R_::fail(r);

  KnownFloorPlanes out;
  out.motion = {exp_so3(q.w) * motion.R_21, motion.t_12_m};
  out.rotation_correction_rad = q.w.norm();
  out.n_1 = floor.n_1;
  out.rho_floor = p.range.rho_f;
  out.rho_top = q.rho_t;
  out.floor = q.fl;
  out.top = q.tp;
  out.n_floor = q.n_floor;
  out.n_top = q.n_top;
  if (const Reason r = top_normal_refusal(x1, x2, out.motion.R_21, motion.t_12_m, q.tp, floor.n_1,
                                          params, &out.n_top_free_1);
      r != Reason::kOk)
    return R_::fail(r);
  return R_::ok(std::move(out));
}

Result<KnownFloorPlanes> fit_known_top_alone(const std::vector<Vector3d>& x1,
                                             const std::vector<Vector3d>& x2,
                                             const KnownMotion& motion, const KnownPlane& floor,
                                             double f, const LandingParams& params, double thr) {
  using R_ = Result<KnownFloorPlanes>;
  const size_t N = x1.size();
  if (const Reason r = refused(N, x2.size(), motion, f, thr); r != Reason::kOk) return R_::fail(r);
  if (static_cast<int>(N) < params.min_platform_inliers) return R_::fail(Reason::kTooFewMatches);
  const TopRange range = top_range(floor, params);
  std::vector<PerMatch> pm;
  classify_floor_matches(x1, x2, motion.R_21, motion.t_12_m, floor.n_1, range.rho_f, f, thr, &pm);
  const TopMode mode = top_mode(pm, range.rho_lo, range.rho_hi, range.max_half_width, thr);
  if (mode.count == 0) return R_::fail(Reason::kNoTopHeight);
  const TopAlone alone = top_alone_of(pm, motion, floor, range, mode, thr);
  const KnownFloorPlanes& out = alone.planes;
  if (out.n_top < params.min_platform_inliers) return R_::fail(Reason::kTopMatchesFew);
  // The top alone must hold a clear majority of the matches: the rest (the floor's few, blur's
  // strays) never outvote it, and a mode that holds half of them is one of two rival planes.
  constexpr double kTopAloneMinShare = 0.6;
  if (alone.on_mode < kTopAloneMinShare * static_cast<double>(alone.informative))
    return R_::fail(Reason::kTopAloneTooFew);
  // Seen in a few places (a tile's corners beside a top that fills the view), the floor does not
  // contradict a top that holds ten times its matches; the pair then fails for want of them
  // (its rotation correction rests on the floor).
  constexpr int kTopPerFloor = 10;
  const int seen = floor_seen_beside(x1, x2, out, f, thr);
  if (seen >= params.min_floor_inliers && kTopPerFloor * seen > alone.on_mode)
    return R_::fail(Reason::kTopAloneFloorSeen);
  // With little floor in sight to compare, a bias of the whole view's parallax (a pose a few
  // milliseconds off its image, features dragged by blur) is the rival of a plane: it scales
  // every match's inverse distance alike. The top must stand off the floor by more than such a
  // bias: its inverse distance 6 % above the floor's (a 3 cm top seen from 0.5 m; a pose 5 ms off
  // its image in a 0.3 m/s descent over a 0.1 m baseline scales the parallax by 1.5 %).
  constexpr double kTopAloneMinRise = 0.06;
  if (mode.rho < (1.0 + kTopAloneMinRise) * range.rho_f) return R_::fail(Reason::kTopAloneLowRise);
  // And with no floor to correct motion capture's rotation by, its error is the other rival: the
  // top's parallax against the floor where its matches are, as an angle, must exceed the
  // largest correction the pair would make: over a short baseline a fraction of a degree makes a
  // bland floor a tall "top". Where its matches are: along the optical axis (the climb after
  // take-off, the descent) a plane's parallax grows from nothing at the epipole, so baseline
  // times the inverse distances' difference, the parallax across the axis, overstates it.
  if (median_parallax_angle(x1, x2, motion.R_21, motion.t_12_m, floor.n_1, mode.rho, range.rho_f,
                            out.top) < params.max_rotation_correction_deg * M_PI / 180.0)
    return R_::fail(Reason::kTopAloneLowParallax);
  KnownFloorPlanes found = out;
  if (const Reason r = top_normal_refusal(x1, x2, motion.R_21, motion.t_12_m, out.top, floor.n_1,
                                          params, &found.n_top_free_1);
      r != Reason::kOk)
    return R_::fail(r);
  return R_::ok(std::move(found));
}

}  // namespace alight::vision
