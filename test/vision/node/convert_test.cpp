// FrameResult -> VISION_TARGET (target_t), as the alight-vision node publishes it.
#include "vision/node/convert.hpp"

#include <gtest/gtest.h>

#include <utility>

namespace alight::vision {
namespace {

FrameResult result(Reason reason) {
  FrameResult r;
  r.utime = 1'700'000'000'123'456;
  r.ref_utime = 1'700'000'000'023'456;
  r.seq = 42;
  r.mission = Mission::kLanding;
  r.reason = reason;
  r.target.p_W = Vector3d(1.0, 2.0, 0.219);
  r.target.n_W = Vector3d(0, 0, 1);
  r.target.pixel = Vector2d(300.5, 200.25);
  r.target.height_m = 0.218;
  r.target.size_m[0] = 0.43, r.target.size_m[1] = 0.27;
  r.target.n_inliers_dominant = 300;
  r.target.n_inliers_target = 60;
  r.baseline_m = 0.21;
  r.n_features = 600, r.n_matches = 400;
  return r;
}

TEST(VisionConvertTest, FoundTargetCarriesEveryField) {
  const target_t m = to_msg(result(Reason::kOk));
  EXPECT_EQ(m.utime, 1'700'000'000'123'456);
  EXPECT_EQ(m.ref_utime, 1'700'000'000'023'456);
  EXPECT_EQ(m.seq, 42);
  EXPECT_EQ(m.mission, target_t::MISSION_LANDING);
  EXPECT_TRUE(m.found);
  EXPECT_EQ(m.reason, target_t::REASON_OK);
  EXPECT_DOUBLE_EQ(m.p_W_target[2], 0.219);
  EXPECT_DOUBLE_EQ(m.n_W[2], 1.0);
  EXPECT_DOUBLE_EQ(m.pixel[1], 200.25);
  EXPECT_DOUBLE_EQ(m.target_height_m, 0.218);
  EXPECT_DOUBLE_EQ(m.size_m[0], 0.43);
  EXPECT_DOUBLE_EQ(m.baseline_m, 0.21);
  EXPECT_EQ(m.n_features, 600);
  EXPECT_EQ(m.n_matches, 400);
  EXPECT_EQ(m.n_inliers_dominant, 300);
  EXPECT_EQ(m.n_inliers_target, 60);
}

// A partial view, and an opening seen with too little parallax to measure it.
TEST(VisionConvertTest, LocatedOnlyTargetsSayWhereToLookButAreNotFound) {
  for (const auto& [reason, constant] :
       {std::pair{Reason::kPartialView, target_t::REASON_PARTIAL_VIEW},
        std::pair{Reason::kLowParallax, target_t::REASON_LOW_PARALLAX}}) {
    const target_t m = to_msg(result(reason));
    EXPECT_FALSE(m.found);
    EXPECT_EQ(m.reason, constant);
    EXPECT_DOUBLE_EQ(m.p_W_target[0], 1.0);
    EXPECT_DOUBLE_EQ(m.size_m[1], 0.27);
  }
}

TEST(VisionConvertTest, OtherFailuresCarryReasonAndCountsOnly) {
  const target_t m = to_msg(result(Reason::kNoTargetPlane));
  EXPECT_FALSE(m.found);
  EXPECT_EQ(m.reason, target_t::REASON_NO_TARGET_PLANE);
  EXPECT_EQ(m.p_W_target[0], 0.0);
  EXPECT_EQ(m.n_W[2], 0.0);
  EXPECT_EQ(m.target_height_m, 0.0);
  EXPECT_EQ(m.size_m[0], 0.0);
  EXPECT_EQ(m.n_matches, 400);
  EXPECT_EQ(m.n_inliers_dominant, 300);
}

TEST(VisionConvertTest, MovingTopBecomesVisionPlatformOnlyWhereMeasured) {
  FrameResult r;
  r.utime = 5'000'000;
  r.seq = 9;
  EXPECT_FALSE(to_platform_msg(r));  // no moving-top stage ran
  MovingTop m;
  m.p_W = Vector3d(1, 2, 0.15);
  m.v_W = Vector3d(0.5, -0.1, 0.02);
  m.cov_p_W = Matrix3d::Identity() * 1e-4;
  m.cov_v_W(0, 1) = 3e-3;
  m.yaw_rad = 0.4;
  m.yaw_rate_rps = 0.1;
  m.size_m[0] = 0.4, m.size_m[1] = 0.3;
  m.n_candidates = 50, m.n_inliers = 40;
  m.camera_W = Vector3d(1.1, 2.05, 0.9);
  m.ref_camera_W = Vector3d(0.9, 2.0, 1.0);
  m.plane_z_m = 0.15;
  r.moving = m;
  r.moving_ref_utime = 4'750'000;
  const auto msg = to_platform_msg(r);
  ASSERT_TRUE(msg);
  EXPECT_EQ(msg->version, platform_motion_t::VERSION);
  EXPECT_TRUE(msg->found);
  EXPECT_EQ(msg->reason, platform_motion_t::REASON_OK);
  EXPECT_EQ(msg->utime, r.utime);
  EXPECT_EQ(msg->ref_utime, r.moving_ref_utime);
  EXPECT_EQ(msg->seq, r.seq);
  EXPECT_EQ(msg->p_W[1], 2.0);
  EXPECT_EQ(msg->v_W[0], 0.5);
  EXPECT_EQ(msg->cov_v_W[1], 3e-3);  // row-major
  EXPECT_EQ(msg->cov_p_W[8], 1e-4);
  EXPECT_EQ(msg->size_m[1], 0.3);
  EXPECT_EQ(msg->n_inliers, 40);
  EXPECT_EQ(msg->camera_W[2], 0.9);  // version 2: where the top was placed from
  EXPECT_EQ(msg->ref_camera_W[0], 0.9);
  EXPECT_EQ(msg->plane_z_m, 0.15);
  // Not found: the reason (platform_motion_t's value) and the counts only.
  m.reason = MovingReason::kOnFloor;
  r.moving = m;
  const auto refused = to_platform_msg(r);
  ASSERT_TRUE(refused);
  EXPECT_FALSE(refused->found);
  EXPECT_EQ(refused->reason, platform_motion_t::REASON_ON_FLOOR);
  EXPECT_EQ(refused->p_W[0], 0.0);
  EXPECT_EQ(refused->n_candidates, 50);
  EXPECT_FALSE(refused->outline);
  // Version 3: a top measured by its outline says so, also when its outline is refused.
  m.outline = true;
  m.reason = MovingReason::kOutlineUnpaired;
  r.moving = m;
  const auto unpaired = to_platform_msg(r);
  ASSERT_TRUE(unpaired);
  EXPECT_EQ(unpaired->version, 3);
  EXPECT_TRUE(unpaired->outline);
  EXPECT_EQ(unpaired->reason, platform_motion_t::REASON_OUTLINE_UNPAIRED);
  static_assert(int(MovingReason::kSizeOutOfRange) == platform_motion_t::REASON_SIZE_OUT_OF_RANGE);
  static_assert(int(MovingReason::kStillTop) == platform_motion_t::REASON_STILL_TOP);
  static_assert(int(MovingReason::kStillPixels) == platform_motion_t::REASON_STILL_PIXELS);
  static_assert(int(MovingReason::kNoEarlierFrame) == platform_motion_t::REASON_NO_EARLIER_FRAME);
  static_assert(int(MovingReason::kOutlineUnpaired) == platform_motion_t::REASON_OUTLINE_UNPAIRED);
}

}  // namespace
}  // namespace alight::vision
