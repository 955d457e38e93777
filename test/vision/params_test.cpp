// Every stage's parameters: defaults are valid; a bad value throws ParamError naming the field.
#include "vision/params.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "common/params.hpp"

namespace alight::vision {
namespace {

template <class P, class Mutate>
void expect_rejects(Mutate mutate, const std::string& key) {
  P p;
  mutate(p);
  try {
    p.validate();
    FAIL() << key << " accepted";
  } catch (const ParamError& e) {
    EXPECT_EQ(e.key(), key);
  }
}

TEST(VisionParamsTest, DefaultsAreValid) {
  EXPECT_NO_THROW(StarParams{}.validate());
  EXPECT_NO_THROW(SurfParams{}.validate());
  EXPECT_NO_THROW(MatchParams{}.validate());
  EXPECT_NO_THROW(TrackerParams{}.validate());
  EXPECT_NO_THROW(HomographyParams{}.validate());
  EXPECT_NO_THROW(DecompositionParams{}.validate());
  EXPECT_NO_THROW(AlignParams{}.validate());
  EXPECT_NO_THROW(WaypointParams{}.validate());
}

TEST(VisionParamsTest, BadValuesNameTheirField) {
  expect_rejects<StarParams>([](auto& p) { p.max_size = 0; }, "max_size");
  expect_rejects<StarParams>([](auto& p) { p.line_threshold = 0.5; }, "line_threshold");
  expect_rejects<SurfParams>([](auto& p) { p.scale_per_size = -1; }, "scale_per_size");
  expect_rejects<MatchParams>([](auto& p) { p.ratio = 1.5; }, "ratio");
  expect_rejects<TrackerParams>([](auto& p) { p.min_tracked = 2; }, "min_tracked");
  expect_rejects<TrackerParams>([](auto& p) { p.match.ratio = 0; }, "match.ratio");
  expect_rejects<HomographyParams>([](auto& p) { p.confidence = 1.0; }, "confidence");
  expect_rejects<HomographyParams>([](auto& p) { p.min_inliers = 3; }, "min_inliers");
  expect_rejects<DecompositionParams>([](auto& p) { p.min_front_fraction = 0.2; },
                                      "min_front_fraction");
  expect_rejects<AlignParams>([](auto& p) { p.max_iterations = -1; }, "max_iterations");
  expect_rejects<AlignParams>([](auto& p) { p.rotation_prior_sigma_deg = -0.1; },
                              "rotation_prior_sigma_deg");
  expect_rejects<AlignParams>([](auto& p) { p.feature_sigma_px = 0; }, "feature_sigma_px");
  expect_rejects<WaypointParams>([](auto& p) { p.min_baseline_m = 0; }, "min_baseline_m");
}

TEST(VisionParamsRegression, InfiniteTrackerTimeoutsAreRefused) {
  // Issue 14: `.inf` loaded, and a reference of any age stayed usable.
  expect_rejects<TrackerParams>([](auto& p) { p.max_frame_gap_s = HUGE_VAL; }, "max_frame_gap_s");
  expect_rejects<TrackerParams>([](auto& p) { p.max_reference_age_s = HUGE_VAL; },
                                "max_reference_age_s");
}

template <class Fn>
ParamError load_error(Fn fn) {
  try {
    fn();
  } catch (const ParamError& e) {
    return e;
  }
  ADD_FAILURE() << "no ParamError thrown";
  return ParamError("", "", "", "");
}

ParamError vision_error(const std::string& yaml) {
  return load_error([&] { load_node_params(ParamNode::from_string(yaml, "vehicle.yaml")); });
}

// Issue 18: the stages' validate() knew no section, so the node's error dropped it and named a
// key that is nowhere in the file.
TEST(VisionParamsRegression, AlignMaxIterationsIsReportedAsVisionAlignMaxIterations) {
  const ParamError e = vision_error("vision:\n  align:\n    max_iterations: -1\n");
  EXPECT_EQ(e.key(), "vision.align.max_iterations");  // was vision.max_iterations
  EXPECT_EQ(e.value(), "-1");
  EXPECT_EQ(e.file(), "vehicle.yaml");
}

TEST(VisionParamsRegression, StarMaxSizeIsReportedAsVisionStarMaxSize) {
  const ParamError e = vision_error("vision:\n  star:\n    max_size: 40\n");
  EXPECT_EQ(e.key(), "vision.star.max_size");  // was vision.max_size
  EXPECT_EQ(e.value(), "40");
  EXPECT_EQ(std::string(e.what()), "vehicle.yaml: vision.star.max_size = 40: must be in [1, 32]");
}

// Issue 18: these were validated but no file could set them.
TEST(VisionParamsTest, EveryValidatedFieldIsSettableFromTheVehicleFile) {
  const NodeParams p = load_node_params(ParamNode::from_string(
      "vision:\n"
      "  homography: {confidence: 0.99, refine_iterations: 3, robust_refinement: false,\n"
      "               local_neighbours: 8}\n"
      "  surf: {scale_per_size: 1.1, min_scale: 1.5, overlapping_subregions: false}\n"
      "  decomposition: {min_singular_gap: 0.001, min_front_fraction: 0.8}\n"
      "  tracker: {frame_threshold_px: 5, match: {ratio: 0.7, mutual: false}}\n"
      "  match: {mutual: false, same_sign_only: false}\n"
      "  star: {min_size: 3, line_threshold: 12, nms_radius_px: 3, subpixel: false}\n"
      "  ingress_star: {grid_cols: 6, max_features: 700}\n"
      "  poses: {max_extrapolation_s: 0.01}\n",
      "vehicle.yaml"));
  const PipelineParams& q = p.pipeline;
  EXPECT_EQ(q.homography.confidence, 0.99);
  EXPECT_EQ(q.homography.refine_iterations, 3);
  EXPECT_FALSE(q.homography.robust_refinement);
  EXPECT_EQ(q.homography.local_neighbours, 8);
  EXPECT_EQ(q.surf.scale_per_size, 1.1);
  EXPECT_EQ(q.surf.min_scale, 1.5);
  EXPECT_FALSE(q.surf.overlapping_subregions);
  EXPECT_EQ(q.decomposition.min_singular_gap, 0.001);
  EXPECT_EQ(q.decomposition.min_front_fraction, 0.8);
  EXPECT_EQ(q.tracker.frame_threshold_px, 5);
  EXPECT_EQ(q.tracker.match.ratio, 0.7);
  EXPECT_FALSE(q.tracker.match.mutual);
  EXPECT_FALSE(q.match.mutual);
  EXPECT_FALSE(q.match.same_sign_only);
  EXPECT_EQ(q.star.min_size, 3);
  EXPECT_EQ(q.star.grid_cols, 8);  // the pipeline's default, not StarParams'
  EXPECT_FALSE(q.star.subpixel);
  EXPECT_EQ(q.ingress_star.grid_cols, 6);
  EXPECT_EQ(q.ingress_star.max_features, 700);
  EXPECT_EQ(q.ingress_star.min_size, StarParams{}.min_size);  // star's keys are star's alone
  EXPECT_EQ(p.poses.max_extrapolation_s, 0.01);
  EXPECT_EQ(vision_error("vision: {homography: {confidence: 1}}").key(),
            "vision.homography.confidence");
  EXPECT_EQ(vision_error("vision: {surf: {min_scale: 0.4}}").key(), "vision.surf.min_scale");
  EXPECT_EQ(vision_error("vision: {decomposition: {min_front_fraction: 0.5}}").key(),
            "vision.decomposition.min_front_fraction");
  EXPECT_EQ(vision_error("vision: {tracker: {match: {ratio: 0}}}").key(),
            "vision.tracker.match.ratio");
}

// Knobs decided as constants in the code (docs/results.md, "Parameters decided"): a vehicle file
// that still sets one is refused, the error naming its full key.
TEST(VisionParamsTest, DecidedKnobsAreNoKeys) {
  for (const std::string section_key :
       {"landing.max_top_on_floor_share", "landing.max_stray_top_share", "landing.photometric_tol",
        "landing.photometric_min_ncc", "landing.photometric_max_sigma",
        "landing.photometric_far_sigmas", "landing.photometric_max_floor_spread",
        "landing.photometric_min_patches", "landing.hold_max_age_s", "landing.top_end_search_m",
        "ingress.max_ray_gap_px"}) {
    const size_t dot = section_key.find('.');
    const ParamError e = vision_error("vision: {" + section_key.substr(0, dot) + ": {" +
                                      section_key.substr(dot + 1) + ": 1}}");
    EXPECT_EQ(e.key(), "vision." + section_key);
    EXPECT_NE(std::string(e.what()).find("unknown key"), std::string::npos) << e.what();
  }
  // Their sections still load without them.
  const NodeParams p = load_node_params(ParamNode::from_string(
      "vision: {landing: {hold_reference: false}, ingress: {parallax_mask: false}}\n",
      "vehicle.yaml"));
  EXPECT_FALSE(p.pipeline.landing.hold_reference);
  EXPECT_FALSE(p.pipeline.ingress.parallax_mask);
}

TEST(VisionParamsTest, WithoutAVisionSectionTheDefaultsApply) {
  const NodeParams p = load_node_params(ParamNode::from_string("autonomy: {}\n", "vehicle.yaml"));
  EXPECT_EQ(p.pipeline.star.grid_rows, 6);
  EXPECT_EQ(p.pipeline.ingress_star.grid_rows, 3);  // each mission's camera its own budget
  EXPECT_EQ(p.pipeline.ingress_star.max_features, 600);
  EXPECT_EQ(p.max_pose_wait_s, NodeParams{}.max_pose_wait_s);
}

// The gear's footprint is autonomy's key, declared there once; the vision reads it from the
// same file (the least top an outline may be, outline.hpp), and no vision key sets it.
TEST(VisionParamsTest, TheGearFootprintIsReadFromAutonomysLandingSection) {
  EXPECT_EQ(load_node_params(ParamNode::from_string("vision: {}\n", "v.yaml"))
                .pipeline.landing.gear_footprint_m,
            LandingParams{}.gear_footprint_m);
  const NodeParams p = load_node_params(
      ParamNode::from_string("autonomy: {landing: {gear_footprint_m: 0.3}}\n", "vehicle.yaml"));
  EXPECT_EQ(p.pipeline.landing.gear_footprint_m, 0.3);
  for (const std::string bad : {"0", "-0.1", ".nan", ".inf"}) {
    const ParamError e = vision_error("autonomy: {landing: {gear_footprint_m: " + bad + "}}\n");
    EXPECT_EQ(e.key(), "autonomy.landing.gear_footprint_m") << bad;
    EXPECT_EQ(e.file(), "vehicle.yaml") << bad;
  }
  const ParamError e = vision_error("vision: {landing: {gear_footprint_m: 0.3}}\n");
  EXPECT_EQ(e.key(), "vision.landing.gear_footprint_m");
  EXPECT_NE(std::string(e.what()).find("unknown key"), std::string::npos) << e.what();
}

}  // namespace
}  // namespace alight::vision
