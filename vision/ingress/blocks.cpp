// Ingress stage 2, the blocks (paper 3.3, Fig. 7; see blocks.hpp).
#include "vision/ingress/blocks.hpp"

#include <algorithm>
#include <cmath>

#include "vision/ingress/cuts.hpp"
#include "vision/ingress/mask.hpp"

namespace alight::vision {
namespace {

// Per cell of the cuts, prefix sums (ny + 1) x (nx + 1) of the wall's inliers (`in`), of the
// features seen through the wall (`off`) and of the clear cells (`clear`: no such features and
// the mask mostly clear), so each block costs O(1).
struct CellCounts {
  int nx = 0, ny = 0;
  std::vector<int> in, off, clear;
  int& at(std::vector<int>& v, int i, int j) const { return v[j * (nx + 1) + i]; }
  int at(const std::vector<int>& v, int i, int j) const { return v[j * (nx + 1) + i]; }
  // Cells [i0, i1) x [j0, j1).
  int block(const std::vector<int>& v, int i0, int j0, int i1, int j1) const {
    return at(v, i1, j1) - at(v, i0, j1) - at(v, i1, j0) + at(v, i0, j0);
  }
  bool clear_strip(int i0, int j0, int i1, int j1) const {
    return block(clear, i0, j0, i1, j1) == (i1 - i0) * (j1 - j0);
  }
  void integrate(std::vector<int>* v) const {
    for (int j = 1; j <= ny; ++j)
      for (int i = 1; i <= nx; ++i)
        at(*v, i, j) += at(*v, i - 1, j) + at(*v, i, j - 1) - at(*v, i - 1, j - 1);
  }
};

// The histogram. A wall inlier within cut_margin_px of a cut is no evidence against the cell it
// falls in: its detector support straddles the border, and on the frame's inner face next to the
// wall's edge the parallax is still within the homography's threshold.
CellCounts count_cells(const Correspondences& c, const HomographyFit& fit, const Cells& cells,
                       const IngressParams& p) {
  const std::vector<double>&xc = cells.xc, &yc = cells.yc;
  CellCounts n;
  n.nx = cells.nx(), n.ny = cells.ny();
  n.in.assign((n.nx + 1) * (n.ny + 1), 0);
  n.off.assign((n.nx + 1) * (n.ny + 1), 0);
  n.clear.assign((n.nx + 1) * (n.ny + 1), 0);
  auto near_cut = [&](const std::vector<double>& cuts, double x) {
    const auto it = std::lower_bound(cuts.begin(), cuts.end(), x);
    return (it != cuts.end() && *it - x < p.cut_margin_px) ||
           (it != cuts.begin() && x - *(it - 1) < p.cut_margin_px);
  };
  for (size_t k = 0; k < c.size(); ++k) {
    const int i = cell_of(xc, c.u2[k].x()), j = cell_of(yc, c.u2[k].y());
    if (seen_through_wall(c, fit, cells, k))
      ++n.at(n.off, i + 1, j + 1);
    else if (fit.inlier[k] && !near_cut(xc, c.u2[k].x()) && !near_cut(yc, c.u2[k].y()))
      ++n.at(n.in, i + 1, j + 1);
  }
  n.integrate(&n.in);
  n.integrate(&n.off);
  const cv::Mat& mask = cells.mask;
  if (!mask.empty()) {
    for (int j = 0; j < n.ny; ++j)
      for (int i = 0; i < n.nx; ++i) {
        const cv::Rect cell = cv::Rect(cv::Point(cvRound(xc[i]), cvRound(yc[j])),
                                       cv::Point(cvRound(xc[i + 1]), cvRound(yc[j + 1]))) &
                              cv::Rect(0, 0, mask.cols, mask.rows);
        if (cell.area() > 0 && n.block(n.off, i, j, i + 1, j + 1) == 0)
          n.at(n.clear, i + 1, j + 1) =
              2 * cv::countNonZero(mask(cell)) < cell.area();  // mostly clear
      }
    n.integrate(&n.clear);
  }
  return n;
}

// Whether a cut is the opening's edge for a block beside it. The opening's edge is a border of
// the mask: along it the mask is set on the block's side (what is seen past the edge moves
// against the wall) and clear 4 px out on the wall's side, and the wall's inliers lie in the
// cell beyond. A line on a flat wall beside the opening has no mask on either side, and the
// image border has no wall beyond. The lines across each cut that show the pattern are counted
// once, when a clear strip first asks.
class EdgeTest {
 public:
  EdgeTest(const Cells& cells, const CellCounts& n, const IngressParams& p) : cells_(cells), n_(n) {
    enabled_ = !cells.mask.empty();
    reach_ = static_cast<int>(std::ceil(p.snap_px)) + 4;  // the snap moved it out
    for (auto& v : run_)
      for (auto& s : v) s.resize(std::max(n.nx, n.ny) + 1);
  }

  // Cut i (of the x cuts when vertical) is the opening's edge for a block on side s (0: towards
  // higher coordinates, 1: lower) spanning cells [c0, c1) along it.
  bool opening_edge(bool vertical, int i, int s, int c0, int c1) {
    if (!enabled_ || i <= 0 || i >= (vertical ? n_.nx : n_.ny)) return false;
    // The wall's inliers in the cell beyond, over the block's span.
    const int beyond = s == 0 ? i - 1 : i;
    const int n_beyond = vertical ? n_.block(n_.in, beyond, c0, beyond + 1, c1)
                                  : n_.block(n_.in, c0, beyond, c1, beyond + 1);
    if (n_beyond < kWallShownInliers) return false;
    // The middle of the span: its ends hold the neighbouring sides.
    const std::vector<double>& along = vertical ? cells_.yc : cells_.xc;
    const double len = along[c1] - along[c0];
    const std::vector<int>& run = edge_lines(vertical, i, s);
    const int lo = std::max(0, static_cast<int>(std::ceil(along[c0] + 0.1 * len)));
    const int hi = std::min(static_cast<int>(run.size()) - 1,
                            static_cast<int>(std::floor(along[c1] - 0.1 * len)));
    return hi > lo && 2 * (run[hi] - run[lo]) >= hi - lo;  // along half the span at least
  }

 private:
  // run[t]: how many lines t' < t across cut i show the edge's pattern for side s.
  const std::vector<int>& edge_lines(bool vertical, int i, int s) {
    std::vector<int>& run = run_[vertical ? 0 : 1][s][i];
    if (!run.empty()) return run;
    const cv::Mat& mask = cells_.mask;
    const int n_along = vertical ? mask.rows : mask.cols;
    const int n_across = vertical ? mask.cols : mask.rows;
    auto set = [&](int t, int x) {
      return x >= 0 && x < n_across &&
             (vertical ? mask.at<uint8_t>(t, x) : mask.at<uint8_t>(x, t)) != 0;
    };
    const int dir = s == 0 ? 1 : -1;  // towards the block
    const int a = static_cast<int>(std::lround(vertical ? cells_.xc[i] : cells_.yc[i]));
    const int x_wall = a - 4 * dir;
    run.assign(n_along + 1, 0);
    for (int t = 0; t < n_along; ++t) {
      bool edge = x_wall >= 0 && x_wall < n_across && !set(t, x_wall);
      if (edge) {
        bool band = false;
        for (int k = 0; k <= reach_ && !band; ++k) band = set(t, a + k * dir);
        edge = band;
      }
      run[t + 1] = run[t] + edge;
    }
    return run;
  }

  const Cells& cells_;
  const CellCounts& n_;
  bool enabled_ = false;
  int reach_ = 0;
  std::vector<std::vector<int>> run_[2][2];  // [x or y cuts][side][cut]
};

// The block's outermost column or row that is clear and not bounded by the opening's edge: a
// block beside such a strip is not bounded by the opening (the block without it holds the same
// features). Inside the block such cells stay: a smooth room's mask covers only part of the
// cells between the ones holding its few features.
bool wall_strip(const CellCounts& n, EdgeTest& edge, int i0, int j0, int i1, int j1) {
  return (n.clear_strip(i0, j0, i0 + 1, j1) && !edge.opening_edge(true, i0, 0, j0, j1)) ||
         (n.clear_strip(i1 - 1, j0, i1, j1) && !edge.opening_edge(true, i1, 1, j0, j1)) ||
         (n.clear_strip(i0, j0, i1, j0 + 1) && !edge.opening_edge(false, j0, 0, i0, i1)) ||
         (n.clear_strip(i0, j1 - 1, i1, j1) && !edge.opening_edge(false, j1, 1, i0, i1));
}

}  // namespace

int cell_of(const std::vector<double>& cuts, double x) {
  const auto it = std::upper_bound(cuts.begin(), cuts.end(), x);
  const int i = static_cast<int>(it - cuts.begin()) - 1;
  return std::clamp(i, 0, static_cast<int>(cuts.size()) - 2);
}

Cells cut_into_cells(const Correspondences& c, const HomographyFit& fit, const cv::Mat& image,
                     const cv::Mat& image_parallax, const cv::Mat& reference_parallax,
                     const IngressParams& p, std::vector<cv::Vec4i>* lines) {
  Cells cells;
  if (p.parallax_mask && !reference_parallax.empty()) {
    std::vector<Vector2d> wall_px;
    for (size_t k = 0; k < c.size(); ++k)
      if (fit.inlier[k]) wall_px.push_back(c.u2[k]);
    cells.mask = off_wall_mask_of_parallax_images(image_parallax, reference_parallax, image.size(),
                                                  fit.H, *c.camera, wall_px, p);
    mask_cuts(cells.mask, p, &cells.xc, &cells.yc, lines, image);
  } else {
    line_cuts(image, p, &cells.xc, &cells.yc, lines);
  }
  return cells;
}

bool seen_through_wall(const Correspondences& c, const HomographyFit& fit, const Cells& cells,
                       size_t k) {
  if (fit.inlier[k]) return false;
  const cv::Mat& mask = cells.mask;
  if (mask.empty()) return true;
  const int u = cvRound(c.u2[k].x()), v = cvRound(c.u2[k].y());
  return u < 0 || v < 0 || u >= mask.cols || v >= mask.rows || mask.at<uint8_t>(v, u) != 0;
}

// Features on the inner faces within the wall's thickness of its front edge fit the wall's
// homography: a block may hold one such inlier per 50 features seen through the wall, and one
// at least (a dim room, a lens's dark corners: an opening seen through with fewer than 50).
constexpr double kBlockInlierShare = 0.02;
constexpr double kBlockStrayInliers = 1.0;

Block best_block(const Correspondences& c, const HomographyFit& fit, const Cells& cells,
                 const IngressParams& p) {
  const CellCounts n = count_cells(c, fit, cells, p);
  EdgeTest edge(cells, n, p);
  const std::vector<double>&xc = cells.xc, &yc = cells.yc;
  Block best;
  double best_area = 0;
  for (int i0 = 0; i0 < n.nx; ++i0)
    for (int i1 = i0 + 1; i1 <= n.nx; ++i1)
      for (int j0 = 0; j0 < n.ny; ++j0)
        for (int j1 = j0 + 1; j1 <= n.ny; ++j1) {
          if (wall_strip(n, edge, i0, j0, i1, j1)) continue;
          const int n_in = n.block(n.in, i0, j0, i1, j1);
          const int n_off = n.block(n.off, i0, j0, i1, j1);
          if (n_in > std::max(kBlockStrayInliers, kBlockInlierShare * n_off)) continue;
          const double area = (xc[i1] - xc[i0]) * (yc[j1] - yc[j0]);
          if (n_off > best.n_off || (n_off == best.n_off && n_off > 0 && area > best_area)) {
            best = Block{i0, j0, i1, j1, n_off};
            best_area = area;
          }
        }
  const Block& b = best;
  best.at_border = b.i0 == 0 || b.j0 == 0 || b.i1 == n.nx || b.j1 == n.ny;
  if (b.i0 > 0) best.wall_beyond[0] = n.block(n.in, 0, b.j0, b.i0, b.j1);
  if (b.i1 < n.nx) best.wall_beyond[1] = n.block(n.in, b.i1, b.j0, n.nx, b.j1);
  if (b.j0 > 0) best.wall_beyond[2] = n.block(n.in, b.i0, 0, b.i1, b.j0);
  if (b.j1 < n.ny) best.wall_beyond[3] = n.block(n.in, b.i0, b.j1, b.i1, n.ny);
  return best;
}

}  // namespace alight::vision
