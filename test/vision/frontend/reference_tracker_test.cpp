// Reference frame selection (paper 3.1.1) on a sequence of warped photo-like views: the reference
// is the oldest frame with min_tracked continuously tracked features, and the reset rules hold.
#include "vision/frontend/reference_tracker.hpp"

#include <gtest/gtest.h>

#include "test/vision/test_images.hpp"
#include "vision/frontend/surf_descriptor.hpp"
#include "vision/geometry/homography.hpp"

namespace alight::vision {
namespace {

using testing::procedural_photo;
using testing::view_homography;
using testing::view_of;

struct Sequence {
  cv::Mat source = procedural_photo(1400, 900, 31);
  /// View k: the camera drifts 25 px per frame to the right and rotates slowly.
  Matrix3d H(int k) const {
    return view_homography(1400, 900, 0.004 * k, 1.0, -25.0 * k + 300, 0, 0, 0);
  }
  TrackedFrame frame(int k, int64_t utime) const {
    const cv::Mat img = view_of(source, H(k), 0.0, 1.5, 100 + k);
    TrackedFrame f;
    f.utime = utime;
    const cv::Mat I = integral_image(img);
    f.keypoints = *detect_star(img, I, StarParams{});
    f.descriptors = describe_surf(I, f.keypoints, SurfParams{});
    return f;
  }
};

TEST(ReferenceTrackerTest, ReferenceIsTheOldestFrameWithEnoughContinuousTracks) {
  const Sequence seq;
  TrackerParams p;
  p.min_tracked = 60;
  ReferenceTracker tracker(p);
  int64_t last_ref = -1;
  bool advanced = false;
  for (int k = 0; k < 25; ++k) {
    const auto u = tracker.add(seq.frame(k, 1'000'000 + k * 100'000));
    if (k == 0) {
      EXPECT_EQ(u.status, Reason::kNoReference);
      continue;
    }
    ASSERT_EQ(u.status, Reason::kOk) << k;
    EXPECT_GE(u.n_tracked, p.min_tracked);
    EXPECT_GE(u.reference->utime, last_ref);  // the reference only moves forward
    advanced = advanced || (last_ref >= 0 && u.reference->utime > last_ref);
    last_ref = u.reference->utime;
    // The tracks are true correspondences: they follow the known homography.
    const int ref_k = int((u.reference->utime - 1'000'000) / 100'000);
    const Matrix3d H = seq.H(k) * seq.H(ref_k).inverse();
    int good = 0;
    const auto m = tracked_matches(*u.reference, *u.current);
    EXPECT_EQ(int(m.size()), u.n_tracked);
    for (const auto& mm : m) {
      const auto& a = u.reference->keypoints[mm.i1];
      const auto& b = u.current->keypoints[mm.i2];
      good += transfer_error(H, Vector2d(a.x, a.y), Vector2d(b.x, b.y)) < 1.5;
    }
    EXPECT_GT(good, 0.9 * m.size()) << k;
  }
  EXPECT_TRUE(advanced);  // overlap shrinks: the reference had to move
  EXPECT_GT(last_ref, 1'000'000);
  EXPECT_LT(tracker.history_size(), 26u);
}

TEST(ReferenceTrackerTest, BlankFrameResetsAndTheNextFrameHasNoReference) {
  const Sequence seq;
  ReferenceTracker tracker;
  tracker.add(seq.frame(0, 1'000'000));
  EXPECT_EQ(tracker.add(seq.frame(1, 1'100'000)).status, Reason::kOk);
  TrackedFrame blank;
  blank.utime = 1'200'000;
  blank.descriptors = cv::Mat(0, kSurfLength, CV_32F);
  const auto u = tracker.add(blank);
  EXPECT_EQ(u.status, Reason::kTooFewFeatures);
  EXPECT_TRUE(u.reset);
  EXPECT_EQ(tracker.history_size(), 0u);
  EXPECT_EQ(tracker.add(seq.frame(2, 1'300'000)).status, Reason::kNoReference);
  EXPECT_EQ(tracker.add(seq.frame(3, 1'400'000)).status, Reason::kOk);
}

TEST(ReferenceTrackerTest, TimeGapOrTimeGoingBackwardsResets) {
  const Sequence seq;
  TrackerParams p;
  p.max_frame_gap_s = 0.5;
  ReferenceTracker tracker(p);
  tracker.add(seq.frame(0, 1'000'000));
  const auto gap = tracker.add(seq.frame(1, 2'000'000));
  EXPECT_TRUE(gap.reset);
  EXPECT_EQ(gap.status, Reason::kNoReference);
  const auto back = tracker.add(seq.frame(2, 1'900'000));
  EXPECT_TRUE(back.reset);
  EXPECT_EQ(back.status, Reason::kNoReference);
  EXPECT_EQ(tracker.add(seq.frame(3, 2'000'000)).status, Reason::kOk);
  tracker.reset();
  EXPECT_EQ(tracker.add(seq.frame(4, 2'100'000)).status, Reason::kNoReference);
}

TEST(ReferenceTrackerTest, UnrelatedViewLeavesNoReference) {
  const Sequence seq;
  ReferenceTracker tracker;
  tracker.add(seq.frame(0, 1'000'000));
  const cv::Mat other = procedural_photo(640, 480, 999);
  TrackedFrame f;
  f.utime = 1'100'000;
  const cv::Mat I = integral_image(other);
  f.keypoints = *detect_star(other, I, StarParams{});
  f.descriptors = describe_surf(I, f.keypoints, SurfParams{});
  const auto u = tracker.add(f);
  EXPECT_EQ(u.status, Reason::kNoReference);
  EXPECT_LT(u.n_frame_matches, TrackerParams{}.min_tracked);
  EXPECT_EQ(tracker.history_size(), 1u);
}

}  // namespace
}  // namespace alight::vision
