#pragma once
// Parameters of the vision library, one struct per stage (paper sections 3.1 and 3.2), with
// defaults and units at each field. validate() throws ParamError naming the field and value;
// loading from a file is the node's job (issue 6).

#include <cstdint>

namespace alight::vision {

/// STAR / CenSurE detector (paper 3.1.1; Agrawal, Konolige & Blas, ECCV 2008).
struct StarParams {
  /// Smallest filter index n: inner box 2n+1, outer 4n+1 [px]. Not 1: the 3 x 3 / 5 x 5
  /// filter answers to single-pixel texture and noise that a little blur or a 10 % scale
  /// change removes, so on fine texture (fur, gravel) those peaks took most of the
  /// max_features budget and were not found again in the other view.
  int min_size = 2;
  int max_size = 6;                 ///< largest filter index n (border 2n+1 px is skipped)
  double response_threshold = 6.0;  ///< |mean(inner) - mean(ring)| to keep a peak [grey levels]
  double line_threshold = 10.0;     ///< Harris ratio r: reject edges with tr^2/det > (r+1)^2/r
  int nms_radius_px = 2;            ///< spatial non-maximum suppression radius [px]
  int max_features = 600;           ///< strongest peaks kept (0: all)
  /// Spread over the image (0: off): first at most max_features / (grid_cols * grid_rows)
  /// strongest per cell, then the strongest of the rest. A richly textured patch (a printed
  /// platform top) otherwise takes nearly all features and leaves the floor too few for its
  /// homography. [cells]
  int grid_cols = 0, grid_rows = 0;
  bool subpixel = true;  ///< paper 3.1.1: quadratic refinement of x, y and scale
  void validate() const;
};

/// Upright SURF descriptor (Bay, Tuytelaars & Van Gool, ECCV 2006 / CVIU 2008).
struct SurfParams {
  double scale_per_size = 0.8;  ///< SURF scale s per CenSurE filter half-width (n + 0.5) [-]
  double min_scale = 1.2;       ///< lower bound of s (Haar size 2s >= 2 px) [px]
  /// MU-SURF sub-regions (Agrawal, Konolige & Blas 2008, sec. 4): overlapping by 2s, each
  /// Gaussian-weighted about its centre, and the 4 x 4 grid weighted again; false: SURF's
  /// disjoint 5s x 5s sub-regions under one window Gaussian.
  bool overlapping_subregions = true;
  void validate() const;
};

/// Descriptor matching: nearest neighbour, Lowe's ratio test, mutual check.
struct MatchParams {
  double ratio = 0.8;          ///< best / second-best distance must be below this [-]
  bool mutual = true;          ///< keep a match only if it is also the reverse best match
  double max_distance = 0.6;   ///< Euclidean distance of unit descriptors above which no match [-]
  bool same_sign_only = true;  ///< match bright blobs with bright, dark with dark (SURF's trick)
  void validate() const;
};

/// Reference frame selection by continuous tracking (paper 3.1.1).
struct TrackerParams {
  int min_tracked = 40;          ///< N: features that must be tracked from reference to now [-]
  int max_history = 60;          ///< frames kept (bounds the reference age in frames) [-]
  double max_frame_gap_s = 1.0;  ///< a larger gap between frames resets the history, <= 60 [s]
  double max_reference_age_s = 10.0;  ///< older frames are never the reference, <= 600 [s]
  MatchParams match{};                ///< frame-to-frame matching
  /// Frame-to-frame matches must fit one homography within this; consecutive frames are close,
  /// so off-plane parallax stays below it while wrong matches do not (0: no check) [px].
  double frame_threshold_px = 8.0;
  uint64_t seed = 1;  ///< RANSAC seed of the frame-to-frame check [-]
  void validate() const;
};

/// Robust homography (paper 3.1.2; Fischler & Bolles 1981 RANSAC, Hartley 1997 normalisation,
/// Chum, Matas & Kittler 2003 LO-RANSAC refinement).
struct HomographyParams {
  double threshold_px = 2.0;  ///< inlier if the transfer error in image 2 is below [px]
  double confidence = 0.995;  ///< adaptive stopping: probability of one all-inlier sample [-]
  int max_iterations = 2000;  ///< hard cap of RANSAC samples [-]
  int min_inliers = 12;       ///< fewer inliers: no plane [-]
  int refine_iterations = 5;  ///< Levenberg-Marquardt steps on the inliers' transfer error [-]
  /// Final refinement: Cauchy-weighted (IRLS) instead of plain least squares over the inliers,
  /// its scale from their median residual, so near-miss matches just inside threshold_px pull
  /// less (Holland & Welsch 1977).
  bool robust_refinement = true;
  /// Second plane (3.2): draw the 3 other points of a sample among the k nearest neighbours of
  /// the first in image 1 (a platform is compact), which also bounds the work when no second
  /// plane exists: stop once a plane of min_inliers would have been sampled with `confidence`.
  int local_neighbours = 16;  ///< k [-]
  uint64_t seed = 1;          ///< RANSAC random seed [-]
  void validate() const;
};

/// Homography decomposition (paper 3.1.2; Longuet-Higgins 1986).
struct DecompositionParams {
  double min_singular_gap = 1e-4;   ///< sigma1 - sigma3 of the normalised H below: no translation
  double min_front_fraction = 0.9;  ///< share of inliers that must lie in front of both cameras
  void validate() const;
};

/// Two-plane alignment (paper 3.2).
struct AlignParams {
  double max_rotation_disagreement_deg = 5.0;      ///< planes' R21 must agree within [deg]
  double max_translation_disagreement_deg = 20.0;  ///< planes' t12 directions agree within [deg]
  int max_iterations = 15;  ///< Levenberg-Marquardt iterations of the joint refinement [-]
  /// Joint refinement Cauchy-weighted (IRLS, each plane's scale from its median residual)
  /// instead of plain least squares, as the final fit of each homography.
  bool robust = true;
  /// Motion capture's R21 as a prior on the joint refinement, with this standard deviation
  /// [deg]; 0 = vision alone (the paper). Breaks the rotation-translation (bas-relief) ambiguity
  /// of a narrow field of view that leaves the planes' distances a few percent off.
  double rotation_prior_sigma_deg = 0.0;
  double feature_sigma_px = 0.5;  ///< feature position noise the prior is weighed against [px]
  void validate() const;
};

/// Waypoint geometry (paper 3.1.3, eqs. 3-6).
struct WaypointParams {
  double min_baseline_m = 0.03;             ///< smaller camera translation: no usable scale [m]
  double max_translation_angle_deg = 30.0;  ///< vision vs motion-capture t12 direction [deg]
  double max_rotation_error_deg = 5.0;      ///< vision vs motion-capture R21 [deg]
  void validate() const;
};

}  // namespace alight::vision
