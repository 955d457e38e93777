// A moving platform's top from its outline in two frames (beyond paper 3.2; see
// moving_outline.hpp): the corners placed on the top's plane from each view, a still rectangle
// set aside, the earlier outline paired by the least turn, the gates, the measurement.
#include "vision/landing/moving_outline.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <optional>

namespace alight::vision {
namespace {

struct Camera {
  Isometry3d X_WC;
  const Correspondences* c = nullptr;
  bool current = true;  // camera 2 (else the reference's, camera 1)
  Vector3d ray_W(const Vector2d& u) const {
    return X_WC.linear() * (current ? c->ray_of_pixel2(u) : c->ray_of_pixel1(u));
  }
  std::optional<Vector2d> pixel(const Vector3d& p_W) const {
    const Vector3d p_C = X_WC.inverse() * p_W;
    if (!(p_C.z() > 1e-6)) return std::nullopt;
    return current ? c->pixel2(p_C) : c->pixel1(p_C);
  }
};

// One outline's corners as rays: where each meets the level plane z is a + b z (xy).
struct Placed {
  std::array<Vector2d, 4> a, b;
  bool dark = true;
  bool ok = false;
  Vector2d at(int i, double z) const { return a[i] + b[i] * z; }
};

// Stage 1: an outline's corner rays from its camera; not ok where one does not point down.
Placed place(const Outline& o, const Camera& cam) {
  assert(o.corners.size() == 4);
  Placed p;
  p.dark = o.dark;
  const Vector3d C = cam.X_WC.translation();
  for (int i = 0; i < 4; ++i) {
    const Vector3d d = cam.ray_W(o.corners[i]);
    if (!(d.z() < -1e-6)) return p;
    p.b[i] = d.head<2>() / d.z();
    p.a[i] = C.head<2>() - p.b[i] * C.z();
  }
  p.ok = true;
  return p;
}

// Stage 2: how well the earlier outline e, its corner (i + k) % 4 to now's corner i, is
// explained as a rectangle that stayed put at one height between the floor and the lower camera
// (z_lo, z_hi): the least-squares height where both views' rays meet, held within them (*h), each
// corner carried from the current view onto it and into the earlier image; the farthest
// corner's distance from e's [px] (infinite where one leaves the image).
double still_residual_px(const Placed& e, const Placed& now, int k, const Outline& e_px,
                         const Camera& cam_1, double z_lo, double z_hi, double* h) {
  double num = 0, den = 0;
  for (int i = 0; i < 4; ++i) {
    const int j = (i + k) % 4;
    const Vector2d da = now.a[i] - e.a[j], db = now.b[i] - e.b[j];
    num -= da.dot(db);
    den += db.squaredNorm();
  }
  // No parallax between the views (a camera that stayed put): any height carries the corners.
  *h = std::clamp(den > 1e-12 ? num / den : z_lo, z_lo, z_hi);
  double worst = 0;
  for (int i = 0; i < 4; ++i) {
    const auto u = cam_1.pixel(Vector3d(now.at(i, *h).x(), now.at(i, *h).y(), *h));
    if (!u) return INFINITY;
    worst = std::max(worst, (*u - e_px.corners[(i + k) % 4]).norm());
  }
  return worst;
}

struct Pair {
  Similarity2 S;
  int k = 0;
  size_t earlier = 0;
  double r2_sum = 0;  // squared residuals of the corners under S [m^2]
};

// The depth along the current camera's axis of a point [m]: a pixel there spans depth / f.
double depth_m(const Camera& cam, const Vector2d& xy, double z) {
  return (cam.X_WC.inverse() * Vector3d(xy.x(), xy.y(), z)).z();
}

// Stage 3: the earlier outline and corner order whose similarity on the top's plane carries
// every corner within kOutlinePairPx at its depth, with a scale within max_scale_change, of those
// the least turn.
std::optional<Pair> pair_outline(const std::vector<Placed>& earlier, const Placed& now,
                                 const Camera& cam_2, double z_top, double focal_px,
                                 const MovingTopParams& params) {
  std::optional<Pair> best;
  for (size_t e = 0; e < earlier.size(); ++e) {
    if (!earlier[e].ok || earlier[e].dark != now.dark) continue;
    for (int k = 0; k < 4; ++k) {
      std::vector<Vector2d> p, q;
      for (int i = 0; i < 4; ++i) {
        p.push_back(earlier[e].at((i + k) % 4, z_top));
        q.push_back(now.at(i, z_top));
      }
      const auto S = fit_similarity(p, q);
      if (!S || std::abs(S->s - 1) > params.max_scale_change) continue;
      double r2_sum = 0;
      bool fits = true;
      for (int i = 0; i < 4 && fits; ++i) {
        const double r = (S->apply(p[i]) - q[i]).norm();
        r2_sum += r * r;
        fits = r <= kOutlinePairPx * depth_m(cam_2, q[i], z_top) / focal_px;
      }
      if (fits && (!best || std::abs(S->theta) < std::abs(best->S.theta)))
        best = Pair{*S, k, e, r2_sum};
    }
  }
  return best;
}

// Stage 4, the size: the current corners' opposite sides' mean lengths (long, short) and the
// long sides' direction (the mean of the two, one reversed), on the top's plane.
struct Sides {
  double long_m = 0, short_m = 0, yaw_rad = 0;
};
Sides sides_of(const std::array<Vector2d, 4>& q) {
  const Vector2d e0 = q[1] - q[0], e1 = q[2] - q[1], e2 = q[3] - q[2], e3 = q[0] - q[3];
  const double a = 0.5 * (e0.norm() + e2.norm()), b = 0.5 * (e1.norm() + e3.norm());
  const Vector2d dir = a >= b ? Vector2d(e0 - e2) : Vector2d(e1 - e3);
  return {std::max(a, b), std::min(a, b), wrap_axis_angle(std::atan2(dir.y(), dir.x()))};
}

// Stage 5: the measurement (moving_top.hpp's fields) of the current corners q and the earlier
// ones p (in q's order) under S.
void measure(const std::array<Vector2d, 4>& p, const std::array<Vector2d, 4>& q, const Pair& pr,
             const Camera& cam_1, const Camera& cam_2, double dt_s, double z_top,
             const MovingTopParams& params, MovingTop* out) {
  Vector2d m1 = Vector2d::Zero(), m2 = Vector2d::Zero();
  for (int i = 0; i < 4; ++i) m1 += p[i] / 4, m2 += q[i] / 4;
  double spread = 0;
  for (int i = 0; i < 4; ++i) spread += (q[i] - m2).squaredNorm();
  const Sides sides = sides_of(q);
  out->size_m[0] = sides.long_m;
  out->size_m[1] = sides.short_m;
  out->yaw_rad = sides.yaw_rad;
  out->yaw_rate_rps = pr.S.theta / dt_s;
  out->scale = pr.S.s;
  out->camera_W = cam_2.X_WC.translation();
  out->ref_camera_W = cam_1.X_WC.translation();
  out->plane_z_m = z_top;
  // The heave as find_moving_top's: the earlier corners at the plane, so s is the current's.
  const double d2 = cam_2.X_WC.translation().z() - z_top;
  const double dz = d2 - d2 / pr.S.s;
  out->p_W = Vector3d(m2.x(), m2.y(), z_top + dz);
  const Vector2d vel = (m2 - m1) / dt_s;
  out->v_W = Vector3d(vel.x(), vel.y(), dz / dt_s);

  // The corners' variance: the fit's residuals (4 parameters over 8 coordinates), at least
  // kOutlineCornerPx at the top's depth.
  const double px_m = kOutlineCornerPx * depth_m(cam_2, m2, z_top) / cam_2.c->camera->K()(0, 0);
  const double var_r = std::max(pr.r2_sum / 4, px_m * px_m);
  const double var_s = set_covariances(var_r, 4, spread, m2, vel, cam_1.X_WC.translation(),
                                       cam_2.X_WC.translation(), dt_s, params, out);
  // The long sides' direction: two sides of length L, each end off by the corners' error.
  out->var_yaw = std::max(var_s, var_r / std::max(1e-6, sides.long_m * sides.long_m));
}

// Whether the points xy at times t (three) lie on one straight track at one speed: the
// least-squares line through them (per axis, over t) within tol_m of each.
bool on_one_track(const std::array<double, 3>& t, const std::array<Vector2d, 3>& xy, double tol_m) {
  const double mt = (t[0] + t[1] + t[2]) / 3;
  const Vector2d mx = (xy[0] + xy[1] + xy[2]) / 3;
  double stt = 0;
  Vector2d stx = Vector2d::Zero();
  for (int i = 0; i < 3; ++i) stt += (t[i] - mt) * (t[i] - mt), stx += (t[i] - mt) * (xy[i] - mx);
  if (!(stt > 0)) return false;
  const Vector2d v = stx / stt;
  for (int i = 0; i < 3; ++i)
    if ((xy[i] - (mx + v * (t[i] - mt))).norm() > tol_m) return false;
  return true;
}

}  // namespace

MovingTop find_moving_outline(const std::vector<EarlierOutlines>& earlier,
                              const std::vector<Outline>& now, const Correspondences& c,
                              double floor_z_m, const MovingTopParams& params, size_t* used) {
  assert(c.camera && c.mount && !now.empty());
  MovingTop out;
  out.outline = true;
  out.n_candidates = static_cast<int>(now.size());
  const Camera cam_2{camera_in_world(c.pose_2.X_WB(), c.mount->X_BC()), &c, true};
  const double focal_px = c.camera->K()(0, 0);
  const double z_top = floor_z_m + params.top_height_m;
  // Each earlier frame's camera and outlines placed (stage 1).
  struct View {
    Correspondences c;
    Camera cam;
    std::vector<Placed> placed;
  };
  std::vector<View> views;
  double z_low = cam_2.X_WC.translation().z();
  for (const EarlierOutlines& e : earlier) {
    assert(e.outlines && e.dt_s > 0);
    View v{c, {}, {}};
    v.c.pose_1 = e.pose;
    v.c.readout_1 = e.readout;
    v.c.grid_1 = nullptr;
    views.push_back(std::move(v));
  }
  for (size_t j = 0; j < views.size(); ++j) {
    View& v = views[j];
    v.cam = Camera{camera_in_world(v.c.pose_1.X_WB(), c.mount->X_BC()), &v.c, false};
    for (const Outline& o : *earlier[j].outlines) v.placed.push_back(place(o, v.cam));
    z_low = std::min(z_low, v.cam.X_WC.translation().z());
  }
  if (!(z_low > z_top + 0.05)) {
    out.reason = MovingReason::kNotAboveFloor;
    return out;
  }
  // The still rectangles set aside: the floor's and still tops' up to twice the assumed top's
  // height (kStillTopHeights). Any height a camera's motion leaves free would absorb a platform
  // moving along that motion.
  const double still_max_z =
      std::min(z_low - 0.05, floor_z_m + kStillTopHeights * params.top_height_m);

  std::optional<MovingReason> first;
  for (const Outline& o : now) {
    const Placed p2 = place(o, cam_2);
    if (!p2.ok) continue;
    // Stage 2, against every earlier frame interval_s old or more: a floor's pattern region is
    // found in most frames where it stays, and paired with a copy one period on in any other; a
    // younger frame leaves a slow platform's motion within the tolerance.
    std::optional<MovingReason> still;
    for (size_t j = 0; j < views.size() && !still; ++j) {
      if (earlier[j].dt_s < params.interval_s) continue;
      const View& v = views[j];
      const std::vector<Outline>& e_px = *earlier[j].outlines;
      for (size_t e = 0; e < v.placed.size() && !still; ++e) {
        if (!v.placed[e].ok || v.placed[e].dark != p2.dark) continue;
        for (int k = 0; k < 4 && !still; ++k) {
          double h = 0;
          if (still_residual_px(v.placed[e], p2, k, e_px[e], v.cam, floor_z_m - 0.05, still_max_z,
                                &h) <= kOutlineStillPx)
            still = h < floor_z_m + 0.5 * params.top_height_m ? MovingReason::kOnFloor
                                                              : MovingReason::kStillTop;
        }
      }
    }
    if (still) {
      if (!first) first = still;
      continue;
    }
    // Stage 3, in each earlier frame; then two of them, kMinOutlineSpanS apart or more, whose
    // earlier outlines' centres lie with the current one's on one track at one speed.
    std::vector<std::pair<size_t, Pair>> pairs;
    for (size_t j = 0; j < views.size(); ++j)
      if (const auto pr = pair_outline(views[j].placed, p2, cam_2, z_top, focal_px, params))
        pairs.emplace_back(j, *pr);
    const auto centre = [&](size_t j, const Pair& pr) {
      Vector2d m = Vector2d::Zero();
      for (int i = 0; i < 4; ++i) m += views[j].placed[pr.earlier].at(i, z_top) / 4;
      return m;
    };
    Vector2d m2 = Vector2d::Zero();
    for (int i = 0; i < 4; ++i) m2 += p2.at(i, z_top) / 4;
    const double tol_m = kOutlinePairPx * depth_m(cam_2, m2, z_top) / focal_px;
    std::optional<size_t> chosen;  // into pairs
    for (size_t a = 0; a < pairs.size(); ++a)
      for (size_t b = 0; b < pairs.size(); ++b) {
        const double ta = earlier[pairs[a].first].dt_s, tb = earlier[pairs[b].first].dt_s;
        if (!(tb - ta >= kMinOutlineSpanS)) continue;
        if (!on_one_track({0.0, -ta, -tb},
                          {m2, centre(pairs[a].first, pairs[a].second),
                           centre(pairs[b].first, pairs[b].second)},
                          tol_m))
          continue;
        // The longer interval measures the motion best.
        if (!chosen || earlier[pairs[b].first].dt_s > earlier[pairs[*chosen].first].dt_s)
          chosen = b;
      }
    if (!chosen) {
      if (!first) first = MovingReason::kOutlineUnpaired;
      continue;
    }
    const size_t j = pairs[*chosen].first;
    const Pair& pr = pairs[*chosen].second;
    const double dt_s = earlier[j].dt_s;
    std::array<Vector2d, 4> p, q;
    for (int i = 0; i < 4; ++i) {
      p[i] = views[j].placed[pr.earlier].at((i + pr.k) % 4, z_top);
      q[i] = p2.at(i, z_top);
    }
    // Stage 4.
    Vector2d shift = Vector2d::Zero();
    for (int i = 0; i < 4; ++i) shift += (q[i] - p[i]) / 4;
    const Sides sides = sides_of(q);
    const MovingReason why = motion_beyond_a_platform(shift.norm() / dt_s, pr.S, dt_s, params)
                                 ? MovingReason::kTooFast
                             : sides.short_m < params.min_size_m || sides.long_m > params.max_size_m
                                 ? MovingReason::kSizeOutOfRange
                                 : MovingReason::kOk;
    if (why != MovingReason::kOk) {
      if (!first) first = why;
      continue;
    }
    // Stage 5.
    out.dt_s = dt_s;
    out.n_inliers = 4;
    measure(p, q, pr, views[j].cam, cam_2, dt_s, z_top, params, &out);
    out.reason = MovingReason::kOk;
    if (used) *used = j;
    return out;
  }
  out.reason = first.value_or(MovingReason::kOutlineUnpaired);
  return out;
}

}  // namespace alight::vision
