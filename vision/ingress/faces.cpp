// Ingress stage 3, the faces (beyond paper 3.3: eq. 2 for each face's plane; see faces.hpp).
#include "vision/ingress/faces.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "vision/geometry/pixel_rays.hpp"

namespace alight::vision {
namespace {

// The search reaches as far as a face this thick can show in perspective: a thick outer wall
// with its lining (the scene families' walls are 5-30 cm).
constexpr double kMaxWallThicknessM = 0.4;
// A face shows where the two views' difference, a line's mean, rises by more than the noise of
// the smoothed images' difference (grey levels).
constexpr double kFaceMinRise = 2.0;
// The strip starts on the first pixel beyond the cut (the cut is rounded to a pixel, so its own
// may lie on either side of the edge). A face's points that tell it from the wall are its
// deepest, next to its far edge where the cut lies, and a face a few pixels wide has no others:
// leaving out two sigma of the smoothing, where the room's difference spreads over the border,
// would leave such a face unseen, and that spread adds to the face's and the wall's models
// alike.
constexpr int kFaceFirstPx = 1;

// One side's search: the cut line, the offsets k0 .. k_end searched towards the wall, the front
// edge's candidates up to e_max, and the wall's motion to compare the views by.
struct FaceSearch {
  const CutGeometry& g;
  int side;
  bool vertical;
  double a0, b, mean_along;  // the cut, its across-coordinate rounded at its centre
  int n_across, k0, k_end, e_max;
  Matrix3d R_12;
  Vector3d t_12, n2, c1_2;  // n2~ of the wall (n2~^T X2 = 1 on it); camera 1's centre in camera 2

  Vector2d pixel(double along, double across) const {
    return vertical ? Vector2d(across, along) : Vector2d(along, across);
  }
  // The reference's value where the plane n~ (camera 2, n~^T X = 1) puts the point seen along
  // ray r2, bilinear; nullopt off the reference or behind a camera.
  std::optional<float> reference_at(const Vector3d& n, const Vector3d& r2) const {
    const double den = n.dot(r2);
    if (!(den > 0)) return std::nullopt;
    const auto u1 = g.camera->project(R_12 * (r2 / den) + t_12);
    if (!u1 || !(u1->x() >= 0 && u1->y() >= 0 && u1->x() <= g.reference.cols - 2 &&
                 u1->y() <= g.reference.rows - 2))
      return std::nullopt;
    const int x = static_cast<int>(u1->x()), y = static_cast<int>(u1->y());
    const float fx = static_cast<float>(u1->x() - x), fy = static_cast<float>(u1->y() - y);
    const uint8_t* r0 = g.reference.ptr<uint8_t>(y) + x;
    const uint8_t* r1 = g.reference.ptr<uint8_t>(y + 1) + x;
    return (1 - fy) * ((1 - fx) * r0[0] + fx * r0[1]) + fy * ((1 - fx) * r1[0] + fx * r1[1]);
  }
};

// The strip: whole rows (lines across the side) of k0 .. k_end px towards the wall, every few
// along the side (the cost, not the answer, grows with them), kept only where the wall model
// sees every pixel, so every candidate sums the same pixels. Row-major, n_k a row.
struct FaceStrip {
  int n_k = 0, n_rows = 0;
  std::vector<Vector3d> ray;
  std::vector<float> current, wall_diff;
};
FaceStrip read_strip(const FaceSearch& s, int lo, int hi) {
  constexpr int kMaxRows = 48;
  FaceStrip f;
  f.n_k = s.k_end - s.k0 + 1;
  // A lens's rays are kept per pixel (pixel_rays.hpp); without one a ray is two divisions.
  PixelRays* rays = s.g.camera->has_distortion() ? &pixel_rays(*s.g.camera) : nullptr;
  const int step = std::max(1, (hi - lo + 1 + kMaxRows - 1) / kMaxRows);
  for (int t = lo; t <= hi; t += step) {
    const int x0 = static_cast<int>(std::lround(s.a0 + s.b * (t - s.mean_along)));
    bool whole = true;
    const size_t begin = f.ray.size();
    for (int k = s.k0; k <= s.k_end && whole; ++k) {
      const int x = x0 + s.side * k;
      if (x < 0 || x >= s.n_across) {
        whole = false;
        break;
      }
      const Vector2d u = s.pixel(t, x);
      const Vector3d r =
          rays ? rays->at(static_cast<int>(u.x()), static_cast<int>(u.y())) : s.g.camera->ray(u);
      const auto ref = s.reference_at(s.n2, r);
      if (!ref) {
        whole = false;
        break;
      }
      const float cur = s.g.image.at<uint8_t>(static_cast<int>(u.y()), static_cast<int>(u.x()));
      f.ray.push_back(r), f.current.push_back(cur), f.wall_diff.push_back(std::abs(cur - *ref));
    }
    if (!whole) {
      f.ray.resize(begin), f.current.resize(begin), f.wall_diff.resize(begin);
    }
  }
  f.n_rows = static_cast<int>(f.ray.size()) / f.n_k;
  return f;
}

// The face plane (n~ in camera 2) through the front edge e px out from the cut along the wall's
// normal; nullopt where the edge's line is off the wall, seen edge-on, or camera 1 sees the
// face from behind.
std::optional<Vector3d> face_plane(const FaceSearch& s, int e, double along_lo, double along_hi) {
  auto on_wall = [&](double along) -> std::optional<Vector3d> {
    const Vector3d r = s.g.camera->ray(
        s.pixel(along, s.a0 + s.b * (along - s.mean_along) + s.side * static_cast<double>(e)));
    const double den = s.n2.dot(r);
    if (!(den > 0)) return std::nullopt;
    return Vector3d(r / den);
  };
  const auto X_lo = on_wall(along_lo), X_hi = on_wall(along_hi);
  if (!X_lo || !X_hi) return std::nullopt;
  const Vector3d m = s.n2.normalized().cross(*X_hi - *X_lo);
  const double offset = m.dot(*X_lo);
  if (!(std::abs(offset) > 1e-9 * m.norm() * X_lo->norm())) return std::nullopt;  // edge-on
  const Vector3d face = m / offset;                                               // n~
  if (!(face.dot(s.c1_2) < 1)) return std::nullopt;  // camera 1 on the face's far side
  return face;
}

// cost[e - k0]: the face's model over k0 <= k < e, the wall's beyond (e = k0: no face); infinity
// where a candidate could not be read. Past the least the cost only rises (the face's model
// takes in more of the wall): the search stops once a candidate two or more beyond the least
// has risen kFaceStopRise a line above it (`risen`), and a candidate's sum stops there too:
// the candidates' pixels grow with the square of the reach.
constexpr double kFaceStopRise = 20.0;  // grey levels a line: ten times kFaceMinRise
struct FaceCosts {
  std::vector<double> cost;
  bool risen = false;
};
FaceCosts face_costs(const FaceSearch& s, const FaceStrip& f, int lo, int hi) {
  const int n_k = f.n_k, n_rows = f.n_rows, k0 = s.k0;
  // wall_from[j]: the wall model's difference summed over k >= k0 + j.
  std::vector<double> wall_from(n_k + 1, 0.0);
  for (int j = n_k - 1; j >= 0; --j) {
    wall_from[j] = wall_from[j + 1];
    for (int r = 0; r < n_rows; ++r) wall_from[j] += f.wall_diff[r * n_k + j];
  }
  FaceCosts c;
  c.cost.assign(s.e_max - k0 + 1, std::numeric_limits<double>::infinity());
  c.cost[0] = wall_from[0];
  double least_so_far = c.cost[0];
  int best_so_far = 0;
  const double stop = kFaceStopRise * n_rows;
  for (int e = k0 + 1; e <= s.e_max; ++e) {
    const auto face = face_plane(s, e, lo, hi);
    if (!face) continue;
    double sum = wall_from[e - k0];
    bool ok = true;
    const bool may_stop = e - k0 >= best_so_far + 2;
    bool stopped = false;
    for (int r = 0; r < n_rows && ok && !stopped; ++r) {
      for (int j = 0; j < e - k0; ++j) {
        const auto ref = s.reference_at(*face, f.ray[r * n_k + j]);
        if (!ref) {
          ok = false;
          break;
        }
        sum += std::abs(f.current[r * n_k + j] - *ref);
      }
      stopped = may_stop && sum - least_so_far >= stop;
    }
    if (stopped) {
      c.risen = true;
      break;
    }
    if (!ok) continue;
    c.cost[e - k0] = sum;
    if (sum < least_so_far) least_so_far = sum, best_so_far = e - k0;
  }
  return c;
}

// The front edge is the least cost's candidate, to a fraction of a pixel by the parabola
// through it and its neighbours (the cost falls as the face's model takes in more of the face
// and rises once it takes in the wall beyond its front edge). Not the farthest candidate near
// the least: where the face's texture is faint the cost is flat over pixels either side of the
// front edge, and the farthest of them widens the opening. A strip whose cost never rises by
// kFaceMinRise grey levels a line tells the face from the wall nowhere (a smooth wall): a
// unchanged.
double least_cost_edge(const FaceSearch& s, const FaceCosts& c, int n_rows, double a) {
  const std::vector<double>& cost = c.cost;
  double least = std::numeric_limits<double>::infinity(), most = 0;
  int best = -1;
  for (int i = 0; i < static_cast<int>(cost.size()); ++i)
    if (std::isfinite(cost[i])) {
      if (cost[i] < least) least = cost[i], best = i;
      most = std::max(most, cost[i]);
    }
  if (best <= 0 || (!c.risen && (most - least) / n_rows < kFaceMinRise)) return a;
  double frac = 0;
  if (best + 1 < static_cast<int>(cost.size()) && std::isfinite(cost[best + 1]) &&
      std::isfinite(cost[best - 1])) {
    const double curvature = cost[best - 1] - 2 * cost[best] + cost[best + 1];
    if (curvature > 0)
      frac = std::clamp(0.5 * (cost[best - 1] - cost[best + 1]) / curvature, -0.5, 0.5);
  }
  return s.a0 + s.side * (best + s.k0 + frac);
}

}  // namespace

double face_front_edge(int side, bool vertical, double a, double b, double mean_along, int lo,
                       int hi, const CutGeometry& g) {
  if (!g.camera || g.image.empty() || g.reference.size() != g.image.size() ||
      !(g.wall_depth_m > 0) || !std::isfinite(g.wall_depth_m))
    return a;
  const double centre = vertical ? g.principal_px.x() : g.principal_px.y();
  if (side == 0 || (a - centre) * side <= 0) return a;
  const int n_across = vertical ? g.image.cols : g.image.rows;
  const double reach =
      std::min(std::abs(a - centre) * kMaxWallThicknessM / g.wall_depth_m, 0.25 * n_across);
  const int e_max = static_cast<int>(std::floor(reach));
  const int k0 = kFaceFirstPx;
  const int k_end = e_max + k0 + 8;  // beyond the farthest front edge: the wall's own level
  if (e_max <= k0) return a;
  const Vector3d n2 = g.wall.n_2();
  if (!n2.allFinite()) return a;
  const FaceSearch s{g,
                     side,
                     vertical,
                     std::round(a),
                     b,
                     mean_along,
                     n_across,
                     k0,
                     k_end,
                     e_max,
                     g.wall.R_21.transpose(),
                     g.wall.t_12,
                     n2,
                     -(g.wall.R_21 * g.wall.t_12)};
  const FaceStrip strip = read_strip(s, lo, hi);
  if (strip.n_rows < 4) return a;
  return least_cost_edge(s, face_costs(s, strip, lo, hi), strip.n_rows, a);
}

OpeningBox to_front_edges(const OpeningBox& box, cv::Size image_size, const CutGeometry& geometry) {
  const double w = box.right - box.left, h = box.bottom - box.top;
  auto span = [](double from, double to, int n) {
    return std::pair{std::clamp(static_cast<int>(std::ceil(from)), 0, n - 1),
                     std::clamp(static_cast<int>(std::floor(to)), 0, n - 1)};
  };
  const auto [y_lo, y_hi] = span(box.top + 0.1 * h, box.bottom - 0.1 * h, image_size.height);
  const auto [x_lo, x_hi] = span(box.left + 0.1 * w, box.right - 0.1 * w, image_size.width);
  const double y_mid = 0.5 * (box.top + box.bottom), x_mid = 0.5 * (box.left + box.right);
  return {face_front_edge(-1, true, box.left, 0, y_mid, y_lo, y_hi, geometry),
          face_front_edge(+1, true, box.right, 0, y_mid, y_lo, y_hi, geometry),
          face_front_edge(-1, false, box.top, 0, x_mid, x_lo, x_hi, geometry),
          face_front_edge(+1, false, box.bottom, 0, x_mid, x_lo, x_hi, geometry)};
}

}  // namespace alight::vision
