// The alight-vision node's input boundary (vision/node/inputs.hpp), driven with a real StampGuard
// and an injected clock, as the node drives it with Node::accept_stamp.

#include "vision/node/inputs.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <new>
#include <opencv2/core.hpp>

#include "common/channels.hpp"
#include "common/params.hpp"
#include "common/stamp_guard.hpp"
#include "vision/params.hpp"

namespace alight::vision {
namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;  // Unix time of the test's start [us]

struct Boundary {
  StampGuard guard;
  int64_t steady_us = 1'000'000;
  std::map<std::string, int> rejected_values, rejected_stamps;
  StampCheck accept = [this](const std::string& ch, int64_t utime) {
    const bool ok = stamp_ok(guard.check(ch, utime, steady_us, kT0 + steady_us));
    if (!ok) ++rejected_stamps[ch];
    return ok;
  };
  RejectValue reject = [this](const std::string& ch, const std::string&) { ++rejected_values[ch]; };
};

pose_t pose_msg(int64_t utime, double x) {
  pose_t m{};
  m.utime = utime;
  m.pos[0] = x;
  m.orientation[0] = 1.0;
  return m;
}

TEST(VisionInputsRegression, PoseStampedAnHourAheadDoesNotPushLaterPosesOut) {
  // Fed straight into the pose buffer (as the node did), a pose an hour ahead moved the
  // buffer's newest to t + 1 h: every later pose was older than the 5 s history window and
  // dropped, so no frame after it ever had a pose.
  {
    PoseBuffer raw;
    raw.add(from_msg(pose_msg(kT0, 0.0)));
    raw.add(from_msg(pose_msg(kT0 + 3'600'000'000, 0.0)));
    EXPECT_FALSE(raw.add(from_msg(pose_msg(kT0 + 10'000, 0.0))));  // what went wrong
  }
  Boundary b;
  PoseBuffer poses;
  int64_t t = kT0;
  for (int i = 0; i < 100; ++i, t += 10'000, b.steady_us += 10'000)
    EXPECT_TRUE(add_mocap_pose(pose_msg(t, 0.001 * i), poses, b.accept, b.reject));
  EXPECT_FALSE(add_mocap_pose(pose_msg(t + 3'600'000'000, 9.0), poses, b.accept, b.reject));
  EXPECT_EQ(b.rejected_stamps[channels::kMocapPose], 1);
  for (int i = 0; i < 100; ++i, t += 10'000, b.steady_us += 10'000)
    EXPECT_TRUE(add_mocap_pose(pose_msg(t, 0.1 + 0.001 * i), poses, b.accept, b.reject));
  PoseSample at;
  ASSERT_EQ(poses.lookup(t - 25'000, &at), PoseBuffer::Status::kOk);
  EXPECT_NEAR(at.p_W_B.x(), 0.1 + 0.001 * 97.5, 1e-9);
}

TEST(VisionInputsRegression, NonFinitePoseIsRefusedCountedAndTheLastGoodKept) {
  Boundary b;
  PoseBuffer poses;
  ASSERT_TRUE(add_mocap_pose(pose_msg(kT0, 1.0), poses, b.accept, b.reject));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (int field = 0; field < 5; ++field) {
    pose_t m = pose_msg(kT0 + 10'000, 2.0);
    switch (field) {
      case 0:
        m.pos[1] = nan;
        break;
      case 1:
        m.vel[2] = inf;
        break;
      case 2:
        m.orientation[3] = nan;
        break;
      case 3:
        m.angular_velocity_B[0] = -inf;
        break;
      case 4:
        m.orientation[0] = 0.0;
        break;  // zero quaternion: from_msg would divide by 0
    }
    EXPECT_FALSE(add_mocap_pose(m, poses, b.accept, b.reject)) << field;
  }
  EXPECT_EQ(b.rejected_values[channels::kMocapPose], 5);
  EXPECT_EQ(poses.size(), 1u);
  EXPECT_EQ(poses.newest().p_W_B.x(), 1.0);
  // A NaN pose stamped far ahead did not move the stamp guard: the next good pose is taken.
  pose_t bad = pose_msg(kT0 + 3'600'000'000, 0.0);
  bad.pos[0] = nan;
  EXPECT_FALSE(add_mocap_pose(bad, poses, b.accept, b.reject));
  b.steady_us += 10'000;
  EXPECT_TRUE(add_mocap_pose(pose_msg(kT0 + 10'000, 3.0), poses, b.accept, b.reject));
  EXPECT_EQ(b.rejected_stamps[channels::kMocapPose], 0);
}

TEST(VisionInputsTest, SlightlyUnnormalisedQuaternionIsTakenAndNormalised) {
  pose_t m = pose_msg(kT0, 0.0);
  m.orientation[0] = 1.004;
  std::string err;
  const auto p = mocap_pose_from_msg(m, &err);
  ASSERT_TRUE(p) << err;
  EXPECT_NEAR(p->q_WB.norm(), 1.0, 1e-12);
}

TEST(VisionInputsTest, CameraFrameAheadIsDroppedAndABadImageIsReportedAtItsStamp) {
  Boundary b;
  image_t ok = image_to_msg(cv::Mat(48, 64, CV_8UC1, cv::Scalar(7)), kT0);
  FrameInput f = camera_frame(ok, b.accept, b.reject);
  EXPECT_TRUE(f.use);
  ASSERT_TRUE(f.image);
  EXPECT_EQ(f.image->pixels.cols, 64);

  image_t ahead = ok;
  ahead.utime = kT0 + 3'600'000'000;
  f = camera_frame(ahead, b.accept, b.reject);
  EXPECT_FALSE(f.use);
  EXPECT_EQ(b.rejected_stamps[channels::kCamera], 1);

  image_t overflow = ok;  // the RGB frame whose width * 3 wrapped in int32
  overflow.utime = kT0 + 33'000;
  overflow.pixelformat = image_t::PIXEL_FORMAT_RGB;
  overflow.width = 0x55555556;
  overflow.height = 1;
  overflow.row_stride = 2;
  overflow.data = {1, 2};
  overflow.size = 2;
  b.steady_us += 33'000;
  f = camera_frame(overflow, b.accept, b.reject);
  EXPECT_TRUE(f.use);
  EXPECT_FALSE(f.image);
  EXPECT_EQ(b.rejected_values[channels::kCamera], 1);
}

TEST(VisionInputsTest, ExceptionsOutOfAFrameBecomeTextNotAnExit) {
  EXPECT_FALSE(run_guarded([] {}));
  const auto cv_error =
      run_guarded([] { CV_Error(cv::Error::StsBadArg, "homography of 3 points"); });
  ASSERT_TRUE(cv_error);
  EXPECT_NE(cv_error->find("homography of 3 points"), std::string::npos) << *cv_error;
  EXPECT_TRUE(run_guarded([] { throw std::bad_alloc(); }));
  EXPECT_TRUE(run_guarded([] { throw 42; }));
}

TEST(VisionParamsRegression, InfiniteOrHugeTimeoutsAreRefusedNamingFileKeyAndValue) {
  // Issue 14: `.inf` loaded for max_pose_wait_s: a frame waited for its pose forever (and
  // inf * 1e6 converted to int64 is undefined).
  struct Case {
    const char* yaml;
    const char* key;
    const char* value;
  };
  for (const Case& c :
       {Case{"vision: {max_pose_wait_s: .inf}", "vision.max_pose_wait_s", ".inf"},
        Case{"vision: {max_pose_wait_s: 1e300}", "vision.max_pose_wait_s", "1e+300"},
        Case{"vision: {max_pose_wait_s: .nan}", "vision.max_pose_wait_s", ".nan"},
        Case{"vision: {diag_rate_hz: .inf}", "vision.diag_rate_hz", ".inf"}}) {
    try {
      load_node_params(ParamNode::from_string(c.yaml, "vehicle.yaml"));
      ADD_FAILURE() << "accepted: " << c.yaml;
    } catch (const ParamError& e) {
      EXPECT_EQ(e.file(), "vehicle.yaml") << e.what();
      EXPECT_EQ(e.key(), c.key) << e.what();
      EXPECT_EQ(e.value(), c.value) << e.what();
    }
  }
  EXPECT_NO_THROW(load_node_params(ParamNode::from_string("vision: {max_pose_wait_s: 5}")));
}

// Issue 15: the CAMERA queue bounds memory; no queue, or one deeper than LCM's own (whose
// overflow is silent), is refused at its full key.
TEST(VisionParams, CameraQueueIsBoundedOnBothSides) {
  EXPECT_EQ(NodeParams{}.camera_queue_frames, 120);  // 2 s at 60 Hz
  for (const char* yaml :
       {"vision: {camera_queue_frames: 0}", "vision: {camera_queue_frames: 4096}"}) {
    try {
      load_node_params(ParamNode::from_string(yaml, "vehicle.yaml"));
      ADD_FAILURE() << "accepted: " << yaml;
    } catch (const ParamError& e) {
      EXPECT_EQ(e.key(), "vision.camera_queue_frames") << e.what();
    }
  }
  EXPECT_EQ(load_node_params(ParamNode::from_string("vision: {camera_queue_frames: 30}"))
                .camera_queue_frames,
            30);
}

}  // namespace
}  // namespace alight::vision
