#pragma once
// Ingress, stage 3 of 4 (wall -> blocks -> faces -> opening), beyond the paper: each side of
// the block out across the wall's inner face to its front edge. The off-wall mask's border lies
// on the wall's inner faces (jambs, sill, lintel), up to their far edge, so the width measured
// in the wall plane would fall short by the wall's thickness in perspective. A face of a wall
// t thick runs from the front edge, on the wall plane, straight back along the wall's normal, so
// given where its front edge lies in the image the face is a known plane: the one through that
// edge's line on the wall plane that holds the wall's normal. Its homography (paper eq. 2 with
// the face's n~) maps the reference onto the current image across the face as the wall's does
// beyond it; the front edge is where the two models together explain the views (a change point,
// as in Irani & Anandan's plane + parallax, ECCV 1996).

#include <opencv2/core.hpp>

#include "common/camera_model.hpp"
#include "vision/geometry/decomposition.hpp"

namespace alight::vision {

/// Where the wall's inner faces can show, and the two views to test them.
struct CutGeometry {
  Vector2d principal_px = Vector2d::Zero();
  double wall_depth_m = 0;              ///< along the optical axis
  PlaneMotion wall;                     ///< the wall's homography, decomposed (camera 1: reference)
  const CameraModel* camera = nullptr;  ///< nullptr: no face search
  cv::Mat image, reference;             ///< both frames' parallax_image(), full size
};

/// The across-coordinate of the wall's front edge beyond the inner face next to the cut
/// a + b (along - mean_along), along in [lo, hi] (x of a vertical cut at row y), the wall on
/// the cut's `side` (-1: lower across-coordinates, +1: higher): where a face plane through that
/// edge along the wall's normal and the wall beyond it explain the two views best. Searched as
/// far as a face 0.4 m thick can reach: a face's far edge at `across` from the
/// principal point has its front edge `across` t / Z further out, and it shows only on the side
/// away from the principal point (beyond, the front edge hides it). The search starts on the
/// first pixel beyond the cut: a face's deepest points, next to its far edge, are the ones that
/// tell it from the wall. `a` unchanged when no face shows (the cost rises by less than 2 grey
/// levels a line over the search).
double face_front_edge(int side, bool vertical, double a, double b, double mean_along, int lo,
                       int hi, const CutGeometry& geometry);

/// The block's box in the current image [px], its sides at the cuts or their front edges.
struct OpeningBox {
  double left, right, top, bottom;
};

/// Each side of the box out across the wall's inner face to its front edge (face_front_edge),
/// read on the middle eight tenths of the side (the corners hold the neighbouring faces too).
/// The wall lies outside the block on every side: it is not read from the mask beside the cut,
/// where a flat room next to a cut on the face's far edge leaves the mask clear on the
/// opening's side too. `image_size`: the current image's.
OpeningBox to_front_edges(const OpeningBox& box, cv::Size image_size, const CutGeometry& geometry);

}  // namespace alight::vision
