#include "vision/params.hpp"

#include "common/params.hpp"

namespace alight::vision {

void StarParams::validate() const {
  param_check(min_size >= 1, "min_size", min_size, "must be >= 1");
  param_check(max_size >= min_size && max_size <= 32, "max_size", max_size,
              "must be in [min_size, 32]");
  param_check(response_threshold >= 0.0, "response_threshold", response_threshold, "must be >= 0");
  param_check(line_threshold > 1.0, "line_threshold", line_threshold, "must be > 1");
  param_check(nms_radius_px >= 1 && nms_radius_px <= 8, "nms_radius_px", nms_radius_px,
              "must be in [1, 8]");
  param_check(max_features >= 0, "max_features", max_features, "must be >= 0");
  param_check(grid_cols >= 0 && grid_cols <= 64, "grid_cols", grid_cols, "must be in [0, 64]");
  param_check(grid_rows >= 0 && grid_rows <= 64, "grid_rows", grid_rows, "must be in [0, 64]");
  param_check((grid_cols == 0) == (grid_rows == 0), "grid_rows", grid_rows,
              "grid_cols and grid_rows are both 0 (off) or both > 0");
}

void SurfParams::validate() const {
  param_check(scale_per_size > 0.0, "scale_per_size", scale_per_size, "must be > 0");
  param_check(min_scale >= 0.5, "min_scale", min_scale, "must be >= 0.5");
}

void MatchParams::validate() const {
  param_check(ratio > 0.0 && ratio <= 1.0, "ratio", ratio, "must be in (0, 1]");
  param_check(max_distance > 0.0 && max_distance <= 2.0, "max_distance", max_distance,
              "must be in (0, 2]");
}

void TrackerParams::validate() const {
  param_check(min_tracked >= 4, "min_tracked", min_tracked, "must be >= 4");
  param_check(max_history >= 2, "max_history", max_history, "must be >= 2");
  // Finite and bounded: an infinite gap or age would keep a reference from any time ago.
  param_check(max_frame_gap_s > 0.0 && max_frame_gap_s <= 60.0, "max_frame_gap_s", max_frame_gap_s,
              "must be in (0, 60] s");
  param_check(max_reference_age_s > 0.0 && max_reference_age_s <= 600.0, "max_reference_age_s",
              max_reference_age_s, "must be in (0, 600] s");
  param_check(frame_threshold_px >= 0.0, "frame_threshold_px", frame_threshold_px, "must be >= 0");
  try {
    match.validate();
  } catch (const ParamError& e) {
    throw e.located("", "match");
  }
}

void HomographyParams::validate() const {
  param_check(threshold_px > 0.0, "threshold_px", threshold_px, "must be > 0");
  param_check(confidence > 0.0 && confidence < 1.0, "confidence", confidence, "must be in (0, 1)");
  param_check(max_iterations >= 1, "max_iterations", max_iterations, "must be >= 1");
  param_check(min_inliers >= 4, "min_inliers", min_inliers, "must be >= 4");
  param_check(refine_iterations >= 0, "refine_iterations", refine_iterations, "must be >= 0");
  param_check(local_neighbours >= 3, "local_neighbours", local_neighbours, "must be >= 3");
}

void DecompositionParams::validate() const {
  param_check(min_singular_gap > 0.0, "min_singular_gap", min_singular_gap, "must be > 0");
  param_check(min_front_fraction > 0.5 && min_front_fraction <= 1.0, "min_front_fraction",
              min_front_fraction, "must be in (0.5, 1]");
}

void AlignParams::validate() const {
  param_check(max_rotation_disagreement_deg > 0.0, "max_rotation_disagreement_deg",
              max_rotation_disagreement_deg, "must be > 0");
  param_check(max_translation_disagreement_deg > 0.0, "max_translation_disagreement_deg",
              max_translation_disagreement_deg, "must be > 0");
  param_check(max_iterations >= 0, "max_iterations", max_iterations, "must be >= 0");
  param_check(rotation_prior_sigma_deg >= 0.0, "rotation_prior_sigma_deg", rotation_prior_sigma_deg,
              "must be >= 0 (0 = no prior)");
  param_check(feature_sigma_px > 0.0, "feature_sigma_px", feature_sigma_px, "must be > 0");
}

void WaypointParams::validate() const {
  param_check(min_baseline_m > 0.0, "min_baseline_m", min_baseline_m, "must be > 0");
  param_check(max_translation_angle_deg > 0.0 && max_translation_angle_deg <= 180.0,
              "max_translation_angle_deg", max_translation_angle_deg, "must be in (0, 180]");
  param_check(max_rotation_error_deg > 0.0, "max_rotation_error_deg", max_rotation_error_deg,
              "must be > 0");
}

}  // namespace alight::vision
