// Landing stage 3, the extent out to the top's rims and ends (beyond paper 3.2 and its Fig. 6b;
// see rim.hpp).
#include "vision/landing/rim.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

#include "common/median.hpp"
#include "vision/geometry/bilinear.hpp"

namespace alight::vision {
namespace {

// One side of the features' extent in the top's plane (world): the line base_W + t along_W,
// t in [t_lo, t_hi], moved outward by d along out_W.
struct Side {
  Vector3d base_W, out_W, along_W;
  double t_lo, t_hi;
};

// The least-squares line y = a + b x through points v (x, y); false for fewer than three or all
// at one x.
bool fit_line(const std::vector<Eigen::Vector2d>& v, double* a, double* b) {
  const double n = static_cast<double>(v.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const auto& q : v) sx += q.x(), sy += q.y(), sxx += q.x() * q.x(), sxy += q.x() * q.y();
  const double den = n * sxx - sx * sx;
  if (v.size() < 3 || den <= 0) return false;
  *b = (n * sxy - sx * sy) / den;
  *a = (sy - *b * sx) / n;
  return true;
}

// Where a profile P (P[j] at offset j steps) darkens outward: G_j = P[j - k] - P[j + k], its
// local maxima over j >= j0 at least min_step and at least half the strongest, innermost first,
// each to a fraction of a step by a parabola through it (offset in steps, G).
std::vector<std::pair<double, double>> darkening_steps(const std::vector<double>& P, int j0, int k,
                                                       double min_step) {
  const int n = static_cast<int>(P.size());
  std::vector<double> g(n, 0.0);
  double strongest = 0;
  for (int j = std::max(j0, k); j + k < n; ++j) {
    g[j] = P[j - k] - P[j + k];
    strongest = std::max(strongest, g[j]);
  }
  std::vector<std::pair<double, double>> steps;
  for (int j = std::max(j0, k) + 1; j + k + 1 < n; ++j) {
    const double l = g[j - 1], c = g[j], r = g[j + 1];
    if (c < min_step || c < 0.5 * strongest || c < l || c < r) continue;
    const double den = l - 2 * c + r;
    steps.emplace_back(j + (den < 0 ? 0.5 * (l - r) / den : 0.0), c);
  }
  return steps;
}

// A grid point's raw pixels in the reference (through H_12 from the current camera's ray) and
// in the current image; nullopt behind either camera or outside the lens' model.
struct PixelPair {
  Vector2d u1, u2;
  static PixelPair between(const PixelPair& a, const PixelPair& b, double f) {
    return {a.u1 + f * (b.u1 - a.u1), a.u2 + f * (b.u2 - a.u2)};
  }
};
std::optional<PixelPair> grid_pixels(const Correspondences& c, const Matrix3d& H_12,
                                     const Vector3d& X_C2) {
  if (X_C2.z() <= 0) return std::nullopt;
  const Vector3d r1 = H_12 * (X_C2 / X_C2.z());
  if (r1.z() <= 0) return std::nullopt;
  const auto u1 = c.pixel1(r1), u2 = c.pixel2(X_C2);
  if (!u1 || !u2) return std::nullopt;
  return PixelPair{*u1, *u2};
}

// The grid's pixels are interpolated along each line between columns this many apart: across
// them (4 px at most, the end search's one-pixel columns) the lens and the perspective bend a
// line's pixels off a straight line by under 0.012 px, with strong radial distortion (k1 -0.4,
// k2 0.2) at the image's corner, against the half-pixel steps the searches read.
constexpr int kLatticeCols = 4;

// Both images' grey levels at a grid of points of the top's plane beside a side (rim_offset,
// top_end_offset): n_t lines along the side, t_step_m apart (min_t_step_m at least, max_lines at
// most), and columns outward col_m apart, at offsets [j_lo, j_hi) past the side and margin
// columns further either way, so that lines read turned by up to max_tan stay on the grid
// (offset j is column j - j_lo + margin). g2 is the current image at the point, g1 the reference
// at the same point of the top's plane (H_12 takes a current ray to the reference's), kUnseen
// where either is out of view. nullopt: fewer than min_lines lines.
struct SideGrid {
  static constexpr float kUnseen = -1.0f;
  int n_t = 0, n_g = 0, margin = 0;
  double t_step_m = 0, t_mid = 0;    // along the side; t_mid the middle of [t_lo, t_hi]
  Vector3d corner_C2, di_C2, dj_C2;  // the point of line i, column j: corner + i di + j dj
  std::vector<float> g1, g2;
  Vector3d point_C2(int i, int j) const { return corner_C2 + i * di_C2 + j * dj_C2; }
  size_t at(int i, int j) const { return static_cast<size_t>(i) * n_g + j; }
};
std::optional<SideGrid> read_side(const Correspondences& c, const cv::Mat& gray_1,
                                  const cv::Mat& gray_2, const Matrix3d& H_12,
                                  const Isometry3d& X_WC2, const Side& side, double min_t_step_m,
                                  int max_lines, int min_lines, double col_m, int j_lo, int j_hi,
                                  double max_tan) {
  SideGrid g;
  g.t_step_m = std::max(min_t_step_m, (side.t_hi - side.t_lo) / (max_lines - 1));
  g.n_t = static_cast<int>(std::floor((side.t_hi - side.t_lo) / g.t_step_m)) + 1;
  if (g.n_t < min_lines) return std::nullopt;
  g.margin = static_cast<int>(std::ceil(0.5 * (side.t_hi - side.t_lo) * max_tan / col_m)) + 1;
  const int n_g = g.n_g = (j_hi - j_lo) + 2 * g.margin;
  const double first_col_m = (j_lo - g.margin) * col_m;
  g.t_mid = 0.5 * (side.t_lo + side.t_hi);
  // The grid is affine in the top's plane, and so in camera 2's frame.
  const Isometry3d X_C2W = X_WC2.inverse();
  g.corner_C2 = X_C2W * (side.base_W + first_col_m * side.out_W + side.t_lo * side.along_W);
  g.dj_C2 = X_C2W.linear() * (col_m * side.out_W);
  g.di_C2 = X_C2W.linear() * (g.t_step_m * side.along_W);
  g.g1.assign(static_cast<size_t>(g.n_t) * n_g, SideGrid::kUnseen);
  g.g2.assign(g.g1.size(), SideGrid::kUnseen);
  // Each line's pixels projected at its lattice columns (every kLatticeCols-th and the last) and
  // interpolated between them; a stretch with an end out of either view point by point.
  std::vector<int> node_j;
  std::vector<std::optional<PixelPair>> node;
  auto sample = [&](int i, int j, const std::optional<PixelPair>& q) {
    double v1, v2;
    if (!q || !bilinear_inside(gray_1, q->u1, &v1) || !bilinear_inside(gray_2, q->u2, &v2)) return;
    g.g1[g.at(i, j)] = static_cast<float>(v1);
    g.g2[g.at(i, j)] = static_cast<float>(v2);
  };
  for (int i = 0; i < g.n_t; ++i) {
    node_j.clear();
    node.clear();
    for (int j = 0;; j += kLatticeCols) {
      node_j.push_back(std::min(j, n_g - 1));
      node.push_back(grid_pixels(c, H_12, g.point_C2(i, node_j.back())));
      if (node_j.back() == n_g - 1) break;
    }
    for (size_t k = 0; k < node.size(); ++k) {
      sample(i, node_j[k], node[k]);
      if (k + 1 == node.size()) break;
      const int ja = node_j[k], jb = node_j[k + 1];
      for (int j = ja + 1; j < jb; ++j)
        sample(i, j,
               node[k] && node[k + 1]
                   ? std::optional<PixelPair>(PixelPair::between(
                         *node[k], *node[k + 1], static_cast<double>(j - ja) / (jb - ja)))
                   : grid_pixels(c, H_12, g.point_C2(i, j)));
    }
  }
  return g;
}

// The side's rim, or nullopt when the two images do not show one step at the same place of the
// top's plane (rim.hpp). step_m is half a pixel of the current image on the top.
struct Rim {
  double d_m;          // outward from the side where the rim crosses the middle of the stretch read
  double turn_rad;     // the rim's turn from the side: offset d_m + (t - mid) tan(turn_rad)
  bool turn_measured;  // false: the stretches gave no turn and the lines were read unturned
};

// The rim search's grid (rim_offset): profiles G_j = P[j - kRimK] - P[j + kRimK], across one
// pixel either side (a step is half a pixel); profile index j is the offset (j - kRimJ0) steps,
// kRimJ0 four pixels inside the side, the top's own level. A line a pixel along the side at
// least, at most kRimMaxLines of them: a long side's mean is steady with fewer, and every line is
// read at every offset, so the lines bound the search's cost. The turn from kRimStretches
// stretches of the side: each a sixth of a 14 cm side, across which a rim turned 15 deg spreads
// its step over 6 mm, a pixel and a half at the search height.
constexpr int kRimK = 2, kRimJ0 = 8, kRimMaxLines = 48, kRimStretches = 6;
// The search's reach in the top's plane: a blank top's features stop short of its edges by the
// detector's border and the gaps between sparse features, a few centimetres at the search
// height. A rim steps by kRimMinStep grey levels at least in the mean of the lines (several
// times that mean's noise), and the two images' steps agree within kRimMaxDisagreementPx (each
// read to half a pixel, blur spreading it by up to one more; a step off the top's plane moves by
// its parallax). A minimum-area rectangle of a few dozen features on a blank top can be 10 deg
// or more off its edges: the rim's (and the end's) turn is fitted up to kRimMaxTurnDeg.
constexpr double kRimSearchM = 0.05, kRimMinStep = 6.0, kRimMaxDisagreementPx = 1.5;
constexpr double kRimMaxTurnDeg = 15.0;

// The mean of grid values g over lines [i0, i1) turned by tan_turn at each of n_d offsets (step_m
// apart); it ends where most of the lines are out of either view (a side cut by the border).
std::vector<double> rim_profile(const SideGrid& grid, const std::vector<float>& g, const Side& side,
                                double step_m, int n_d, double tan_turn, int i0, int i1) {
  const int n_g = grid.n_g, margin = grid.margin;
  const double t_step_m = grid.t_step_m, t_mid = grid.t_mid;
  std::vector<double> P;
  for (int j = 0; j < n_d; ++j) {
    double sum = 0;
    int n = 0;
    for (int i = i0; i < i1; ++i) {
      const double x = j + margin + (side.t_lo + i * t_step_m - t_mid) * tan_turn / step_m;
      const int x0 = std::clamp(static_cast<int>(std::floor(x)), 0, n_g - 2);
      const double f = std::clamp(x - x0, 0.0, 1.0);
      const float a = g[static_cast<size_t>(i) * n_g + x0],
                  b = g[static_cast<size_t>(i) * n_g + x0 + 1];
      if (a < 0 || b < 0) continue;
      sum += (1 - f) * a + f * b, ++n;
    }
    if (5 * n < 4 * (i1 - i0)) break;
    P.push_back(sum / n);
  }
  return P;
}

// The rim's turn as a tangent (offset steps per step along the side): the strongest darkening
// of each stretch in the current image, unturned, and a straight line through them (least
// squares; the stretches more than a pixel off it dropped once). Fewer than three stretches that
// step, or a turn beyond max_tan: nullopt (the lines are then read unturned).
std::optional<double> rim_turn(const SideGrid& grid, const Side& side, double step_m, int n_d,
                               double max_tan) {
  const int n_t = grid.n_t;
  std::vector<Eigen::Vector2d> at;  // (t - t_mid [m], offset [steps])
  for (int s = 0; s < kRimStretches; ++s) {
    const int i0 = s * n_t / kRimStretches, i1 = (s + 1) * n_t / kRimStretches;
    const auto steps = darkening_steps(rim_profile(grid, grid.g2, side, step_m, n_d, 0.0, i0, i1),
                                       kRimJ0, kRimK, kRimMinStep);
    if (steps.empty()) continue;
    const auto strongest =
        std::max_element(steps.begin(), steps.end(),
                         [](const auto& a, const auto& b) { return a.second < b.second; });
    at.emplace_back(side.t_lo + 0.5 * (i0 + i1 - 1) * grid.t_step_m - grid.t_mid, strongest->first);
  }
  double a = 0, b = 0;
  if (!fit_line(at, &a, &b)) return std::nullopt;
  std::vector<Eigen::Vector2d> near;
  for (const auto& q : at)
    if (std::abs(q.y() - (a + b * q.x())) <= 2.0) near.push_back(q);
  if (near.size() < at.size() && !fit_line(near, &a, &b)) return std::nullopt;
  if (std::abs(b * step_m) > max_tan) return std::nullopt;
  return b * step_m;
}

// The rim on the whole side's profiles (P1 the reference's, P2 the current image's, read along
// the turn): the first darkening of P2 that stays dark is the rim or nothing, and the reference
// must step there too. A dark band on the top (a row of print) darkens and brightens again:
// beyond the rim the profile stays below the top's level (its median inside the step) to the
// search's end.
std::optional<Rim> rim_of_profiles(const std::vector<double>& P1, const std::vector<double>& P2,
                                   double step_m, std::optional<double> tan_turn) {
  const int k = kRimK, j0 = kRimJ0;
  const auto steps_1 = darkening_steps(P1, j0, k, kRimMinStep);
  const int n = static_cast<int>(P2.size());
  for (const auto& [j2, g2_step] : darkening_steps(P2, j0, k, kRimMinStep)) {
    const int inner = static_cast<int>(std::floor(j2)) - k;
    const int outer = static_cast<int>(std::ceil(j2)) + k;
    if (inner < 1 || outer + 4 * k > n) break;  // too near the search's end to tell
    const double level = upper_median(std::vector<double>(P2.begin(), P2.begin() + inner));
    const double beyond = *std::max_element(P2.begin() + outer, P2.end());
    if (beyond > level - 0.5 * kRimMinStep) continue;
    for (const auto& step_1 : steps_1)
      if (std::abs(step_1.first - j2) <= 2 * kRimMaxDisagreementPx)
        return Rim{std::max(0.0, (j2 - j0) * step_m), std::atan(tan_turn.value_or(0.0)),
                   tan_turn.has_value()};
    return std::nullopt;
  }
  return std::nullopt;
}

std::optional<Rim> rim_offset(const Correspondences& c, const cv::Mat& gray_1,
                              const cv::Mat& gray_2, const Matrix3d& H_12, const Isometry3d& X_WC2,
                              const Side& side, double step_m) {
  const double max_tan = std::tan(kRimMaxTurnDeg * M_PI / 180.0);
  const int n_d = kRimJ0 + static_cast<int>(std::ceil(kRimSearchM / step_m)) + kRimK + 1;
  const auto grid = read_side(c, gray_1, gray_2, H_12, X_WC2, side, 2 * step_m, kRimMaxLines,
                              2 * kRimStretches, step_m, -kRimJ0, n_d - kRimJ0, max_tan);
  if (!grid) return std::nullopt;
  const auto tan_turn = rim_turn(*grid, side, step_m, n_d, max_tan);
  const double read_tan = tan_turn.value_or(0.0);
  return rim_of_profiles(rim_profile(*grid, grid->g1, side, step_m, n_d, read_tan, 0, grid->n_t),
                         rim_profile(*grid, grid->g2, side, step_m, n_d, read_tan, 0, grid->n_t),
                         step_m, tan_turn);
}

// The top's end search (top_end_offset) in pixels of the current image on the top: kEndInside
// pixels inside the side calibrate the threshold; kEndBeyond pixels beyond an end, in
// kEndParts parts, must stay off the top's plane; a step is read from box means of kEndWindow
// pixels either side; kEndMaxLines lines at most, kEndStretches stretches for the turn.
constexpr int kEndInside = 4, kEndBeyond = 30, kEndParts = 3, kEndWindow = 3;
constexpr int kEndMaxLines = 36, kEndStretches = 6;
// A pixel the top's homography does not explain differs by this many grey levels at least:
// several times the sensor's noise (1-5 levels) and the resampling's error on a sharp texture,
// under the contrast of any texture a floor's features come from.
constexpr double kTopEndMinDiff = 12.0;
// At the top's end the share of such pixels steps up by this much at least: from the top's few
// (near 0 where its plane holds) to a busy floor's many (most pixels), so under half that step
// and above the share a smooth floor band leaves.
constexpr double kTopEndMinRise = 0.4;

// The grid read beside a side at offsets j (pixels past the side) in [j_lo, j_hi), the images'
// gain ratio and the threshold tau above which a pixel's difference between the views, read at
// the same point of the top's plane, says the top's plane does not explain it.
struct EndSearch {
  SideGrid grid;
  int j_lo = 0, j_hi = 0, n_search = 0;
  double gain = 1, tau = 0;
  // Line i at offset j, or -1 outside the grid.
  std::ptrdiff_t cell(int i, int j) const {
    const int col = j - j_lo + grid.margin;
    return col < 0 || col >= grid.n_g ? std::ptrdiff_t{-1}
                                      : static_cast<std::ptrdiff_t>(grid.at(i, col));
  }
  // How far the top's plane is from explaining the pixel at `at`.
  double e_top(std::ptrdiff_t at) const { return std::abs(grid.g2[at] - gain * grid.g1[at]); }
  // The shift of line i along a turn of slope_px pixels per metre along the side.
  int shift(const Side& side, int i, double slope_px) const {
    return static_cast<int>(std::lround((side.t_lo + i * grid.t_step_m - grid.t_mid) * slope_px));
  }
};

// The search's grid and its calibration: the images' gains differ (automatic gain, flicker), so
// the inside strip's ratio evens them; the threshold lies above the top's own disagreement in
// that strip (noise, blur, the plane's error across its texture): twice its 90th percentile,
// and kTopEndMinDiff. nullopt where too little of the strip is seen.
std::optional<EndSearch> end_search(const Correspondences& c, const cv::Mat& gray_1,
                                    const cv::Mat& gray_2, const Matrix3d& H_12_top,
                                    const Isometry3d& X_WC2, const Side& side, double px_m,
                                    double end_search_m) {
  const double max_tan = std::tan(kRimMaxTurnDeg * M_PI / 180.0);
  EndSearch s;
  s.n_search = static_cast<int>(std::ceil(end_search_m / px_m));
  s.j_lo = -kEndInside, s.j_hi = s.n_search + kEndBeyond;
  auto grid = read_side(c, gray_1, gray_2, H_12_top, X_WC2, side, px_m, kEndMaxLines,
                        2 * kEndStretches, px_m, s.j_lo, s.j_hi, max_tan);
  if (!grid) return std::nullopt;
  s.grid = std::move(*grid);
  const std::vector<float>&v1_top = s.grid.g1, &v2 = s.grid.g2;
  double sum_2 = 0, sum_1 = 0;
  std::vector<std::ptrdiff_t> inside;
  for (int i = 0; i < s.grid.n_t; ++i)
    for (int j = s.j_lo; j < 0; ++j)
      if (const auto at = s.cell(i, j); at >= 0 && v2[at] >= 0) {
        inside.push_back(at);
        sum_2 += v2[at], sum_1 += v1_top[at];
      }
  if (5 * inside.size() < 4 * static_cast<size_t>(s.grid.n_t * kEndInside) || sum_1 <= 0)
    return std::nullopt;
  s.gain = sum_2 / sum_1;
  std::vector<double> e_inside;
  for (const auto at : inside) e_inside.push_back(s.e_top(at));
  const auto q90 = e_inside.begin() + static_cast<std::ptrdiff_t>(0.9 * (e_inside.size() - 1));
  std::nth_element(e_inside.begin(), q90, e_inside.end());
  s.tau = std::max(kTopEndMinDiff, 2.0 * *q90);
  return s;
}

// The share of the pixels the top's plane does not explain over lines [i0, i1) read along a
// turn (offsets grow by slope_px pixels per metre along the side): f[k] at offset k + j_lo, from
// the inside strip on. It ends where more than a fifth of the lines are out of either view.
std::vector<double> share_off_top(const EndSearch& s, const Side& side, double slope_px, int i0,
                                  int i1) {
  std::vector<double> f;
  for (int j = s.j_lo; j < s.j_hi; ++j) {
    int off = 0, seen = 0;
    for (int i = i0; i < i1; ++i) {
      const auto at = s.cell(i, j + s.shift(side, i, slope_px));
      if (at < 0 || s.grid.g2[at] < 0) continue;
      ++seen;
      off += s.e_top(at) > s.tau;
    }
    if (5 * seen < 4 * (i1 - i0)) break;
    f.push_back(static_cast<double>(off) / seen);
  }
  return f;
}

// The end: the innermost offset within the search where the share f steps up (box means of
// kEndWindow pixels either side) by at least half its strongest step there (beyond a rim a side
// face or a second texture can step again), to a fraction of a pixel by a parabola; (offset
// [px], rise).
std::optional<Eigen::Vector2d> step_up(const EndSearch& s, const std::vector<double>& f) {
  const int n_k = std::min(static_cast<int>(f.size()), s.n_search - s.j_lo + kEndWindow);
  std::vector<double> rise(n_k, -1.0);
  for (int k = kEndWindow; k + kEndWindow <= n_k; ++k) {
    double in = 0, out = 0;
    for (int w = 1; w <= kEndWindow; ++w) in += f[k - w], out += f[k + w - 1];
    rise[k] = (out - in) / kEndWindow;
  }
  const auto best = std::max_element(rise.begin(), rise.end());
  if (best == rise.end() || *best <= 0) return std::nullopt;
  int k = static_cast<int>(best - rise.begin());
  for (int q = 1; q + 1 < k; ++q)
    if (rise[q] >= 0.5 * *best && rise[q] >= rise[q - 1] && rise[q] >= rise[q + 1]) {
      k = q;
      break;
    }
  double at = k;
  if (k > 0 && k + 1 < n_k && rise[k - 1] >= 0 && rise[k + 1] >= 0) {
    const double den = rise[k - 1] - 2 * rise[k] + rise[k + 1];
    if (den < 0) at += 0.5 * (rise[k - 1] - rise[k + 1]) / den;
  }
  return Eigen::Vector2d(at - 0.5 + s.j_lo, rise[k]);  // the step lies between k - 1 and k
}

// The end's turn [px / m], as the rim's: the stretches' ends unturned and a least-squares line
// through them. A straight end steps in most stretches: the one farthest off is dropped while
// it lies more than two pixels off, down to kEndStretches - 2 of them. nullopt without such a
// line or with a turn beyond kRimMaxTurnDeg.
std::optional<double> end_slope(const EndSearch& s, const Side& side, double px_m) {
  const int n_t = s.grid.n_t;
  std::vector<Eigen::Vector2d> at_stretch;  // (t - t_mid [m], end [px])
  for (int k = 0; k < kEndStretches; ++k) {
    const int i0 = k * n_t / kEndStretches, i1 = (k + 1) * n_t / kEndStretches;
    const auto e = step_up(s, share_off_top(s, side, 0.0, i0, i1));
    if (e && e->y() >= kTopEndMinRise)
      at_stretch.emplace_back(side.t_lo + 0.5 * (i0 + i1 - 1) * s.grid.t_step_m - s.grid.t_mid,
                              e->x());
  }
  double slope = 0;
  for (;;) {
    double mid = 0;  // [px] at t_mid
    if (at_stretch.size() + 2 < kEndStretches || !fit_line(at_stretch, &mid, &slope))
      return std::nullopt;
    const auto off = [&](const Eigen::Vector2d& q) {
      return std::abs(q.y() - mid - slope * q.x());
    };
    const auto worst =
        std::max_element(at_stretch.begin(), at_stretch.end(),
                         [&](const auto& a, const auto& b) { return off(a) < off(b); });
    if (off(*worst) <= 2.0) break;
    at_stretch.erase(worst);
  }
  if (std::abs(slope * px_m) > std::tan(kRimMaxTurnDeg * M_PI / 180.0)) return std::nullopt;
  return slope;
}

// Beyond the end e (on the whole side's share f) the top's plane fails for kEndBeyond pixels as
// often as it fails at the end, part by part: the floor is busy from the end on, and the band
// that an edge of a rug moves by between the views is no end. Inside, it explains the images.
bool off_top_beyond(const EndSearch& s, const std::vector<double>& f, const Eigen::Vector2d& e) {
  const int j_end = static_cast<int>(std::lround(e.x()));
  const auto f_at = [&](int j) { return f[static_cast<size_t>(j - s.j_lo)]; };
  if (j_end + 1 + kEndBeyond - s.j_lo > static_cast<int>(f.size())) return false;
  double inside_share = 0;
  for (int j = 0; j < j_end - 1; ++j) inside_share = std::max(inside_share, f_at(j));
  if (inside_share > 0.5 * e.y()) return false;
  for (int part = 0; part < kEndParts; ++part) {
    double share = 0;
    for (int j = 0; j < kEndBeyond / kEndParts; ++j)
      share += f_at(j_end + 1 + part * kEndBeyond / kEndParts + j);
    if (share / (kEndBeyond / kEndParts) - inside_share < kTopEndMinRise) return false;
  }
  return true;
}

// The floor's plane explains at least half of the pixels beyond the end that the top's does not
// (a floor, not a second top or a side face). H_12_floor takes a current ray to the reference's
// ray of the same point on the floor's plane.
// How far the floor's plane is from explaining the grid's pixel `at` on line i: the current
// grey against the reference's at the same point of the floor's plane (H_12_floor takes a current
// ray to the reference's ray of that point), evened by the search's gain; nullopt where the
// reference does not see that point.
std::optional<double> e_floor(const Correspondences& c, const cv::Mat& gray_1, const EndSearch& s,
                              const Matrix3d& H_12_floor, int i, std::ptrdiff_t at) {
  const Vector3d r1 = H_12_floor * s.grid.point_C2(i, static_cast<int>(at % s.grid.n_g));
  double v1_floor;
  const auto u1 = r1.z() > 0 ? c.pixel1(r1) : std::nullopt;
  if (!u1 || !bilinear_inside(gray_1, *u1, &v1_floor)) return std::nullopt;
  return std::abs(s.grid.g2[at] - s.gain * v1_floor);
}

bool floor_beyond(const Correspondences& c, const cv::Mat& gray_1, const EndSearch& s,
                  const Side& side, const Matrix3d& H_12_floor, int j_end, double slope) {
  int off_top = 0, on_floor = 0;
  for (int i = 0; i < s.grid.n_t; ++i) {
    const int shift = s.shift(side, i, slope);
    for (int j = j_end + 1; j < j_end + 1 + kEndBeyond; ++j) {
      const auto at = s.cell(i, j + shift);
      if (at < 0 || s.grid.g2[at] < 0 || s.e_top(at) <= s.tau) continue;
      ++off_top;
      const auto e = e_floor(c, gray_1, s, H_12_floor, i, at);
      on_floor += e && *e <= s.tau;
    }
  }
  return 2 * on_floor >= off_top;
}

// Where the top's plane stops explaining the images beyond a side (rim.hpp, the top's end), on
// the side's end search s: the side's offset and turn, or nullopt where the floor beyond shows
// no texture to tell it by, or its lines do not end along one straight line. H_12_floor takes a
// current ray to the reference's ray of the same point on the floor's plane; px_m is a pixel of
// the current image on the top.
std::optional<Rim> top_end_offset(const Correspondences& c, const cv::Mat& gray_1,
                                  const EndSearch& s, const Matrix3d& H_12_floor, const Side& side,
                                  double px_m) {
  const auto slope = end_slope(s, side, px_m);
  if (!slope) return std::nullopt;
  const std::vector<double> f = share_off_top(s, side, *slope, 0, s.grid.n_t);
  const auto e = step_up(s, f);
  if (!e || e->y() < kTopEndMinRise) return std::nullopt;
  if (!off_top_beyond(s, f, *e) ||
      !floor_beyond(c, gray_1, s, side, H_12_floor, static_cast<int>(std::lround(e->x())), *slope))
    return std::nullopt;
  return Rim{std::max(0.0, e->x()) * px_m, std::atan(*slope * px_m), true};
}

// The side of `r` on axis k towards sign: its lo or its hi.
double& side_of(TopRect& r, int k, int sign) { return sign < 0 ? r.lo[k] : r.hi[k]; }
double side_of(const TopRect& r, int k, int sign) { return sign < 0 ? r.lo[k] : r.hi[k]; }

// What every side's search reads: the images, the planes' homographies taking a current ray to
// the reference's ray of the same point on the top / the floor, the current camera, half a pixel
// on the top (step_m) and the end search's reach.
struct SideSearch {
  const Correspondences& c;
  const cv::Mat &gray_1, &gray_2;
  Matrix3d H_12_top, H_12_floor;
  Isometry3d X_WC2;
  double step_m, end_search_m;
};

// A side with neither a rim nor an end may be the top's edge over a smooth floor, which neither
// plane explains better than the other, or a side of the features only, the top running on past
// them over print that gives no features (a photograph's smooth areas, blurred lettering) to an
// edge beyond the search or beyond the image. The end search's pixels beyond the side tell the
// two apart where they have texture: the top's plane alone explains those on the top, the
// floor's alone those on the floor. The top runs on over offsets [j_from, j_to) (pixels past the
// side) where the former are at least kRunsOnMinShare of those seen there and at least twice the
// latter: half a floor's texture tells it, and a tenth is over the few pixels that fit both
// planes by chance on a smooth top or floor. Smooth where neither share reaches that tenth.
// Unseen where under half of those offsets' pixels are in both views (by either plane): there
// the views tell nothing.
constexpr double kRunsOnMinShare = 0.1;
enum class Past { kEnds, kRunsOn, kSmooth, kUnseen };
Past top_runs_on(const Correspondences& c, const cv::Mat& gray_1, const EndSearch& s,
                 const Matrix3d& H_12_floor, int j_from, int j_to) {
  int cells = 0, seen = 0, top_only = 0, floor_only = 0;
  for (int i = 0; i < s.grid.n_t; ++i)
    for (int j = j_from; j < j_to; ++j) {
      const auto at = s.cell(i, j);
      ++cells;
      if (at < 0 || s.grid.g2[at] < 0) continue;
      const auto e = e_floor(c, gray_1, s, H_12_floor, i, at);
      if (!e) continue;
      ++seen;
      const bool on_top = s.e_top(at) <= s.tau;
      const bool on_floor = *e <= s.tau;
      top_only += on_top && !on_floor;
      floor_only += on_floor && !on_top;
    }
  if (2 * seen < cells) return Past::kUnseen;
  if (top_only > 0 && top_only >= kRunsOnMinShare * seen && top_only >= 2 * floor_only)
    return Past::kRunsOn;
  return floor_only >= kRunsOnMinShare * seen ? Past::kEnds : Past::kSmooth;
}

// What a side's search read: its rim (or end), else what lies past it.
struct SideRead {
  std::optional<Rim> rim;
  Past past = Past::kEnds;
};

// The walk's reads (past_side) take kWalkLines lines at most, a few pixels wide: a share over a
// hundred-odd pixels tells a tenth from a half, and a walk reads a metre in 40 steps.
constexpr int kWalkLines = 16;

// What lies past a side over offsets [from_m, to_m) (top_runs_on): the end search's grid there,
// unturned, with the gain and threshold of `cal`, calibrated on the top's own pixels inside the
// features' side (past it the walk may already be on the floor).
Past past_side(const SideSearch& q, const Side& side, const EndSearch& cal, double from_m,
               double to_m) {
  const double px_m = 2 * q.step_m;
  EndSearch s;
  s.j_lo = static_cast<int>(std::floor(from_m / px_m));
  s.j_hi = std::max(s.j_lo + 1, static_cast<int>(std::ceil(to_m / px_m)));
  s.gain = cal.gain, s.tau = cal.tau;
  auto grid = read_side(q.c, q.gray_1, q.gray_2, q.H_12_top, q.X_WC2, side, px_m, kWalkLines,
                        kWalkLines / 2, px_m, s.j_lo, s.j_hi, 0.0);
  if (!grid) return Past::kUnseen;
  s.grid = std::move(*grid);
  return top_runs_on(q.c, q.gray_1, s, q.H_12_floor, s.j_lo, s.j_hi);
}

// A smooth stretch the walk meets from `from_m` past the side may be bare print between rows of
// lettering or a photograph's soft area, the top running on past it: the top shows again within
// the end search's reach (kTopEndSearchM, a bare margin or band of print) before the floor
// does. The stretch's length (to where the top shows again), or 0 where the floor shows first,
// the view ends, or the reach is smooth throughout.
double smooth_gap(const SideSearch& q, const Side& side, const EndSearch& cal, double from_m) {
  const double step_m = 0.5 * kRimSearchM;
  for (double d = step_m; d <= kTopEndSearchM; d += step_m) {
    const Past p = past_side(q, side, cal, from_m + d, from_m + d + step_m);
    if (p == Past::kRunsOn) return d;
    if (p != Past::kSmooth) return 0.0;
  }
  return 0.0;
}

// How far past the features a side the top runs on past is followed: a top's side can lie a
// large part of its length past features that cover a band of it.
constexpr double kRunOnMaxM = 1.0;

// The side of `rect` on axis k towards sign, read along the middle of the other axis' extent
// (near the corners the lines run into the neighbouring sides' rims): its rim, else its end. A
// side without either past which the top runs on (over the second half of the rim search's reach,
// so the top lies beyond half that reach) is walked outward half the rim search's reach
// (kRimSearchM) at a time, while the top runs on over the next half reach, up to kRunOnMaxM.
// A smooth stretch past which the top shows again within the end search's reach is stepped
// over (smooth_gap: bare print between rows). Where the top stops running on, the rim or end
// lies within the rim search's reach of the walk: the rim is read there (one past which the top
// runs on too is print on the top, not its rim), else the end; a stretch that tells neither way
// to the end search's reach (smooth print, a smooth floor) leaves the side where the walk stands,
// as far out as the top was seen. A walk that leaves the view, or kRunOnMaxM,
// while the top runs on reports it running on (kRunsOn: its extent unseen). Without `walk`, the
// rim and the end only.
SideRead side_rim(const SideSearch& q, const TopRect& rect, int k, int sign, bool walk = true) {
  const int o = 1 - k;
  const double span = rect.hi[o] - rect.lo[o];
  const double at = side_of(rect, k, sign);
  const Side side{rect.origin_W + at * rect.axis[k], sign * rect.axis[k], rect.axis[o],
                  rect.lo[o] + 0.15 * span, rect.hi[o] - 0.15 * span};
  if (auto rim = rim_offset(q.c, q.gray_1, q.gray_2, q.H_12_top, q.X_WC2, side, q.step_m))
    return {rim, Past::kEnds};
  if (q.end_search_m <= 0) return {};
  const double px_m = 2 * q.step_m;
  const auto s =
      end_search(q.c, q.gray_1, q.gray_2, q.H_12_top, q.X_WC2, side, px_m, q.end_search_m);
  if (!s) return {};
  if (auto end = top_end_offset(q.c, q.gray_1, *s, q.H_12_floor, side, px_m))
    return {end, Past::kEnds};
  const double step_m = 0.5 * kRimSearchM;
  if (!walk || past_side(q, side, *s, step_m, 2 * step_m) != Past::kRunsOn) return {};
  for (double past = step_m;; past += step_m) {
    if (past + step_m > kRunOnMaxM) return {std::nullopt, Past::kRunsOn};
    const Past next = past_side(q, side, *s, past + step_m, past + 2 * step_m);
    if (next == Past::kUnseen) return {std::nullopt, Past::kRunsOn};
    if (next == Past::kRunsOn) continue;
    const double gap = next == Past::kSmooth ? smooth_gap(q, side, *s, past + step_m) : 0.0;
    if (gap > 0) {
      past += gap;
      continue;
    }
    Side out = side;
    out.base_W += past * side.out_W;
    if (const auto rim = rim_offset(q.c, q.gray_1, q.gray_2, q.H_12_top, q.X_WC2, out, q.step_m);
        rim &&
        past_side(q, side, *s, past + rim->d_m, past + rim->d_m + kRimSearchM) != Past::kRunsOn)
      return {Rim{rim->d_m + past, rim->turn_rad, rim->turn_measured}, Past::kEnds};
    if (const auto e =
            end_search(q.c, q.gray_1, q.gray_2, q.H_12_top, q.X_WC2, out, px_m, q.end_search_m))
      if (const auto end = top_end_offset(q.c, q.gray_1, *e, q.H_12_floor, out, px_m))
        return {Rim{end->d_m + past, end->turn_rad, end->turn_measured}, Past::kEnds};
    return {Rim{past, 0.0, false}, Past::kEnds};
  }
}

// A side's rim as found on the features' extent.
struct FoundRim {
  int k, sign;
  Vector3d at_W;    // from origin_W: where the rim crosses the middle of the stretch read
  double turn_rad;  // the whole rectangle's turn that squares it to this rim
  bool turn_measured;
};

// The rectangle's turn onto its rims: the median of the measured turns, where at least two
// were measured and agree within 4 deg, and it exceeds half a degree. A rim whose stretches gave
// no turn says nothing about it (its lines were read unturned), so it neither turns nor vetoes.
std::optional<double> rims_turn(const std::vector<FoundRim>& found) {
  std::vector<double> turns;
  for (const auto& f : found)
    if (f.turn_measured) turns.push_back(f.turn_rad);
  if (turns.size() < 2) return std::nullopt;
  std::sort(turns.begin(), turns.end());
  const double turn = turns[turns.size() / 2];
  if (turns.back() - turns.front() > 4.0 * M_PI / 180.0 || std::abs(turn) <= 0.5 * M_PI / 180.0)
    return std::nullopt;
  return turn;
}

}  // namespace

std::optional<TopRect> rim_rect(const Correspondences& c, const cv::Mat& gray_1,
                                const cv::Mat& gray_2, const LandingPlanes& planes,
                                const Isometry3d& X_WC2, const std::vector<Vector3d>& pts_W,
                                const TopRect& features, const TopRect& widened,
                                double end_search_m, bool* runs_on) {
  // The reference's point of the top's plane seen at a current ray: the top's homography
  // (calibrated, x2 ~ H x1), which explains the top's features, not the poses' motion.
  const SideSearch q{c,
                     gray_1,
                     gray_2,
                     planes.top.homography().inverse(),
                     planes.floor.homography().inverse(),
                     X_WC2,
                     0.5 * (X_WC2.inverse() * features.origin_W).z() / c.camera->K()(0, 0),
                     end_search_m};
  std::vector<FoundRim> found;
  std::array<bool, 4> running{};  // index 2 k + (sign > 0)
  const auto report = [&] {
    if (runs_on) *runs_on = std::any_of(running.begin(), running.end(), [](bool b) { return b; });
  };
  TopRect r = widened;
  for (int k = 0; k < 2; ++k)
    for (const int sign : {-1, 1}) {
      const SideRead read = side_rim(q, features, k, sign);
      running[2 * k + (sign > 0)] = read.past == Past::kRunsOn;
      if (!read.rim) continue;
      const Rim& rim = *read.rim;
      const double s = side_of(features, k, sign) + sign * rim.d_m;
      side_of(r, k, sign) = s;
      // The turn that takes axis k's side onto the rim, as a turn of the whole rectangle about
      // the top's normal (from the long axis towards the short one).
      const int o = 1 - k;
      found.push_back(
          {k, sign,
           s * features.axis[k] + 0.5 * (features.lo[o] + features.hi[o]) * features.axis[o],
           (k == 1 ? sign : -sign) * rim.turn_rad, rim.turn_measured});
    }
  report();
  if (found.empty()) return std::nullopt;
  const auto turn = rims_turn(found);
  if (!turn) return r;
  // Turned: the features' extent along the turned axes (widened where no rim is), each rim's
  // side where its crossing lies along them. A side without a rim was searched along the
  // unturned side, whose far end may lie beyond the search's reach from the turned rim: it is
  // searched again along the turned axes, and a rim found there ends the top on that side (not
  // walked again: a walk ends at a rim, or out of view, whichever way the side is turned).
  const Vector3d l = std::cos(*turn) * features.axis[0] + std::sin(*turn) * features.axis[1];
  const Vector3d sh = -std::sin(*turn) * features.axis[0] + std::cos(*turn) * features.axis[1];
  const TopRect turned = features_rect(pts_W, features.origin_W, l, sh);
  TopRect t = widened_by_shortfall(turned, pts_W.size());
  for (int k = 0; k < 2; ++k)
    for (const int sign : {-1, 1}) {
      const auto f = std::find_if(found.begin(), found.end(),
                                  [&](const FoundRim& g) { return g.k == k && g.sign == sign; });
      if (f != found.end()) {
        side_of(t, k, sign) = f->at_W.dot(t.axis[k]);
      } else if (const SideRead read = side_rim(q, turned, k, sign, false); read.rim) {
        side_of(t, k, sign) = side_of(turned, k, sign) + sign * read.rim->d_m;
        running[2 * k + (sign > 0)] = false;
      }
    }
  report();
  return t;
}

}  // namespace alight::vision
