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

}  // namespace
}  // namespace alight::vision
