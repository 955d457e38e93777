#pragma once
// Landing, stage 3 of 3 (planes -> gates -> extent): where the top's edges are, hence its
// centre, size and heading. The top's features intersected with its plane (paper 3.1.3,
// eqs. 4-6) in world; the axes of their minimum-area rectangle are the platform's and the
// rectangle's centre is the aiming point (the mean would follow the texture's feature density,
// the extent follows the edges); its sides are widened by the features' expected shortfall
// (side_from_extent). The paper (3.2) finds the top's plane and centre from its features and
// measures no size; beyond it, the rectangle is taken out to the top's rims where the images
// show them (rim.hpp).

#include <cstdint>
#include <optional>
#include <vector>

#include "vision/landing/planes.hpp"

namespace alight::vision {

/// A side of the platform top from the extent (range) of its n features along it. Features
/// never sit on the top's edges (none where the detector's support reaches the floor, and n
/// draws over a side of length L span on average L (n - 1) / (n + 1): order statistics of the
/// uniform distribution), so the range falls short of the side; range (n + 1) / (n - 1) is its
/// unbiased estimate for features spread uniformly over the top (the minimum-variance unbiased
/// estimator of a uniform distribution's width). n < 2: the range itself.
double side_from_extent(double range_m, size_t n);

/// The top's rectangle in its plane: its axes (long, short) and its sides' places along them
/// from origin_W [m].
struct TopRect {
  Vector3d origin_W, axis[2];
  double lo[2], hi[2];
};

/// A stray is one or two top matches among a few dozen that fit the top's plane by chance on the
/// floor beside it: up to this share of the top's features are dropped as strays. Where more
/// would have to go, the features, not a few strays, cover the floor, and the gates decide.
constexpr double kMaxStrayTopShare = 0.1;

/// The top's features without the strays that stretch them over the floor. The top is opaque,
/// so no floor match off its plane lies inside the hull of its features (as in
/// floor_seen_around_top). While some do and removing one hull corner leaves fewer inside, the
/// corner that leaves the fewest goes (the one farthest from the features' centroid on a tie),
/// up to max_share of the features; at that limit with floor still inside, the features are
/// left as they were (the features, not a few strays, cover the floor: the gates decide about
/// those). Returns the kept top matches as a mask over the correspondences.
std::vector<uint8_t> without_strays(const Correspondences& c, const LandingPlanes& planes,
                                    const Matrix3d& H_top_px, double threshold_px,
                                    double max_share);

/// The top's features (without_strays, up to kMaxStrayTopShare of them) intersected with the top's
/// plane seen from camera 2 at X_WC2 (eqs. 4-6 with motion capture's baseline_m), in world;
/// those whose ray misses the plane are left out.
std::vector<Vector3d> top_points_W(const Correspondences& c, const LandingPlanes& planes,
                                   const Matrix3d& H_top_px, const Isometry3d& X_WC2,
                                   double baseline_m, const PipelineParams& params);

/// The top's unit normal in world, towards camera 2.
Vector3d top_normal_W(const LandingPlanes& planes, const Isometry3d& X_WC2);

/// The features' rectangle: the axes of their minimum-area bounding rectangle in the plane of
/// normal n_W (Freeman & Shapira 1975, rotating calipers, as cv::minAreaRect), their extent
/// along those axes from their mean. nullopt when the rectangle has no extent.
std::optional<TopRect> features_extent(const std::vector<Vector3d>& pts_W, const Vector3d& n_W);

/// The features' rectangle of the top's points (features_extent), or kTopPointsFew: under four
/// points (a plane's fewest), or a rectangle without extent.
Result<TopRect> top_features_rect(const std::vector<Vector3d>& pts_W, const Vector3d& n_W);

/// The extent of pts_W along two axes, from `mean`.
TopRect features_rect(const std::vector<Vector3d>& pts_W, const Vector3d& mean,
                      const Vector3d& ax_long, const Vector3d& ax_short);

/// The extent widened by side_from_extent's (n + 1) / (n - 1), half on each side: the
/// features' expected shortfall of the top's edges.
TopRect widened_by_shortfall(TopRect r, size_t n);

/// The estimate of a top measured as r: the waypoint of its centre on the top's plane and the
/// height above the floor's along the same ray (eqs. 4-6), its sizes (long first), yaw and
/// outline. kAimBehindCamera when the centre is behind camera 2, else the waypoints' reason
/// (geometry/waypoint.hpp) where either fails; kOk with *e filled.
Reason measure_top(const Correspondences& c, const LandingPlanes& planes, const TopRect& r,
                   const Isometry3d& X_WC2, const PipelineParams& params, TargetEstimate* e);

}  // namespace alight::vision
