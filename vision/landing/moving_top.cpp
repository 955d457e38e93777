// A moving platform's top between two frames (beyond paper 3.2; see moving_top.hpp): the
// floor's matches by the known floor (eq. 2 with the metric motion of eq. 3), the others on a
// level plane from each view (eqs. 4-6), their similarity by RANSAC, the gates, the measurement.
#include "vision/landing/moving_top.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "common/median.hpp"
#include "vision/geometry/bilinear.hpp"
#include "vision/landing/extent.hpp"
#include "vision/landing/moving_edges.hpp"
#include "vision/landing/similarity_inliers.hpp"

namespace alight::vision {

const char* to_string(MovingReason r) {
  switch (r) {
    case MovingReason::kOk:
      return "ok";
    case MovingReason::kNoEarlierFrame:
      return "no_earlier_frame";
    case MovingReason::kNotAboveFloor:
      return "not_above_floor";
    case MovingReason::kTooFewCandidates:
      return "too_few_candidates";
    case MovingReason::kNoCommonMotion:
      return "no_common_motion";
    case MovingReason::kOnFloor:
      return "on_floor";
    case MovingReason::kTooFast:
      return "too_fast";
    case MovingReason::kSizeOutOfRange:
      return "size_out_of_range";
    case MovingReason::kStillTop:
      return "still_top";
    case MovingReason::kStillPixels:
      return "still_pixels";
    case MovingReason::kOutlineUnpaired:
      return "outline_unpaired";
  }
  return "unknown";
}

Vector2d Similarity2::apply(const Vector2d& p) const {
  const double c = std::cos(theta), sn = std::sin(theta);
  return s * Vector2d(c * p.x() - sn * p.y(), sn * p.x() + c * p.y()) + t;
}

std::optional<Similarity2> fit_similarity(const std::vector<Vector2d>& p,
                                          const std::vector<Vector2d>& q) {
  assert(p.size() == q.size());
  if (p.size() < 2) return std::nullopt;
  Vector2d mp = Vector2d::Zero(), mq = Vector2d::Zero();
  for (size_t i = 0; i < p.size(); ++i) mp += p[i], mq += q[i];
  mp /= double(p.size()), mq /= double(q.size());
  // As complex numbers: q - mq = a (p - mp), a = s e^{i theta} = sum conj(p') q' / sum |p'|^2.
  double re = 0, im = 0, pp = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const Vector2d a = p[i] - mp, b = q[i] - mq;
    re += a.x() * b.x() + a.y() * b.y();
    im += a.x() * b.y() - a.y() * b.x();
    pp += a.squaredNorm();
  }
  if (!(pp > 1e-12)) return std::nullopt;
  Similarity2 S;
  S.s = std::hypot(re, im) / pp;
  S.theta = std::atan2(im, re);
  S.t = mq - S.apply(mp);  // apply adds S.t, still zero: t = mq - s R mp
  return S;
}

double set_covariances(double var_r, double n, double spread, const Vector2d& centre_W,
                       const Vector2d& vel_W, const Vector3d& ref_camera_W,
                       const Vector3d& camera_W, double dt_s, const MovingTopParams& params,
                       MovingTop* out) {
  const double d2 = camera_W.z() - out->plane_z_m;
  const double sh = params.top_height_sigma_m / std::max(0.1, d2);
  // A height error scales the points about each camera's nadir: the centre moves along its
  // offset from camera 2's nadir, the velocity along the speed relative to the camera.
  const Vector2d u = (centre_W - camera_W.head<2>()) * sh;
  const Vector2d v_cam = (camera_W - ref_camera_W).head<2>() / dt_s;
  const Vector2d w = (vel_W - v_cam) * sh;
  const double var_s = var_r / std::max(1e-6, spread);
  out->cov_p_W.setZero();
  out->cov_p_W.topLeftCorner<2, 2>() = var_r / n * Eigen::Matrix2d::Identity() + u * u.transpose();
  out->cov_p_W(2, 2) = params.top_height_sigma_m * params.top_height_sigma_m + d2 * d2 * var_s;
  out->cov_v_W.setZero();
  out->cov_v_W.topLeftCorner<2, 2>() =
      2 * var_r / (n * dt_s * dt_s) * Eigen::Matrix2d::Identity() + w * w.transpose();
  out->cov_v_W(2, 2) = d2 * d2 * var_s / (dt_s * dt_s);
  out->var_yaw_rate = 2 * var_s / (dt_s * dt_s);
  return var_s;
}

bool motion_beyond_a_platform(double speed_mps, const Similarity2& S, double dt_s,
                              const MovingTopParams& params) {
  return speed_mps > params.max_speed_mps ||
         std::abs(S.theta) / dt_s > params.max_yaw_rate_dps * M_PI / 180 ||
         std::abs(S.s - 1) > params.max_scale_change;
}

namespace {

// One match placed in the world: its rays from both cameras and, off the floor, its points on
// the assumed top plane seen from each view.
struct Placed {
  size_t index = 0;
  Vector2d p1 = Vector2d::Zero(), p2 = Vector2d::Zero();  // on the top plane, world xy [m]
  double tol_m = 0;         // threshold_px at its distance from camera 2 [m]
  double floor_err_px = 0;  // transfer error under the known floor [px]
};

struct Views {
  Isometry3d X_WC1, X_WC2;
  double focal_px = 1;
};

// Transfer error of match i under the known floor: its reference ray onto the floor, into the
// current camera, against its current ray [px]; infinite where either misses the floor.
double floor_error_px(const Views& v, const Vector3d& r1, const Vector3d& r2, double floor_z_m) {
  const auto F = ray_at_height(v.X_WC1.translation(), v.X_WC1.linear() * r1, floor_z_m);
  if (!F) return INFINITY;
  const Vector3d x = v.X_WC2.inverse() * *F;
  if (!(x.z() > 1e-6)) return INFINITY;
  return v.focal_px * (x.hnormalized() - r2.hnormalized()).norm();
}

// Stage 1: every match placed; those the known floor does not carry within floor_tol_px and
// whose rays meet the top's plane from both views are the candidates. *carried marks, per
// correspondence, those the known floor does carry.
std::vector<Placed> place_candidates(const Correspondences& c, const Views& v, double floor_z_m,
                                     const MovingTopParams& params, std::vector<uint8_t>* carried) {
  std::vector<Placed> out;
  carried->assign(c.size(), 0);
  const double z_top = floor_z_m + params.top_height_m;
  for (size_t i = 0; i < c.size(); ++i) {
    const Vector3d r1 = c.camera->ray(c.u1[i]), r2 = c.camera->ray(c.u2[i]);
    Placed m;
    m.index = i;
    m.floor_err_px = floor_error_px(v, r1, r2, floor_z_m);
    if (m.floor_err_px <= params.floor_tol_px) {
      (*carried)[i] = 1;
      continue;
    }
    const Vector3d d1 = v.X_WC1.linear() * r1, d2 = v.X_WC2.linear() * r2;
    const auto P1 = ray_at_height(v.X_WC1.translation(), d1, z_top);
    const auto P2 = ray_at_height(v.X_WC2.translation(), d2, z_top);
    if (!P1 || !P2) continue;
    m.p1 = P1->head<2>();
    m.p2 = P2->head<2>();
    m.tol_m = params.threshold_px * (*P2 - v.X_WC2.translation()).norm() / r2.norm() / v.focal_px;
    out.push_back(m);
  }
  return out;
}

std::optional<Similarity2> fit_on(const std::vector<Placed>& cand, const std::vector<size_t>& in) {
  std::vector<Vector2d> p, q;
  for (size_t k : in) p.push_back(cand[k].p1), q.push_back(cand[k].p2);
  return fit_similarity(p, q);
}

// Stage 2: the largest set of candidates sharing one similarity. Draws of two candidates at
// least 2 cm apart on the plane (seeded; the same inputs give the same set), the best refined by
// least squares over its inliers twice. Ties keep the first drawn.
std::vector<size_t> common_motion(const std::vector<Placed>& cand, const MovingTopParams& params,
                                  Similarity2* S_out) {
  std::vector<size_t> best;
  if (cand.size() < 2) return best;
  std::vector<Vector2d> p1, p2;
  std::vector<double> tol;
  for (const Placed& m : cand) p1.push_back(m.p1), p2.push_back(m.p2), tol.push_back(m.tol_m);
  const SimilarityCandidates lanes(p1, p2, tol);
  std::mt19937_64 rng(params.seed);
  std::uniform_int_distribution<size_t> pick(0, cand.size() - 1);
  for (int it = 0; it < params.iterations; ++it) {
    const size_t a = pick(rng), b = pick(rng);
    if (a == b || (cand[a].p1 - cand[b].p1).norm() < 0.02) continue;
    const auto S = fit_similarity({cand[a].p1, cand[b].p1}, {cand[a].p2, cand[b].p2});
    if (!S || std::abs(S->s - 1) > params.max_scale_change) continue;
    if (similarity_inliers(*S, lanes, nullptr) > best.size())
      similarity_inliers(*S, lanes, &best), *S_out = *S;
  }
  for (int refine = 0; refine < 2 && best.size() >= 3; ++refine) {
    const auto S = fit_on(cand, best);
    if (!S) break;
    std::vector<size_t> in;
    if (similarity_inliers(*S, lanes, &in) < best.size()) break;
    best = std::move(in), *S_out = *S;
  }
  return best;
}

// Stages 2 and 3's first gates: the largest common motion whose matches are not the floor's and
// whose motion a platform makes. A cluster of floor matches just outside floor_tol_px (motion
// capture's noise, and its stamp's error times the body's turn: a turning camera puts many floor
// matches a few pixels off the known floor's prediction, and they share one apparent motion) is
// no top: most of its matches are carried by the floor within a few tolerances. A motion faster
// than max_speed_mps, turning faster than max_yaw_rate_dps or scaled beyond max_scale_change is
// none either: a floor of one pattern repeated (a chessboard, tiles) matches each copy to the
// next, and those matches share one rigid motion of a period per interval, metres a second,
// often the largest set in the view. Either is set aside and the largest motion among the
// remaining candidates taken, up to kSetsAside times (the floor seen through the turn's error,
// once or twice split by the image's regions; a pattern's copies along either of its axes).
// *reason: kNoCommonMotion when the first search finds no set of min_inliers, else the first set
// aside's (kOnFloor, kTooFast) when every set found was set aside.
constexpr int kSetsAside = 2;

bool floor_cluster(const std::vector<Placed>& cand, const std::vector<size_t>& in,
                   const MovingTopParams& params) {
  const auto on_floor = std::count_if(in.begin(), in.end(), [&](size_t k) {
    return cand[k].floor_err_px <= kFloorClusterTols * params.floor_tol_px;
  });
  return double(on_floor) > params.max_floor_share * double(in.size());
}

bool beyond_a_platform(const std::vector<Placed>& cand, const std::vector<size_t>& in,
                       const Similarity2& S, double dt_s, const MovingTopParams& params) {
  Vector2d shift = Vector2d::Zero();
  for (size_t k : in) shift += cand[k].p2 - cand[k].p1;
  return motion_beyond_a_platform(shift.norm() / double(in.size()) / dt_s, S, dt_s, params);
}

std::vector<size_t> platform_motion(const std::vector<Placed>& cand, double dt_s,
                                    const MovingTopParams& params, Similarity2* S,
                                    MovingReason* reason) {
  std::vector<size_t> pool(cand.size());
  for (size_t k = 0; k < pool.size(); ++k) pool[k] = k;
  MovingReason first_aside = MovingReason::kOk;
  for (int pass = 0;; ++pass) {
    std::vector<Placed> sub;
    for (size_t k : pool) sub.push_back(cand[k]);
    std::vector<size_t> in;
    for (size_t j : common_motion(sub, params, S)) in.push_back(pool[j]);
    if (int(in.size()) < params.min_inliers) {
      *reason = pass == 0 ? MovingReason::kNoCommonMotion : first_aside;
      return in;
    }
    const MovingReason why = floor_cluster(cand, in, params) ? MovingReason::kOnFloor
                             : beyond_a_platform(cand, in, *S, dt_s, params)
                                 ? MovingReason::kTooFast
                                 : MovingReason::kOk;
    if (why == MovingReason::kOk) {
      *reason = MovingReason::kOk;
      return in;
    }
    if (pass == 0) first_aside = why;
    if (pass == kSetsAside) {
      *reason = first_aside;
      return in;
    }
    std::vector<uint8_t> taken(cand.size(), 0);
    for (size_t k : in) taken[k] = 1;
    pool.erase(std::remove_if(pool.begin(), pool.end(), [&](size_t k) { return taken[k]; }),
               pool.end());
  }
}

// Stage 3's first step: the set as one region of the plane. The top is one piece, its matches
// spread over its print; a match elsewhere that shares its motion by chance (a floor feature
// mismatched by the motion's few pixels, likelier the slower the top) lies apart from them and,
// taken into the set, stretches its rectangle, turns its yaw and may touch the border (the view
// then read as cut). The set's matches are linked where two lie within kLinkSpacings times the
// median distance of a match to its nearest (placed at the current exposure); a linked piece of
// at most kStrayMatches matches is left out. Over matches spread evenly, a match's nearest lies
// beyond four times the median distance with a probability of e^-11; a part of the top's print
// apart from the rest (a detail at one end of a plain top) holds several: left out, the views
// would show part of the top.
constexpr double kLinkSpacings = 4.0;
constexpr size_t kStrayMatches = 2;

std::vector<size_t> one_region(const std::vector<Placed>& cand, const std::vector<size_t>& in) {
  const size_t n = in.size();
  if (n < 3) return in;
  const auto d = [&](size_t i, size_t j) { return (cand[in[i]].p2 - cand[in[j]].p2).norm(); };
  std::vector<double> nearest(n, INFINITY);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j) {
      const double dij = d(i, j);
      nearest[i] = std::min(nearest[i], dij);
      nearest[j] = std::min(nearest[j], dij);
    }
  std::vector<double> sorted = nearest;
  std::nth_element(sorted.begin(), sorted.begin() + n / 2, sorted.end());
  const double link_m = kLinkSpacings * sorted[n / 2];
  std::vector<size_t> root(n);
  for (size_t i = 0; i < n; ++i) root[i] = i;
  const auto find = [&](size_t i) {
    while (root[i] != i) i = root[i] = root[root[i]];
    return i;
  };
  for (size_t i = 0; i < n; ++i)
    for (size_t j = i + 1; j < n; ++j)
      if (d(i, j) <= link_m) root[find(i)] = find(j);
  std::vector<size_t> size(n, 0);
  for (size_t i = 0; i < n; ++i) ++size[find(i)];
  std::vector<size_t> kept;
  for (size_t i = 0; i < n; ++i)
    if (size[find(i)] > kStrayMatches) kept.push_back(in[i]);
  return kept;
}

// A gate of stage 3, the last: the matches that stay put inside the moving set's footprint (its
// rectangle on the top's plane in the current view, the inner kStillInner of it: at the assumed
// height the edges may be a few centimetres off). A cart hides the floor under it; a still top's
// own matches stay where they were. Still: carried by the known floor (a still top's parallax
// over a short baseline may be under floor_tol_px), or a candidate that moves only by the height
// error's scale about the cameras' nadirs (at most max_scale_change times their horizontal shift).
constexpr double kStillInner = 0.8;

int still_inside(const Correspondences& c, const std::vector<Placed>& cand,
                 const std::vector<uint8_t>& carried, const std::vector<size_t>& in,
                 const TopRect& rect, const Views& v, double floor_z_m,
                 const MovingTopParams& params) {
  const double z_top = floor_z_m + params.top_height_m;
  std::vector<uint8_t> moving(c.size(), 0);
  for (size_t k : in) moving[cand[k].index] = 1;
  const auto inside = [&](const Vector3d& P) {
    for (int i = 0; i < 2; ++i) {
      const double x = rect.axis[i].dot(P - rect.origin_W);
      const double mid = 0.5 * (rect.lo[i] + rect.hi[i]), half = 0.5 * (rect.hi[i] - rect.lo[i]);
      if (std::abs(x - mid) > kStillInner * half) return false;
    }
    return true;
  };
  const double shift = (v.X_WC2.translation() - v.X_WC1.translation()).head<2>().norm();
  int n = 0;
  for (const Placed& m : cand)
    if (!moving[m.index] && (m.p2 - m.p1).norm() <= m.tol_m + params.max_scale_change * shift &&
        inside(Vector3d(m.p2.x(), m.p2.y(), z_top)))
      ++n;
  for (size_t i = 0; i < c.size(); ++i) {
    if (!carried[i]) continue;
    const auto P =
        ray_at_height(v.X_WC2.translation(), v.X_WC2.linear() * c.camera->ray(c.u2[i]), z_top);
    if (P && inside(*P)) ++n;
  }
  return n;
}

// A gate of stage 3: the set's own pixels under a still top and under the measured motion.
// Around each inlier's current feature (up to kMaxPatches of them, evenly spread over the set)
// a patch of (2 kPatchHalf + 1)^2 pixels, placed on the top's plane from view 2 and read in the
// earlier image where a still top had it and where the motion had it; each patch's zero-mean
// normalised cross-correlation with the current one, the best over shifts of up to
// kPatchSlackPx (both hypotheses alike: the poses' stamps and the exposure's smear misplace a
// frame by a pixel or two, and a fine print decorrelates within one). Over a patch the map
// from the current image to the earlier one is affine to a small fraction of a pixel (the
// plane's homography across 9 pixels), so each is read once on a grid widened by the slack and
// the shifts are steps on that grid. A patch the still top had outside the earlier image is
// explained by nothing there (-1); one the two hypotheses place within a patch's width of each
// other has no vote (they read the same pixels: a platform creeping a few millimetres a frame,
// whose measured speed is harmless either way). ncc_still / ncc_moving: the medians over the
// patches that vote, NaN when none does.
constexpr int kPatchHalf = 4;
constexpr int kPatchSlackPx = 2;
constexpr size_t kMaxPatches = 32;
constexpr int kPatchSide = 2 * kPatchHalf + 1;
constexpr int kGridSide = kPatchSide + 2 * kPatchSlackPx;

// The earlier image on the grid around a patch: m0 the centre's pixel there, J the map's
// derivative (columns: per current pixel along x, y). False where the grid leaves the image.
bool read_grid(const cv::Mat& gray_1, const Vector2d& m0, const Eigen::Matrix2d& J, double* grid) {
  constexpr int h = kPatchHalf + kPatchSlackPx;
  for (int j = -h; j <= h; ++j)
    for (int i = -h; i <= h; ++i)
      if (!bilinear_inside(gray_1, m0 + J * Vector2d(i, j), &grid[(j + h) * kGridSide + i + h]))
        return false;
  return true;
}

// The best zero-mean normalised cross-correlation of the current patch with the grid's windows.
double best_window_ncc(const double* now, const double* grid) {
  constexpr double n = kPatchSide * kPatchSide;
  double mn = 0, vn = 0;
  for (int k = 0; k < kPatchSide * kPatchSide; ++k) mn += now[k] / n;
  for (int k = 0; k < kPatchSide * kPatchSide; ++k) vn += (now[k] - mn) * (now[k] - mn);
  double best = -1;
  for (int sy = 0; sy <= 2 * kPatchSlackPx; ++sy)
    for (int sx = 0; sx <= 2 * kPatchSlackPx; ++sx) {
      double s = 0, ss = 0, sc = 0;
      for (int j = 0; j < kPatchSide; ++j)
        for (int i = 0; i < kPatchSide; ++i) {
          const double g = grid[(j + sy) * kGridSide + i + sx];
          s += g, ss += g * g, sc += g * (now[j * kPatchSide + i] - mn);
        }
      const double vg = ss - s * s / n;
      if (vn > 0 && vg > 0) best = std::max(best, sc / std::sqrt(vn * vg));
    }
  return best;
}

void patch_ncc(const Correspondences& c, const std::vector<Placed>& cand,
               const std::vector<size_t>& in, const Similarity2& S, const Views& v, double z_top,
               const cv::Mat& gray_1, const cv::Mat& gray_2, MovingTop* out) {
  const Isometry3d X_C1W = v.X_WC1.inverse();
  const double cs = std::cos(S.theta), sn = std::sin(S.theta);
  // A point on the top's plane's pixel in the earlier image under each hypothesis (still: where
  // it is; moving: S^-1 of it).
  const auto map = [&](const Vector2d& xy, bool moved) -> std::optional<Vector2d> {
    Vector2d at = xy;
    if (moved) {
      const Vector2d d = (xy - S.t) / S.s;
      at = Vector2d(cs * d.x() + sn * d.y(), -sn * d.x() + cs * d.y());
    }
    const Vector3d p_C1 = X_C1W * Vector3d(at.x(), at.y(), z_top);
    if (!(p_C1.z() > 0)) return std::nullopt;
    return c.pixel1(p_C1);
  };
  // The patch's centre and edges (central differences) placed on the top's plane once, from the
  // current view; their images give each hypothesis's centre and the map's derivative.
  const Vector2d kEdges[5] = {
      {0, 0}, {kPatchHalf, 0}, {-kPatchHalf, 0}, {0, kPatchHalf}, {0, -kPatchHalf}};
  const auto affine = [&](const Vector2d(&xy)[5], bool moved, Vector2d* m0, Eigen::Matrix2d* J) {
    std::optional<Vector2d> m[5];
    for (int e = 0; e < 5; ++e)
      if (!(m[e] = map(xy[e], moved))) return false;
    *m0 = *m[0];
    J->col(0) = (*m[1] - *m[2]) / (2.0 * kPatchHalf);
    J->col(1) = (*m[3] - *m[4]) / (2.0 * kPatchHalf);
    return true;
  };
  const double step = std::max(1.0, double(in.size()) / kMaxPatches);
  std::vector<double> stills, moveds;
  double now[kPatchSide * kPatchSide], grid[kGridSide * kGridSide];
  for (double f = 0; f < double(in.size()); f += step) {
    const Vector2d u0 = c.u2[cand[in[size_t(f)]].index].array().round();
    if (!(u0.x() >= kPatchHalf && u0.y() >= kPatchHalf && u0.x() < gray_2.cols - kPatchHalf &&
          u0.y() < gray_2.rows - kPatchHalf))
      continue;
    for (int j = 0; j < kPatchSide; ++j)
      for (int i = 0; i < kPatchSide; ++i)
        now[j * kPatchSide + i] =
            gray_2.at<uint8_t>(int(u0.y()) + j - kPatchHalf, int(u0.x()) + i - kPatchHalf);
    Vector2d xy[5];
    bool placed = true;
    for (int e = 0; e < 5 && placed; ++e) {
      const auto P = ray_at_height(v.X_WC2.translation(),
                                   v.X_WC2.linear() * c.ray_of_pixel2(u0 + kEdges[e]), z_top);
      if ((placed = P.has_value())) xy[e] = P->head<2>();
    }
    Vector2d m_moved, m_still;
    Eigen::Matrix2d J_moved, J_still;
    if (!placed || !affine(xy, true, &m_moved, &J_moved) ||
        !read_grid(gray_1, m_moved, J_moved, grid))
      continue;
    const bool still_mapped = affine(xy, false, &m_still, &J_still);
    if (still_mapped && (m_still - m_moved).norm() < kPatchSide) continue;
    const double moving = best_window_ncc(now, grid);
    double still = -1;
    if (still_mapped && read_grid(gray_1, m_still, J_still, grid))
      still = best_window_ncc(now, grid);
    stills.push_back(still);
    moveds.push_back(moving);
  }
  out->ncc_still = stills.empty() ? NAN : upper_median(stills);
  out->ncc_moving = moveds.empty() ? NAN : upper_median(moveds);
}

// Whether the inliers come within margin_px of two opposite borders of the current image.
bool fills_view_across(const Correspondences& c, const std::vector<Placed>& cand,
                       const std::vector<size_t>& in, double margin_px) {
  const double w = c.camera->width - 0.5 - margin_px, h = c.camera->height - 0.5 - margin_px;
  const double lo = -0.5 + margin_px;
  bool left = false, right = false, top = false, bottom = false;
  for (size_t k : in) {
    const Vector2d& u = c.u2[cand[k].index];
    left = left || u.x() < lo;
    right = right || u.x() > w;
    top = top || u.y() < lo;
    bottom = bottom || u.y() > h;
  }
  return (left && right) || (top && bottom);
}

// A cut top's horizontal position variance: no information [m^2].
constexpr double kCutPositionVar = 100.0;
// A yaw known only to the quarter turn (the rectangle of a part of the top, or of too few
// features): uniform over it [rad^2].
constexpr double kUnknownYawVar = (M_PI / 4) * (M_PI / 4) / 3;

// The variance of the rectangle's yaw (of pts_W, whose rectangle has yaw_rad), the top's axes
// modulo a quarter turn. The minimum-area rectangle's orientation rests on the few features
// nearest the edges, so its error is not the similarity's turn between the frames: it is
// estimated from the rectangles of kYawSplits interleaved subsets, whose yaws each carry about
// kYawSplits times the variance of the whole set's (the split-sample estimate: the spread of
// the subsets' yaws about their mean over kYawSplits (kYawSplits - 1)). Too few features for
// the subsets: the variance of a yaw known only to the quarter turn.
constexpr int kYawSplits = 4;
double rect_yaw_variance(const std::vector<Vector3d>& pts_W, double yaw_rad) {
  if (pts_W.size() < 4 * kYawSplits) return kUnknownYawVar;
  double d[kYawSplits];
  double mean = 0;
  for (int k = 0; k < kYawSplits; ++k) {
    std::vector<Vector3d> sub;
    for (size_t i = k; i < pts_W.size(); i += kYawSplits) sub.push_back(pts_W[i]);
    const auto rect = features_extent(sub, Vector3d::UnitZ());
    if (!rect) return kUnknownYawVar;
    const double a = std::atan2(rect->axis[0].y(), rect->axis[0].x());
    d[k] = std::remainder(a - yaw_rad, M_PI / 2);  // the axes modulo a quarter turn
    mean += d[k] / kYawSplits;
  }
  double ss = 0;
  for (const double x : d) ss += (x - mean) * (x - mean);
  return std::min(kUnknownYawVar, ss / (kYawSplits * (kYawSplits - 1)));
}

// Stage 4: the measurement of the accepted set: its rectangle (centre, size, yaw) at the
// current exposure, its velocity, turn and heave over the interval, and their covariances from
// the fit's residuals and the height's uncertainty (moving_top.hpp).
// edges: the top's rectangle out to its edges (moving_edges.hpp) with its yaw's variance, where
// found; else the features' rectangle widened by their shortfall.
void measure(const std::vector<Placed>& cand, const std::vector<size_t>& in, const Similarity2& S,
             const Views& v, double dt_s, double floor_z_m, const MovingTopParams& params,
             const std::optional<EdgesRect>& edges, MovingTop* out) {
  const double n = double(in.size());
  std::vector<Vector3d> pts_W;
  Vector2d m1 = Vector2d::Zero(), m2 = Vector2d::Zero();
  double r2_sum = 0, spread = 0;
  for (size_t k : in) {
    m1 += cand[k].p1, m2 += cand[k].p2;
    r2_sum += (S.apply(cand[k].p1) - cand[k].p2).squaredNorm();
  }
  m1 /= n, m2 /= n;
  const double z_top = floor_z_m + params.top_height_m;
  for (size_t k : in) {
    pts_W.emplace_back(cand[k].p2.x(), cand[k].p2.y(), z_top);
    spread += (cand[k].p2 - m2).squaredNorm();
  }
  const auto features = features_extent(pts_W, Vector3d::UnitZ());
  assert(features);  // the size gate ran on the same points
  const TopRect* rect = edges ? &edges->rect : &*features;
  Vector3d centre = rect->origin_W;
  for (int a = 0; a < 2; ++a) centre += 0.5 * (rect->lo[a] + rect->hi[a]) * rect->axis[a];
  const TopRect wide = edges ? *rect : widened_by_shortfall(*rect, in.size());
  out->edges = edges.has_value();
  out->size_m[0] = wide.hi[0] - wide.lo[0];
  out->size_m[1] = wide.hi[1] - wide.lo[1];
  out->yaw_rad = wrap_axis_angle(std::atan2(rect->axis[0].y(), rect->axis[0].x()));
  out->yaw_rate_rps = S.theta / dt_s;
  out->scale = S.s;
  out->camera_W = v.X_WC2.translation();
  out->ref_camera_W = v.X_WC1.translation();
  out->plane_z_m = z_top;
  // Heave: the reference's points at the assumed height (k_1 = 1), so s = k_2.
  const double zc2 = v.X_WC2.translation().z();
  const double d2 = zc2 - z_top;
  const double dz = d2 - d2 / S.s;
  out->p_W = Vector3d(centre.x(), centre.y(), z_top + dz);
  // The matches' mean displacement is the velocity of their centroid; the top turns about its
  // own axis, so the point reported (the rectangle's centre, away from the centroid where the
  // features cluster on one side or the view shows only part of the top) moves at that plus the
  // turn's lever arm: it came from where the turn back by theta puts it, relative to the
  // centroid's current place.
  const Vector2d lever = centre.head<2>() - m2;
  const Vector2d vel = (m2 - m1 + lever - Eigen::Rotation2Dd(-S.theta) * lever) / dt_s;
  out->v_W = Vector3d(vel.x(), vel.y(), dz / dt_s);

  // Residuals: per axis, 4 parameters fitted over 2n coordinates.
  const double var_r = r2_sum / std::max(1.0, 2 * n - 4);
  const double var_s =
      set_covariances(var_r, n, spread, centre.head<2>(), vel, v.X_WC1.translation(),
                      v.X_WC2.translation(), dt_s, params, out);
  if (out->cut) out->cov_p_W.topLeftCorner<2, 2>() = kCutPositionVar * Eigen::Matrix2d::Identity();
  // The turn between the frames has the scale's variance (same residuals, same spread); the
  // yaw itself is the rectangle's, known far less well, and not at all on a top cut by the
  // border.
  out->var_yaw =
      out->cut ? kUnknownYawVar
               : std::max(var_s, edges ? edges->var_yaw : rect_yaw_variance(pts_W, out->yaw_rad));
}

}  // namespace

MovingTop find_moving_top(const Correspondences& c, double dt_s, double floor_z_m,
                          const MovingTopParams& params, const cv::Mat& gray_1,
                          const cv::Mat& gray_2) {
  assert(c.camera && c.mount && dt_s > 0);
  MovingTop out;
  out.dt_s = dt_s;
  out.inliers.assign(c.size(), 0);
  const auto refuse = [&](MovingReason r) {
    out.reason = r;
    return out;
  };
  Views v;
  v.X_WC1 = camera_in_world(c.pose_1.X_WB(), c.mount->X_BC());
  v.X_WC2 = camera_in_world(c.pose_2.X_WB(), c.mount->X_BC());
  v.focal_px = c.camera->K()(0, 0);
  const double z_top = floor_z_m + params.top_height_m;
  if (!(v.X_WC1.translation().z() > z_top + 0.05 && v.X_WC2.translation().z() > z_top + 0.05))
    return refuse(MovingReason::kNotAboveFloor);

  std::vector<uint8_t> carried;
  const std::vector<Placed> cand = place_candidates(c, v, floor_z_m, params, &carried);
  out.n_candidates = static_cast<int>(cand.size());
  if (out.n_candidates < params.min_inliers) return refuse(MovingReason::kTooFewCandidates);
  Similarity2 S;
  std::vector<size_t> in = platform_motion(cand, dt_s, params, &S, &out.reason);
  if (out.reason == MovingReason::kOk) {
    const size_t n_motion = in.size();
    in = one_region(cand, in);
    if (int(in.size()) < params.min_inliers)
      out.reason = MovingReason::kNoCommonMotion;
    else if (in.size() < n_motion)  // the motion of the top's own matches
      if (const auto S_top = fit_on(cand, in)) S = *S_top;
  }
  out.n_inliers = static_cast<int>(in.size());
  if (out.reason != MovingReason::kOk) return out;
  for (size_t k : in) out.inliers[cand[k].index] = 1;

  // Stage 3, the other gates: a size and a still top's explanation (moving_top.hpp).
  std::vector<Vector3d> pts_W;
  for (size_t k : in) pts_W.emplace_back(cand[k].p2.x(), cand[k].p2.y(), z_top);
  const auto rect = features_extent(pts_W, Vector3d::UnitZ());
  if (rect) out.size_m[0] = rect->hi[0] - rect->lo[0], out.size_m[1] = rect->hi[1] - rect->lo[1];
  // A top cut by the current image's border (close over it, it fills the view) still moves as
  // a whole, but its visible part's centre is not its centre: its motion is measured, its
  // position is not (and a cut top may be narrow).
  out.cut = std::any_of(in.begin(), in.end(), [&](size_t k) {
    return !c.camera->in_image(c.u2[cand[k].index], params.edge_margin_px);
  });
  if (!rect || (!out.cut && rect->hi[1] - rect->lo[1] < params.min_size_m) ||
      rect->hi[0] - rect->lo[0] > params.max_size_m)
    return refuse(MovingReason::kSizeOutOfRange);
  if (still_inside(c, cand, carried, in, *rect, v, floor_z_m, params) >=
      kStillShare * out.n_inliers)
    return refuse(MovingReason::kStillTop);
  if (!gray_1.empty() && !gray_2.empty()) {
    assert(gray_1.type() == CV_8UC1 && gray_2.type() == CV_8UC1);
    patch_ncc(c, cand, in, S, v, z_top, gray_1, gray_2, &out);
    if (out.ncc_still >= out.ncc_moving - kStillNccGap) return refuse(MovingReason::kStillPixels);
  }
  // Stage 4: the top's edges by its motion, on a top seen whole (moving_edges.hpp).
  std::optional<EdgesRect> edges;
  if (!out.cut && !gray_1.empty() && !gray_2.empty())
    edges = edges_by_motion(c, v.X_WC1, v.X_WC2, S, z_top, floor_z_m, *rect, pts_W, params, gray_1,
                            gray_2);
  measure(cand, in, S, v, dt_s, floor_z_m, params, edges, &out);
  // Inliers near two opposite borders: the top fills the view across, and the inliers' extent is
  // the view's footprint, not the top's; where the footprint is about the top's size, it read as
  // the whole top and placed the top's centre under the camera. No extent is measured.
  if (fills_view_across(c, cand, in, params.edge_margin_px)) out.size_m[0] = out.size_m[1] = 0;
  return out;
}

}  // namespace alight::vision
