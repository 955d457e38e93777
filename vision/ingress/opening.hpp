#pragma once
// Ingress, stage 4 of 4 (wall -> blocks -> faces -> opening): the block on the wall plane, and
// the checks that it is an opening seen whole. The block's centre and the middles of its sides
// intersected with the wall plane (paper 3.1.3, eqs. 4-6) give the waypoint, the width (paper
// Fig. 12) and the height. Beyond the paper: what is seen through an opening lies behind the
// wall; a block reaching the image border is a partial view, which must show what an opening
// shows at a corner at least; and a whole opening whose view beyond moved too little against the
// wall is located, not measured. Each refusal has its own reason (vision/status.hpp).

#include <optional>
#include <vector>

#include "vision/geometry/decomposition.hpp"
#include "vision/geometry/homography.hpp"
#include "vision/ingress/blocks.hpp"
#include "vision/ingress/faces.hpp"
#include "vision/params.hpp"
#include "vision/target.hpp"

namespace alight::vision {

/// The raw pixel where a side of the box (the raw segment from -> to, a cut fitted along the
/// whole side) crosses the row (a vertical side) or column (a horizontal one) of the box's
/// centre, through the camera's lens: the straight line fitted to the side's points taken
/// through the lens, evaluated at the centre's. Without distortion the segment's middle. Through
/// a distorting lens the opening's straight edge bows in the raw image and a straight cut sits
/// at the bow's mean, so the plain middle lies inside the edge (every width short); the line
/// through the lens, corrected by the bow its own raw image shows, lies on the edge.
Vector2d side_middle(const CameraModel& camera, const Vector2d& from, const Vector2d& to,
                     const Vector2d& centre);

/// The opening of box on the wall's plane (eqs. 4-6): the waypoint of its centre, the width
/// between the middles of its left and right sides (side_middle), the height between those of
/// its top and bottom, the centre as the aiming pixel and the box as the outline, filled into *e. A
/// waypoint's failure is the reason (geometry/waypoint.hpp); an opening narrower or lower than
/// min_size_m is kOpeningTooSmall (e filled all the same).
Reason measure_opening(const Correspondences& c, const PlaneMotion& wall, const OpeningBox& box,
                       const PipelineParams& params, TargetEstimate* e);

/// The block's matches (labelled kTarget) with a 3-D point (X_W_match) that lie more than
/// behind_margin_m behind the wall plane of e (p_W, n_W), and how far each moved against the
/// wall's homography [px].
struct Behind {
  int in_block = 0, behind = 0;
  std::vector<double> parallax_px;
};
Behind behind_the_wall(const Correspondences& c, const HomographyFit& wall,
                       const std::vector<Label>& labels,
                       const std::vector<std::optional<Vector3d>>& X_W_match,
                       const TargetEstimate& e, const IngressParams& params);

/// The checks of the measured opening, in order, and its outcome. What is seen through an
/// opening lies behind the wall: at least min_outliers of the block's features, and
/// min_behind_share of those with a 3-D point, lie behind it; else the "wall" is something seen
/// through the opening and the block is the wall itself (kNotBehindWall). A block reaching the
/// image border is a partial view whose centre and size are unknown; it must show the wall
/// (kWallShownInliers of its inliers) beyond two of its sides (kPartialNotFramed) and its
/// features' median 0.25 m behind the median of
/// the wall's own inliers, not only behind the plane a poor homography's decomposition gives
/// (kPartialNotBehind); then kPartialView. A whole opening whose features behind the wall moved
/// less than min_opening_parallax_px against the wall's homography (median) is located, not
/// measured (kLowParallax): the mask shows the view beyond the opening only where its texture,
/// moved by the parallax, differs from itself, and the block then covers part of the opening.
/// Else kOk.
Reason opening_checks(const Correspondences& c, const HomographyFit& wall, const Block& block,
                      const std::vector<Label>& labels,
                      const std::vector<std::optional<Vector3d>>& X_W_match,
                      const TargetEstimate& e, const IngressParams& params);

}  // namespace alight::vision
