#pragma once
// Ingress, stage 1 of 4 (wall -> blocks -> faces -> opening): which plane is the wall (paper
// 3.3: the dominant homography; 3.1.2 for its decomposition). The dominant homography of the
// matches and a second one among its outliers are the candidates; each is decomposed with motion
// capture's rotation choosing the physical solution, and counts only when its motion agrees
// with motion capture's (the second search also finds a dozen stray matches that fit some
// homography). Beyond the paper, the wall is the nearer of the two by a margin: where the wall's
// photograph is dark and flat and the room's bright, the room's back wall seen through the
// opening holds more matches than the wall around it, and its homography would make the opening
// the only part of the view that agrees with the reference.

#include <optional>
#include <vector>

#include "vision/geometry/decomposition.hpp"
#include "vision/geometry/homography.hpp"
#include "vision/params.hpp"
#include "vision/target.hpp"

namespace alight::vision {

/// Two rays of a true match miss each other by its tracking noise (under a pixel) and motion
/// capture's orientation noise (1-2 px); a repeated texture matched across its epipolar line
/// misses by tens to hundreds of pixels. A gap of this many pixels [px] seen from camera 2 lies
/// several times above the first and under the second.
constexpr double kMaxRayGapPx = 8.0;

/// Every match triangulated with motion capture's poses (the midpoint of the two rays, world):
/// nullopt where the rays are near parallel, the point lies behind either camera, or the rays
/// pass farther apart than max_ray_gap_px seen from camera 2 (a mismatch: a repeated texture
/// matched across its epipolar line has no 3-D point and no say in the planes' depths or the
/// opening's checks). find_ingress_target passes kMaxRayGapPx; 0: no gap check.
std::vector<std::optional<Vector3d>> triangulate_matches(const Correspondences& c,
                                                         double max_ray_gap_px);

/// The wall's plane.
struct Wall {
  const HomographyFit* fit;   ///< its homography (into the PlanePair it was chosen from)
  Result<PlaneMotion> plane;  ///< decomposed; kMotionDisagrees where its motion is not motion
                              ///< capture's, else the decomposition's reason
  double depth_m;  ///< median depth of its triangulated inliers in camera 2 (infinity: none)
};

/// The fewest matches a wall of few features (few_feature_wall) is taken from: three define
/// the plane, the rest confirm it.
inline constexpr int kFewWallMinPoints = 6;

/// Beyond the paper: a smooth wall (sky, snow, a blurred photograph) holds a handful of
/// features, too few for a homography of its own (eight degrees of freedom, and mismatches among
/// them: the second search finds none, or one whose motion disagrees), while the busy room
/// behind a large opening holds the dominant plane. With motion capture's motion the wall's
/// plane has three unknowns: among the triangulated outliers of the dominant plane lying 0.5 m
/// in front of it (dominant_depth_m, camera 2), the plane through three of them (seeded draws)
/// that is upright (normal within 30 deg of the horizontal: from low down the floor is nearer
/// too), faces the camera (within 60 deg of its axis: no plane through both cameras' centres)
/// and transfers the most of them within homography.threshold_px under its induced homography,
/// then the plane that best transfers those (closed form). nullopt when fewer than
/// kFewWallMinPoints support it. *fit receives its homography (the plane-induced one) and
/// inliers among every match; the Wall points to it. find_ingress_target tries it where the
/// dominant plane, taken for the wall, shows nothing behind it.
std::optional<Wall> few_feature_wall(const Correspondences& c, const HomographyFit& dominant,
                                     double dominant_depth_m,
                                     const std::vector<std::optional<Vector3d>>& X_W_match,
                                     const PipelineParams& params, HomographyFit* fit);

/// The wall: the first homography, or the second where it decomposes and is nearer by 0.5 m
/// (a dark, flat wall photograph can hold fewer matches than the room seen through a large
/// opening; on a solid wall the second search can find the wall again,
/// a worse fit of the same plane at the same depth). X_W_match: triangulate_matches().
Wall choose_wall(const Correspondences& c, const PlanePair& planes,
                 const std::vector<std::optional<Vector3d>>& X_W_match,
                 const PipelineParams& params);

}  // namespace alight::vision
