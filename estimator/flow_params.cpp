#include "estimator/flow_params.hpp"

namespace alight::estimator {

const ParamSchema<FlowTrackParams>& FlowTrackParams::schema() {
  using P = FlowTrackParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("downsample", &P::downsample, Range::closed(0, 2), "",
          "detect and track on the image halved this many times (0: full resolution); the "
          "points are mapped back to full-resolution pixels before the fit");
    s.add("max_features", &P::max_features, Range::closed(8, 2000), "", "tracks kept at most");
    s.add("min_tracks", &P::min_tracks, Range::ge(0), "",
          "fewer tracks survive a frame: new features are detected in it, away from the "
          "surviving ones")
        .check([](const P& p) { return p.min_tracks <= p.max_features; },
               "must not exceed max_features");
    s.add("grid_cols", &P::grid_cols, Range::closed(1, 64), "",
          "detection spreads features over a grid, first at most max_features / cells per "
          "cell, so that a richly textured patch does not take them all (the vertical part of "
          "t/d is seen only through the spread of the points)");
    s.add("grid_rows", &P::grid_rows, Range::closed(1, 64), "", "rows of that grid");
    s.add("min_distance_px", &P::min_distance_px, Range::closed(1, 200), "px",
          "no two features closer than this (full-resolution pixels)");
    s.add("quality_level", &P::quality_level, Range::open(0, 1), "",
          "a corner's smaller structure-tensor eigenvalue relative to the image's best");
    s.add("min_quality", &P::min_quality, Range::ge(0), "",
          "and absolute (OpenCV's cornerMinEigenVal scale, 3x3 block): a blank or noise-only "
          "image yields no features");
    s.add("border_px", &P::border_px, Range::closed(0, 100), "px",
          "features are detected and kept only this far inside the image (full-resolution "
          "pixels)");
    s.add("window_px", &P::window_px, Range::closed(5, 63), "px",
          "Lucas-Kanade window side at the tracking level");
    s.add("pyramid_levels", &P::pyramid_levels, Range::closed(0, 6), "",
          "Lucas-Kanade pyramid levels above the tracking level (motion of up to about "
          "window_px * 2^levels / 2 tracking-level pixels is found)");
    s.add("lk_iterations", &P::lk_iterations, Range::closed(1, 100), "",
          "Lucas-Kanade iterations per level at most");
    s.add("lk_epsilon", &P::lk_epsilon, Range::open_closed(0, 1), "px",
          "Lucas-Kanade stops when its update is smaller");
    s.add("max_fb_error_px", &P::max_fb_error_px, Range::open_closed(0, 10), "px",
          "a track is kept when tracking it back lands this close to where it started "
          "(Kalal, Mikolajczyk & Matas 2010; full-resolution pixels)");
    s.add("predict", &P::predict, Range::any(), "",
          "start Lucas-Kanade where the frame's rotation and the last t/d put each point");
    return s;
  }();
  return schema;
}

void FlowTrackParams::validate() const { schema().validate(*this); }

const ParamSchema<FlowFitParams>& FlowFitParams::schema() {
  using P = FlowFitParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("inlier_threshold_px", &P::inlier_threshold_px, Range::closed(0.05, 20), "px",
          "a correspondence is on the floor when the plane-induced homography predicts it this "
          "well (pixels of focal length fx)");
    s.add("ransac_confidence", &P::ransac_confidence, Range::open(0, 1), "",
          "RANSAC stops once an all-inlier sample has been drawn with this probability");
    s.add("ransac_max_iterations", &P::ransac_max_iterations, Range::closed(1, 100000), "",
          "minimal (2-point) samples drawn at most");
    s.add("min_sample_separation_px", &P::min_sample_separation_px, Range::ge(0), "px",
          "the two points of a minimal sample at least this far apart (nearby points fix the "
          "vertical part of t/d badly)");
    s.add("seed", &P::seed, Range::any(), "", "RANSAC seed; every fit starts from it");
    s.add("huber_k", &P::huber_k, Range::closed(0.5, 10), "",
          "Huber loss threshold in robust standard deviations of the residuals (1.345: 95 % "
          "efficiency under Gaussian noise)");
    s.add("min_sigma_px", &P::min_sigma_px, Range::open_closed(0, 10), "px",
          "floor of the residual standard deviation, for the Huber threshold and the covariance");
    s.add("max_independent_points", &P::max_independent_points, Range::ge(3), "",
          "the covariance counts at most this many inliers as independent (it is scaled by "
          "inliers / this when there are more): tracking errors of nearby features share the "
          "texture, the interpolation and the lighting, so they do not average out as 1 / n. "
          "On rendered floors 150 inliers showed errors up to 6 sigma of the uncapped covariance");
    s.add("refine_iterations", &P::refine_iterations, Range::closed(1, 100), "",
          "Levenberg-Marquardt steps of each robust refinement at most");
    s.add("min_inliers", &P::min_inliers, Range::closed(3, 100000), "",
          "fewer inliers: the pair gives no sample");
    s.add("min_inlier_fraction", &P::min_inlier_fraction, Range::closed(0, 1), "",
          "inliers over usable correspondences at least");
    s.add("max_condition", &P::max_condition, Range::ge(1), "",
          "largest over smallest eigenvalue of the fit's information matrix: above it the "
          "points (clustered in a small patch) do not fix all three components");
    s.add("min_incidence_cos", &P::min_incidence_cos, Range::open_closed(0, 1), "",
          "a ray is used when it meets the plane with |cos| of its angle to the normal at "
          "least this (rays near the horizon are dropped)");
    return s;
  }();
  return schema;
}

void FlowFitParams::validate() const { schema().validate(*this); }

const ParamSchema<FlowFrontParams>& FlowFrontParams::schema() {
  using P = FlowFrontParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.section("track", &P::track, FlowTrackParams::schema(), "feature detection and tracking");
    s.section("fit", &P::fit, FlowFitParams::schema(), "robust fit of t/d to the tracks");
    s.add("max_gap_s", &P::max_gap_s, Range::open_closed(0, 10), "s",
          "consecutive frames further apart in exposure time make no pair (the gyro's "
          "rotation and the tracking are less reliable across a gap)");
    return s;
  }();
  return schema;
}

void FlowFrontParams::validate() const { schema().validate(*this); }

}  // namespace alight::estimator
