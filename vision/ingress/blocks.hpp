#pragma once
// Ingress, stage 2 of 4 (wall -> blocks -> faces -> opening): the block of cells seen through
// the wall (paper 3.3, Fig. 7). The image is cut into cells by straight lines (cuts.hpp; beyond
// the paper, those of the off-wall mask, mask.hpp); a 2-D histogram counts, per cell, the wall's
// inliers and the features seen through the wall; the block is the rectangle of cells holding
// the most features seen through the wall and (nearly) none of the wall's, the larger on a tie.

#include <opencv2/core.hpp>
#include <vector>

#include "vision/geometry/homography.hpp"
#include "vision/params.hpp"
#include "vision/target.hpp"

namespace alight::vision {

/// The image cut into cells: cuts xc (x, ascending, the image borders first and last) and yc,
/// and the off-wall mask they came from (empty: the grey image's edges).
struct Cells {
  std::vector<double> xc, yc;
  cv::Mat mask;
  int nx() const { return static_cast<int>(xc.size()) - 1; }
  int ny() const { return static_cast<int>(yc.size()) - 1; }
};

/// The cells of the wall `fit`: with parallax_mask and a reference, the off-wall mask of both
/// frames' parallax_image() (the wall's inliers set its threshold) and its border's cuts
/// (mask_cuts, snapped to the grey `image`'s steps); else the paper's edges of `image`
/// (line_cuts). `lines` receives the segments kept.
Cells cut_into_cells(const Correspondences& c, const HomographyFit& fit, const cv::Mat& image,
                     const cv::Mat& image_parallax, const cv::Mat& reference_parallax,
                     const IngressParams& params, std::vector<cv::Vec4i>* lines);

/// The wall's inliers in a cell that show the wall there: one or two can be a poor homography's
/// strays.
inline constexpr int kWallShownInliers = 3;

/// Whether match k is seen through the wall: an outlier of the wall's homography, and beyond
/// the paper, with the mask, only where the mask marks its pixel: an outlier where the
/// dense comparison finds the wall is a wall feature the homography's fit missed, or a mismatch.
bool seen_through_wall(const Correspondences& c, const HomographyFit& fit, const Cells& cells,
                       size_t k);

/// A block of cells [i0, i1) x [j0, j1), the features seen through the wall it holds, and what
/// lies beyond its sides: whether it reaches the image border (no cut there), and the wall's
/// inliers in the cells beyond each side over its span (left, right, top, bottom; -1 where the
/// side is the image border).
struct Block {
  int i0 = 0, j0 = 0, i1 = 0, j1 = 0;
  int n_off = 0;
  bool at_border = false;
  int wall_beyond[4] = {-1, -1, -1, -1};
};

/// The block holding the most features seen through the wall (the larger on a tie: the inner
/// faces hold no wall inliers, so the faces' far edges bound a smaller block with the same
/// features), with at most 2 % of them in wall inliers (features on the inner faces near the
/// front edge fit the wall's homography), and beyond the paper not bounded by a strip of bare
/// wall: an outermost row or column of cells with no such features and mostly (half or more)
/// clear in the mask, unless the cut beyond it is the opening's edge (kWallShownInliers of the
/// wall's inliers in the cell beyond, and along the middle of the cut, on half of the lines at
/// least, the mask clear 4 px out on the wall's side and set within snap_px + 4 px on the
/// block's side). n_off 0: no block holds any.
Block best_block(const Correspondences& c, const HomographyFit& fit, const Cells& cells,
                 const IngressParams& params);

/// The cell of coordinate x among the cuts (clamped to the first and last).
int cell_of(const std::vector<double>& cuts, double x);

}  // namespace alight::vision
