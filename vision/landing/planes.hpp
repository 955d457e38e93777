#pragma once
// Landing, stage 1 of 3 (planes -> gates -> extent): the floor and the platform's top as two
// planes of one frame's matches, from one of two sources.
//
// The paper's (3.2, eqs. 1-2): the dominant homography of the matches and a second, locally
// sampled one on its outliers, aligned and decomposed together (alignment.hpp, ref. 20). The
// nearer plane is the top: a richly textured top can hold more matches than the floor in view,
// so the roles follow the geometry, not the match count.
//
// Beyond the paper, the known floor (geometry/known_floor.hpp): the floor is the plane
// z = floor_z_m and motion capture gives the camera's motion, so the floor's homography is known
// (eq. 2) and a level top is one unknown away; where the pair finds no floor in view, the top
// alone.

#include <cstdint>
#include <vector>

#include "vision/geometry/decomposition.hpp"
#include "vision/params.hpp"
#include "vision/target.hpp"

namespace alight::vision {

/// The two planes of one frame, however found; top_in / floor_in index the correspondences.
struct LandingPlanes {
  PlaneMotion top, floor;  ///< lengths in baselines (PlaneMotion's convention)
  std::vector<uint8_t> top_in, floor_in;
  int n_top = 0, n_floor = 0;
  bool top_alone = false;  ///< the view holds the top alone (fit_known_top_alone)
};

/// The paper's planes: two free homographies, aligned; the nearer is the top. Labels the first
/// homography's inliers kDominant in out->labels and counts them in out->estimate. Fails with
/// kTooFewMatches / kNoDominantPlane (no first homography), kNoTargetPlane (no second one with
/// min_platform_inliers), or the alignment's reason (alignment.hpp).
Result<LandingPlanes> paper_planes(const Correspondences& c, const PipelineParams& params,
                                   TargetOutcome* out);

/// The planes from the known floor and motion capture's motion: the pair
/// (fit_known_floor_planes), else the top alone (fit_known_top_alone) unless the pair failed for
/// a small baseline. Fails with kNoDominantPlane (the camera not above the floor), kSmallBaseline
/// (motion capture's baseline under min_baseline_m), or the pair's reason: the top alone's
/// refusals are not reported, the pair's say why the view holds no platform.
Result<LandingPlanes> known_floor_planes(const Correspondences& c, const PipelineParams& params);

/// The paper's floor is the known one: its distance from camera 1 within floor_tol_frac of the
/// known floor's, its normal within max_normal_angle_deg.
bool floor_agrees(const PlaneMotion& floor, const Correspondences& c, const PipelineParams& params);

/// Whether the plane of pixel homography H_px (image 1 to 2) carries match i's x1 to its x2
/// within threshold_px.
bool carries(const Matrix3d& H_px, const Correspondences& c, size_t i, double threshold_px);

}  // namespace alight::vision
