#include "vision/landing/moving_edges.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <functional>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/geometry.hpp"

namespace alight::vision {
namespace {

// The grid's cell (i, j) is the plane's point origin + (i, j) cell_m, world axes.
struct Grid {
  int n = 0;
  double cell_m = 0;
  Vector2d origin = Vector2d::Zero();
  cv::Mat map_2, map_top, map_floor;  // CV_32FC2: each cell's pixel in the three readings
  cv::Mat in_view;                    // CV_8U: all three pixels inside their images
  cv::Mat separated;                  // CV_8U: the hypotheses kMinSeparationPx apart
  Vector2d at(double i, double j) const { return origin + cell_m * Vector2d(i, j); }
};

// The maps are smooth over the window: computed exactly every kMapStride cells and interpolated.
constexpr int kMapStride = 4;

// Stage 1: the window and each cell's pixels under the two hypotheses.
std::optional<Grid> cells(const Correspondences& c, const Isometry3d& X_WC1,
                          const Isometry3d& X_WC2, const Similarity2& S, double z_top,
                          double floor_z_m, const TopRect& features) {
  Vector2d lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
  for (const double a : {features.lo[0], features.hi[0]})
    for (const double b : {features.lo[1], features.hi[1]}) {
      const Vector2d p =
          (features.origin_W + a * features.axis[0] + b * features.axis[1]).head<2>();
      lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    }
  const Vector2d centre = 0.5 * (lo + hi);
  const double half = 0.5 * (hi - lo).maxCoeff() + kEdgeReachM;
  const double depth = X_WC2.translation().z() - z_top;
  if (!(depth > 0)) return std::nullopt;
  Grid g;
  g.cell_m = std::max(kCellGsd * depth / c.camera->K()(0, 0), 2 * half / (kMaxCells - 1));
  g.n = kMapStride * int(std::ceil(2 * half / g.cell_m / kMapStride)) + 1;
  g.origin = centre - 0.5 * (g.n - 1) * g.cell_m * Vector2d::Ones();
  const Isometry3d X_C1W = X_WC1.inverse(), X_C2W = X_WC2.inverse();
  const double cs = std::cos(S.theta), sn = std::sin(S.theta);
  const Vector3d o2 = X_WC2.translation();
  // The three pixels of a plane point (NaN where a ray misses its image's side of the camera).
  const auto pixels = [&](const Vector2d& xy, std::array<Vector2d, 3>* px) {
    const Vector2d nan(NAN, NAN);
    px->fill(nan);
    const Vector3d P(xy.x(), xy.y(), z_top);
    const Vector3d r2 = X_C2W * P;
    if (!(r2.z() > 0)) return;
    if (const auto u = c.pixel2(r2)) (*px)[0] = *u;
    const Vector2d d = (xy - S.t) / S.s;
    const Vector3d P1(cs * d.x() + sn * d.y(), -sn * d.x() + cs * d.y(), z_top);
    const Vector3d r1 = X_C1W * P1;
    if (r1.z() > 0)
      if (const auto u = c.pixel1(r1)) (*px)[1] = *u;
    if (const auto F = ray_at_height(o2, P - o2, floor_z_m)) {
      const Vector3d f1 = X_C1W * *F;
      if (f1.z() > 0)
        if (const auto u = c.pixel1(f1)) (*px)[2] = *u;
    }
  };
  const int nc = (g.n - 1) / kMapStride + 1;
  std::vector<std::array<Vector2d, 3>> nodes(size_t(nc) * nc);
  for (int j = 0; j < nc; ++j)
    for (int i = 0; i < nc; ++i)
      pixels(g.at(i * kMapStride, j * kMapStride), &nodes[size_t(j) * nc + i]);
  g.map_2.create(g.n, g.n, CV_32FC2);
  g.map_top.create(g.n, g.n, CV_32FC2);
  g.map_floor.create(g.n, g.n, CV_32FC2);
  g.in_view = cv::Mat::zeros(g.n, g.n, CV_8U);
  g.separated = cv::Mat::zeros(g.n, g.n, CV_8U);
  cv::Mat* maps[3] = {&g.map_2, &g.map_top, &g.map_floor};
  for (int j = 0; j < g.n; ++j) {
    const int cj = std::min(j / kMapStride, nc - 2);
    const double fj = double(j - cj * kMapStride) / kMapStride;
    for (int i = 0; i < g.n; ++i) {
      const int ci = std::min(i / kMapStride, nc - 2);
      const double fi = double(i - ci * kMapStride) / kMapStride;
      const auto& a = nodes[size_t(cj) * nc + ci];
      const auto& b = nodes[size_t(cj) * nc + ci + 1];
      const auto& e = nodes[size_t(cj + 1) * nc + ci];
      const auto& f = nodes[size_t(cj + 1) * nc + ci + 1];
      bool all_in = true;
      std::array<Vector2d, 3> u;
      for (int k = 0; k < 3; ++k) {
        u[k] = (1 - fj) * ((1 - fi) * a[k] + fi * b[k]) + fj * ((1 - fi) * e[k] + fi * f[k]);
        // Half a pixel in: every pixel bilinear reads is the image's (NaN is never in it).
        all_in = all_in && c.camera->in_image(u[k], 0.5);
        maps[k]->at<cv::Vec2f>(j, i) =
            all_in ? cv::Vec2f(float(u[k].x()), float(u[k].y())) : cv::Vec2f(-10.f, -10.f);
      }
      g.in_view.at<uint8_t>(j, i) = all_in;
      g.separated.at<uint8_t>(j, i) = all_in && (u[1] - u[2]).norm() >= kMinSeparationPx;
    }
  }
  return g;
}

enum Vote : uint8_t { kNone = 0, kTop = 1, kFloor = 2 };

// Stage 2: each cell's vote.
cv::Mat votes(const Grid& g, const cv::Mat& gray_1, const cv::Mat& gray_2) {
  const auto read = [&](const cv::Mat& gray, const cv::Mat& map) {
    cv::Mat r, f;
    cv::remap(gray, r, map, cv::noArray(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
    r.convertTo(f, CV_32F);
    cv::GaussianBlur(f, f, cv::Size(3, 3), 0);
    return f;
  };
  const cv::Mat now = read(gray_2, g.map_2);
  const auto msd = [&](const cv::Mat& earlier) {
    cv::Mat d = now - earlier, out;
    cv::boxFilter(d.mul(d), out, CV_32F, cv::Size(kPatchCells, kPatchCells));
    return out;
  };
  const cv::Mat d_top = msd(read(gray_1, g.map_top));
  const cv::Mat d_floor = msd(read(gray_1, g.map_floor));
  // A patch votes only where every cell of it is in view, and its centre's hypotheses apart.
  cv::Mat whole;
  cv::erode(g.in_view, whole, cv::Mat::ones(kPatchCells, kPatchCells, CV_8U), cv::Point(-1, -1), 1,
            cv::BORDER_CONSTANT, 0);
  const float r2 = float(kVoteRatio * kVoteRatio), m2 = float(kMinDiff * kMinDiff),
              e2 = float(kExplainedDiff * kExplainedDiff);
  cv::Mat v = cv::Mat::zeros(g.n, g.n, CV_8U);
  for (int j = 0; j < g.n; ++j)
    for (int i = 0; i < g.n; ++i) {
      if (!whole.at<uint8_t>(j, i) || !g.separated.at<uint8_t>(j, i)) continue;
      const float t = d_top.at<float>(j, i), f = d_floor.at<float>(j, i);
      if (t <= e2 && f > m2 && t <= r2 * f)
        v.at<uint8_t>(j, i) = kTop;
      else if (f <= e2 && t > m2 && f <= r2 * t)
        v.at<uint8_t>(j, i) = kFloor;
    }
  return v;
}

// A rectangle in grid coordinates: axis a at angle theta, b a quarter turn on; extents along each.
struct GridRect {
  explicit GridRect(double turn = 0) : theta(turn), cs(std::cos(turn)), sn(std::sin(turn)) {}
  double theta, cs, sn;
  double lo[2] = {0, 0}, hi[2] = {0, 0};
  double area() const { return (hi[0] - lo[0]) * (hi[1] - lo[1]); }
  Vector2d along(double x, double y) const { return {cs * x + sn * y, -sn * x + cs * y}; }
};

constexpr size_t kMaxRectPoints = 2000;

// The k-th smallest and the k-th largest of v (from 0; k < v.size()), in one pass: the k + 1
// smallest kept in a max-heap, the k + 1 largest in a min-heap. The same values as sorting would
// give; k is a small share of the points (kTrimShare), so most points are one comparison each,
// where selecting each end in the whole vector moves every point several times.
class TrimmedEnds {
 public:
  void of(const std::vector<double>& v, size_t k, double* lo, double* hi) {
    assert(k < v.size());
    low_.assign(v.begin(), v.begin() + k + 1);
    high_ = low_;
    std::make_heap(low_.begin(), low_.end(), std::less<>());
    std::make_heap(high_.begin(), high_.end(), std::greater<>());
    for (size_t i = k + 1; i < v.size(); ++i) {
      const double x = v[i];
      if (x < low_.front()) replace_top(low_, x, std::less<>());
      if (x > high_.front()) replace_top(high_, x, std::greater<>());
    }
    *lo = low_.front(), *hi = high_.front();
  }

 private:
  template <class Cmp>
  static void replace_top(std::vector<double>& h, double x, Cmp cmp) {
    std::pop_heap(h.begin(), h.end(), cmp);
    h.back() = x;
    std::push_heap(h.begin(), h.end(), cmp);
  }
  std::vector<double> low_, high_;
};

// Stage 3: the trimmed minimum-area rectangle of pts (grid coordinates), the turn searched by the
// degree and refined by the tenth.
GridRect trimmed_rect(const std::vector<Vector2d>& pts) {
  const size_t k = size_t(kTrimShare * double(pts.size()));
  std::vector<double> a(pts.size()), b(pts.size());
  TrimmedEnds ends;
  const auto at = [&](double theta) {
    GridRect r(theta);
    for (size_t i = 0; i < pts.size(); ++i) {
      const Vector2d p = r.along(pts[i].x(), pts[i].y());
      a[i] = p.x(), b[i] = p.y();
    }
    ends.of(a, k, &r.lo[0], &r.hi[0]);
    ends.of(b, k, &r.lo[1], &r.hi[1]);
    return r;
  };
  GridRect best = at(0);
  for (int d = 1; d < 90; ++d)
    if (const GridRect r = at(d * M_PI / 180); r.area() < best.area()) best = r;
  const double coarse = best.theta;
  for (int d = -10; d <= 10; ++d)
    if (const GridRect r = at(coarse + d * M_PI / 1800); r.area() < best.area()) best = r;
  return best;
}

// Stage 4: the rim all round, the floor kept out, in view, the features inside, a top's sizes.
bool passes(const GridRect& r, const cv::Mat& v, const Grid& g,
            const std::vector<Vector2d>& features, const MovingTopParams& params) {
  const double side[2] = {(r.hi[0] - r.lo[0]) * g.cell_m, (r.hi[1] - r.lo[1]) * g.cell_m};
  if (std::min(side[0], side[1]) < params.min_size_m ||
      std::max(side[0], side[1]) > params.max_size_m)
    return false;
  std::array<std::array<bool, kSideSegments>, 4> carried{};
  int inside = 0, floor_inside = 0;
  for (int j = 0; j < g.n; ++j)
    for (int i = 0; i < g.n; ++i) {
      const Vector2d p = r.along(i, j);
      const bool near = p.x() >= r.lo[0] - kBandCells && p.x() <= r.hi[0] + kBandCells &&
                        p.y() >= r.lo[1] - kBandCells && p.y() <= r.hi[1] + kBandCells;
      if (!near) continue;
      // Near the rectangle, every cell must be in view and inside the window.
      if (!g.in_view.at<uint8_t>(j, i) || i == 0 || j == 0 || i == g.n - 1 || j == g.n - 1)
        return false;
      const bool in = p.x() > r.lo[0] && p.x() < r.hi[0] && p.y() > r.lo[1] && p.y() < r.hi[1];
      if (!in) continue;
      ++inside;
      const uint8_t vote = v.at<uint8_t>(j, i);
      if (vote == kFloor) ++floor_inside;
      if (vote != kTop) continue;
      for (int ax = 0; ax < 2; ++ax) {
        const double x = ax == 0 ? p.x() : p.y(), y = ax == 0 ? p.y() : p.x();
        const int o = 1 - ax;
        const int seg = std::clamp(int((y - r.lo[o]) / (r.hi[o] - r.lo[o]) * kSideSegments), 0,
                                   kSideSegments - 1);
        if (x - r.lo[ax] <= kBandCells) carried[2 * ax][seg] = true;
        if (r.hi[ax] - x <= kBandCells) carried[2 * ax + 1][seg] = true;
      }
    }
  for (const auto& s : carried)
    if (std::count(s.begin(), s.end(), true) < kSideSupport * kSideSegments) return false;
  if (floor_inside > kMaxFloorInside * inside) return false;
  return std::all_of(features.begin(), features.end(), [&](const Vector2d& q) {
    const Vector2d p = r.along(q.x(), q.y());
    return p.x() >= r.lo[0] - kBandCells && p.x() <= r.hi[0] + kBandCells &&
           p.y() >= r.lo[1] - kBandCells && p.y() <= r.hi[1] + kBandCells;
  });
}

}  // namespace

std::optional<EdgesRect> edges_by_motion(const Correspondences& c, const Isometry3d& X_WC1,
                                         const Isometry3d& X_WC2, const Similarity2& S,
                                         double z_top, double floor_z_m, const TopRect& features,
                                         const std::vector<Vector3d>& pts_W,
                                         const MovingTopParams& params, const cv::Mat& gray_1,
                                         const cv::Mat& gray_2) {
  assert(c.camera && gray_1.type() == CV_8UC1 && gray_2.type() == CV_8UC1);
  assert(gray_2.cols == c.camera->width && gray_2.rows == c.camera->height);
  const auto g = cells(c, X_WC1, X_WC2, S, z_top, floor_z_m, features);
  if (!g) return std::nullopt;
  const cv::Mat v = votes(*g, gray_1, gray_2);
  std::vector<Vector2d> top;
  for (int j = 0; j < g->n; ++j)
    for (int i = 0; i < g->n; ++i)
      if (v.at<uint8_t>(j, i) == kTop) top.emplace_back(i, j);
  if (top.size() < 4 * size_t(kPatchCells * kPatchCells)) return std::nullopt;
  // The rectangle from an even subset (its cost is per point and per turn tried).
  std::vector<Vector2d> some;
  const size_t step = (top.size() + kMaxRectPoints - 1) / kMaxRectPoints;
  for (size_t i = 0; i < top.size(); i += step) some.push_back(top[i]);
  const GridRect r = trimmed_rect(some);
  std::vector<Vector2d> features_cells;
  for (const Vector3d& p : pts_W) features_cells.push_back((p.head<2>() - g->origin) / g->cell_m);
  if (!passes(r, v, *g, features_cells, params)) return std::nullopt;

  // Grid axes are the world's: the rectangle's axes in the world, the long one first.
  const int l = (r.hi[0] - r.lo[0]) >= (r.hi[1] - r.lo[1]) ? 0 : 1;
  const Vector3d a(r.cs, r.sn, 0), b(-a.y(), a.x(), 0);
  EdgesRect e;
  TopRect& out = e.rect;
  out.origin_W = Vector3d(g->origin.x(), g->origin.y(), z_top);
  out.axis[0] = l == 0 ? a : b;
  out.axis[1] = l == 0 ? b : -a;  // right-handed: (long, short, z)
  // A patch astride the rim mixes the floor's mismatch into the top's difference, so the votes
  // can stop up to half a patch inside a rim over a busy floor; a side face, which moves with the
  // top, can carry them a little past a rim towards the camera. Neither is known: the extent is
  // the votes'.
  for (int k = 0; k < 2; ++k) {
    const int src = k == 0 ? l : 1 - l;
    const double sgn = (l == 1 && k == 1) ? -1.0 : 1.0;  // axis[1] = -a when the long axis is b
    const double lo = sgn * r.lo[src] * g->cell_m, hi = sgn * r.hi[src] * g->cell_m;
    out.lo[k] = std::min(lo, hi), out.hi[k] = std::max(lo, hi);
  }
  // Stage 5: the votes also carry what moves with the top below it (a side face in view, the
  // platform's shadow on the floor), a few centimetres past a rim. Where the features cover most
  // of the votes' rectangle, their extent along its axes (widened by their shortfall) measures the
  // sides; where they cover under kBlobShare of it, the print's subject is a blob and the votes'
  // extent stands.
  const TopRect feat = widened_by_shortfall(
      features_rect(pts_W, out.origin_W, out.axis[0], out.axis[1]), pts_W.size());
  const auto area = [](const TopRect& t) { return (t.hi[0] - t.lo[0]) * (t.hi[1] - t.lo[1]); };
  if (area(feat) >= kBlobShare * area(out))
    for (int k = 0; k < 2; ++k) out.lo[k] = feat.lo[k], out.hi[k] = feat.hi[k];
  // Each end of a side is placed to about its band of cells: the turn to that over the side.
  const double rim_m = kBandCells * g->cell_m, long_m = out.hi[0] - out.lo[0];
  e.var_yaw = 2 * (rim_m / long_m) * (rim_m / long_m) / 3;
  return e;
}

}  // namespace alight::vision
