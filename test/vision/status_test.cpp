#include "vision/status.hpp"

#include <gtest/gtest.h>

#include <alight/target_t.hpp>
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
