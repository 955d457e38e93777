#include "vision/status.hpp"

#include <gtest/gtest.h>

#include <alight/target_t.hpp>
#include <set>
#include <string>

namespace alight::vision {
namespace {

TEST(StatusTest, ReasonValuesAreTheTargetMessageConstants) {
  using T = alight::target_t;
  EXPECT_EQ(int(Reason::kOk), T::REASON_OK);
  EXPECT_EQ(int(Reason::kNoPose), T::REASON_NO_POSE);
  EXPECT_EQ(int(Reason::kNoReference), T::REASON_NO_REFERENCE);
  EXPECT_EQ(int(Reason::kTooFewFeatures), T::REASON_TOO_FEW_FEATURES);
  EXPECT_EQ(int(Reason::kTooFewMatches), T::REASON_TOO_FEW_MATCHES);
  EXPECT_EQ(int(Reason::kSmallBaseline), T::REASON_SMALL_BASELINE);
  EXPECT_EQ(int(Reason::kNoDominantPlane), T::REASON_NO_DOMINANT_PLANE);
  EXPECT_EQ(int(Reason::kNoTargetPlane), T::REASON_NO_TARGET_PLANE);
  EXPECT_EQ(int(Reason::kNoOpening), T::REASON_NO_OPENING);
  EXPECT_EQ(int(Reason::kDecompositionFailed), T::REASON_DECOMPOSITION_FAILED);
  EXPECT_EQ(int(Reason::kBadImage), T::REASON_BAD_IMAGE);
  EXPECT_EQ(int(Reason::kPartialView), T::REASON_PARTIAL_VIEW);
  EXPECT_EQ(int(Reason::kLowParallax), T::REASON_LOW_PARALLAX);
  EXPECT_EQ(int(Reason::kMotionBlur), T::REASON_MOTION_BLUR);
  EXPECT_EQ(int(Reason::kTopNotParallel), T::REASON_TOP_NOT_PARALLEL);
  EXPECT_EQ(int(Reason::kNoFloorAroundTop), T::REASON_NO_FLOOR_AROUND_TOP);
  EXPECT_EQ(int(Reason::kTopFitsFloor), T::REASON_TOP_FITS_FLOOR);
  EXPECT_EQ(int(Reason::kTopTilted), T::REASON_TOP_TILTED);
  EXPECT_EQ(int(Reason::kHeightOutOfRange), T::REASON_HEIGHT_OUT_OF_RANGE);
  EXPECT_EQ(int(Reason::kTopPhotometry), T::REASON_TOP_PHOTOMETRY);
  EXPECT_EQ(int(Reason::kFloorPhotometry), T::REASON_FLOOR_PHOTOMETRY);
  EXPECT_EQ(int(Reason::kTopFitDiverged), T::REASON_TOP_FIT_DIVERGED);
  EXPECT_EQ(int(Reason::kTopAloneTooFew), T::REASON_TOP_ALONE_TOO_FEW);
  EXPECT_EQ(int(Reason::kTopAloneFloorSeen), T::REASON_TOP_ALONE_FLOOR_SEEN);
  EXPECT_EQ(int(Reason::kTopAloneLowRise), T::REASON_TOP_ALONE_LOW_RISE);
  EXPECT_EQ(int(Reason::kTopAloneLowParallax), T::REASON_TOP_ALONE_LOW_PARALLAX);
  EXPECT_EQ(int(Reason::kMotionDisagrees), T::REASON_MOTION_DISAGREES);
  EXPECT_EQ(int(Reason::kOpeningTooSmall), T::REASON_OPENING_TOO_SMALL);
  EXPECT_EQ(int(Reason::kNotBehindWall), T::REASON_NOT_BEHIND_WALL);
  EXPECT_EQ(int(Reason::kPartialNotFramed), T::REASON_PARTIAL_NOT_FRAMED);
  EXPECT_EQ(int(Reason::kPartialNotBehind), T::REASON_PARTIAL_NOT_BEHIND);
  EXPECT_EQ(int(Reason::kExposureChange), T::REASON_EXPOSURE_CHANGE);
  EXPECT_EQ(int(Reason::kDuplicateFrame), T::REASON_DUPLICATE_FRAME);
  EXPECT_EQ(int(Reason::kFrameGap), T::REASON_FRAME_GAP);
  EXPECT_EQ(int(Reason::kTopParallaxGap), T::REASON_TOP_PARALLAX_GAP);
  EXPECT_EQ(int(Reason::kOutlineOnFloor), T::REASON_OUTLINE_ON_FLOOR);
  EXPECT_EQ(int(Reason::kOutlineUnmatched), T::REASON_OUTLINE_UNMATCHED);
  EXPECT_EQ(int(Reason::kOutlineSilent), T::REASON_OUTLINE_SILENT);
  EXPECT_EQ(int(Reason::kTopRunsOn), T::REASON_TOP_RUNS_ON);
  EXPECT_EQ(int(Reason::kTopTooSmall), T::REASON_TOP_TOO_SMALL);
  EXPECT_EQ(int(Reason::kDecompositionAmbiguous), T::REASON_DECOMPOSITION_AMBIGUOUS);
  EXPECT_EQ(int(Reason::kPlanesDisagree), T::REASON_PLANES_DISAGREE);
  EXPECT_EQ(int(Reason::kAlignedPlaneBehind), T::REASON_ALIGNED_PLANE_BEHIND);
  EXPECT_EQ(int(Reason::kAimBehindCamera), T::REASON_AIM_BEHIND_CAMERA);
  EXPECT_EQ(int(Reason::kCornerOffPlane), T::REASON_CORNER_OFF_PLANE);
  EXPECT_EQ(int(Reason::kTopPointsFew), T::REASON_TOP_POINTS_FEW);
  EXPECT_EQ(int(Reason::kTopMatchesFew), T::REASON_TOP_MATCHES_FEW);
  EXPECT_EQ(int(Reason::kNoTopHeight), T::REASON_NO_TOP_HEIGHT);
}

TEST(StatusTest, EveryReasonHasItsOwnName) {
  std::set<std::string> names;
  for (int r = 0; r <= alight::target_t::REASON_NO_TOP_HEIGHT; ++r) {
    const std::string name = to_string(static_cast<Reason>(r));
    EXPECT_NE(name, "unknown") << r;
    EXPECT_TRUE(names.insert(name).second) << r << ": " << name;
  }
}

TEST(StatusTest, ResultCarriesEitherAValueOrAReason) {
  const auto ok = Result<int>::ok(3);
  EXPECT_TRUE(ok);
  EXPECT_EQ(*ok, 3);
  EXPECT_EQ(ok.reason(), Reason::kOk);
  const auto bad = Result<int>::fail(Reason::kTooFewMatches);
  EXPECT_FALSE(bad);
  EXPECT_EQ(bad.reason(), Reason::kTooFewMatches);
  EXPECT_EQ(std::string(to_string(bad.reason())), "too few matches");
}

}  // namespace
}  // namespace alight::vision
