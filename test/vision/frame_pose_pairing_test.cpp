// The vision node's frame-to-pose policy (vision/frame_pose_pairing.hpp): known answers for each
// way a pose can come (after the frame, before it, never, in a gap, before the history), frames
// superseding each other, and properties over random input sequences.

#include "vision/frame_pose_pairing.hpp"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <variant>
#include <vector>

namespace alight::vision {
namespace {

using Pairing = FramePosePairing<std::string>;
using Status = PoseBuffer::Status;

constexpr int64_t kMaxWaitUs = 200'000;

// A pose at `utime` moving along x at 1 m/s from the origin, so an interpolated pose shows its
// stamp in its position.
PoseSample pose_at(int64_t utime) {
  PoseSample p;
  p.utime = utime;
  p.p_W_B = Vector3d(utime * 1e-6, 0, 1);
  p.v_W_B = Vector3d(1, 0, 0);
  return p;
}

TEST(JudgeWaitingFrame, EveryStatus) {
  EXPECT_EQ(judge_waiting_frame(Status::kOk, 0, kMaxWaitUs), PairingOutcome::kWithPose);
  EXPECT_EQ(judge_waiting_frame(Status::kOk, 10 * kMaxWaitUs, kMaxWaitUs),
            PairingOutcome::kWithPose);
  for (const Status s : {Status::kEmpty, Status::kAfterNewest}) {
    EXPECT_EQ(judge_waiting_frame(s, 0, kMaxWaitUs), std::nullopt);
    EXPECT_EQ(judge_waiting_frame(s, kMaxWaitUs - 1, kMaxWaitUs), std::nullopt);
    EXPECT_EQ(judge_waiting_frame(s, kMaxWaitUs, kMaxWaitUs), PairingOutcome::kPoseTimedOut);
  }
  for (const Status s : {Status::kBeforeHistory, Status::kGap})
    EXPECT_EQ(judge_waiting_frame(s, 0, kMaxWaitUs), PairingOutcome::kPoseUnavailable);
}

TEST(FramePosePairing, NothingWaitingGivesNothing) {
  Pairing p({}, kMaxWaitUs);
  EXPECT_FALSE(p.poll(0));
  p.add_pose(pose_at(0));
  EXPECT_FALSE(p.poll(1'000'000));
  EXPECT_FALSE(p.waiting_utime());
}

TEST(FramePosePairing, PoseAlreadyThereGoesAtOnceInterpolated) {
  Pairing p({}, kMaxWaitUs);
  for (int64_t t = 0; t <= 30'000; t += 10'000) p.add_pose(pose_at(t));
  EXPECT_FALSE(p.add_frame("f15", 15'000, 500));
  const auto r = p.poll(500);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->frame, "f15");
  EXPECT_EQ(r->utime, 15'000);
  EXPECT_EQ(r->outcome, PairingOutcome::kWithPose);
  EXPECT_EQ(r->pose_status, Status::kOk);
  ASSERT_TRUE(r->pose);
  EXPECT_EQ(r->pose->utime, 15'000);
  EXPECT_NEAR(r->pose->p_W_B.x(), 0.015, 1e-12);
  EXPECT_FALSE(p.poll(500));  // decided once
  EXPECT_EQ(p.counts().with_pose, 1u);
}

TEST(FramePosePairing, WaitsForThePoseAfterTheExposure) {
  Pairing p({}, kMaxWaitUs);
  p.add_pose(pose_at(0));
  p.add_pose(pose_at(10'000));
  p.add_frame("f", 15'000, 1'000'000);
  EXPECT_FALSE(p.poll(1'000'000));
  EXPECT_FALSE(p.poll(1'000'000 + kMaxWaitUs - 1));
  EXPECT_EQ(p.waiting_utime(), 15'000);
  p.add_pose(pose_at(20'000));
  const auto r = p.poll(1'000'000 + kMaxWaitUs - 1);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->outcome, PairingOutcome::kWithPose);
  ASSERT_TRUE(r->pose);
  EXPECT_NEAR(r->pose->p_W_B.x(), 0.015, 1e-12);
}

TEST(FramePosePairing, PoseThatNeverComesTimesOutOnTheCallersClock) {
  Pairing p({}, kMaxWaitUs);
  p.add_pose(pose_at(0));
  p.add_pose(pose_at(10'000));
  // The wait counts from wait_from_utime, not from the exposure.
  p.add_frame("f", 15'000, 5'000'000);
  EXPECT_FALSE(p.poll(5'000'000 + kMaxWaitUs - 1));
  const auto r = p.poll(5'000'000 + kMaxWaitUs);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->frame, "f");
  EXPECT_EQ(r->outcome, PairingOutcome::kPoseTimedOut);
  EXPECT_EQ(r->pose_status, Status::kAfterNewest);
  EXPECT_FALSE(r->pose);
  EXPECT_EQ(p.counts().timed_out, 1u);
}

TEST(FramePosePairing, NoPoseAtAllTimesOut) {
  Pairing p({}, kMaxWaitUs);
  p.add_frame("f", 15'000, 0);
  EXPECT_FALSE(p.poll(kMaxWaitUs - 1));
  const auto r = p.poll(kMaxWaitUs);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->outcome, PairingOutcome::kPoseTimedOut);
  EXPECT_EQ(r->pose_status, Status::kEmpty);
}

TEST(FramePosePairing, ZeroWaitReleasesAtOnce) {
  Pairing p({}, 0);
  p.add_pose(pose_at(0));
  p.add_frame("f", 15'000, 0);
  const auto r = p.poll(0);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->outcome, PairingOutcome::kPoseTimedOut);
}

TEST(FramePosePairing, ExposureBeforeTheHistoryGoesWithoutPoseAtOnce) {
  Pairing p({}, kMaxWaitUs);
  p.add_pose(pose_at(100'000));
  p.add_pose(pose_at(110'000));
  p.add_frame("old", 50'000, 0);
  const auto r = p.poll(0);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->outcome, PairingOutcome::kPoseUnavailable);
  EXPECT_EQ(r->pose_status, Status::kBeforeHistory);
  EXPECT_FALSE(r->pose);
  EXPECT_EQ(p.counts().unavailable, 1u);
}

TEST(FramePosePairing, ExposureInAGapGoesWithoutPoseAtOnce) {
  PoseBufferParams bp;
  bp.max_gap_s = 0.1;
  Pairing p(bp, kMaxWaitUs);
  p.add_pose(pose_at(0));
  p.add_pose(pose_at(300'000));  // motion capture lost for 0.3 s
  p.add_frame("f", 150'000, 0);
  const auto r = p.poll(0);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->outcome, PairingOutcome::kPoseUnavailable);
  EXPECT_EQ(r->pose_status, Status::kGap);
}

TEST(FramePosePairing, ANewerFrameSupersedesTheWaitingOne) {
  Pairing p({}, kMaxWaitUs);
  p.add_pose(pose_at(0));
  EXPECT_FALSE(p.add_frame("a", 15'000, 0));
  EXPECT_FALSE(p.poll(1000));
  const auto dropped = p.add_frame("b", 48'000, 2000);
  ASSERT_TRUE(dropped);
  EXPECT_EQ(dropped->utime, 15'000);
  EXPECT_EQ(dropped->outcome, PairingOutcome::kSuperseded);
  EXPECT_EQ(p.waiting_utime(), 48'000);
  // b's wait counts from its own arrival.
  EXPECT_FALSE(p.poll(2000 + kMaxWaitUs - 1));
  for (int64_t t = 10'000; t <= 50'000; t += 10'000) p.add_pose(pose_at(t));
  const auto r = p.poll(2000 + kMaxWaitUs - 1);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->frame, "b");
  EXPECT_EQ(r->outcome, PairingOutcome::kWithPose);
  EXPECT_EQ(p.counts().superseded, 1u);
  EXPECT_EQ(p.counts().with_pose, 1u);
}

TEST(FramePosePairing, ArrivalOrderNotStampOrderDecidesWhichFrameWaits) {
  // A frame offered after another but exposed earlier still takes its place: the node's stamp
  // guard is what refuses frames going back in time, not this policy.
  Pairing p({}, kMaxWaitUs);
  for (int64_t t = 0; t <= 20'000; t += 10'000) p.add_pose(pose_at(t));
  p.add_frame("late", 35'000, 0);
  const auto dropped = p.add_frame("early", 5'000, 0);
  ASSERT_TRUE(dropped);
  EXPECT_EQ(dropped->utime, 35'000);
  const auto r = p.poll(0);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->frame, "early");
  EXPECT_EQ(r->outcome, PairingOutcome::kWithPose);
}

TEST(FramePosePairing, PosesAddedOutOfOrderAreUsedInTimeOrder) {
  Pairing p({}, kMaxWaitUs);
  p.add_pose(pose_at(20'000));
  p.add_pose(pose_at(0));
  p.add_pose(pose_at(10'000));
  p.add_frame("f", 5'000, 0);
  const auto r = p.poll(0);
  ASSERT_TRUE(r);
  ASSERT_TRUE(r->pose);
  EXPECT_NEAR(r->pose->p_W_B.x(), 0.005, 1e-12);
}

TEST(FramePosePairing, OutcomesHaveNames) {
  for (const auto o : {PairingOutcome::kWithPose, PairingOutcome::kPoseTimedOut,
                       PairingOutcome::kPoseUnavailable, PairingOutcome::kSuperseded})
    EXPECT_NE(std::string(to_string(o)), "?");
}

// --- Properties over random input sequences -------------------------------------------------

struct AddPose {
  int64_t utime;
};
struct AddFrame {
  int64_t utime, wait_from;
};
struct Poll {
  int64_t now;
};
using Op = std::variant<AddPose, AddFrame, Poll>;

// Motion capture at 100 Hz with dropouts, frames at 30 Hz stamped around the poses, the caller's
// clock moving forward: the situations the node meets, in random interleavings.
std::vector<Op> random_ops(uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<Op> ops;
  int64_t pose_t = 0, frame_t = 0, now = 0;
  for (int i = 0; i < 400; ++i) {
    switch (std::uniform_int_distribution<int>(0, 5)(rng)) {
      case 0:
      case 1:
        pose_t += std::uniform_int_distribution<int>(0, 9)(rng) == 0 ? 250'000 : 10'000;
        ops.push_back(AddPose{pose_t});
        break;
      case 2:
        frame_t += 33'333;
        now += std::uniform_int_distribution<int64_t>(0, 20'000)(rng);
        ops.push_back(AddFrame{frame_t, now});
        break;
      default:
        now += std::uniform_int_distribution<int64_t>(0, 80'000)(rng);
        ops.push_back(Poll{now});
        break;
    }
  }
  return ops;
}

struct Event {
  int frame = -1;  // index of the frame in the order offered
  PairingOutcome outcome = PairingOutcome::kWithPose;
  std::optional<Vector3d> p_W_B;
  bool operator==(const Event& o) const {
    return frame == o.frame && outcome == o.outcome && p_W_B == o.p_W_B;
  }
};

std::vector<Event> run(const std::vector<Op>& ops, bool repeat_polls, int* still_waiting) {
  FramePosePairing<int> p({}, kMaxWaitUs);
  std::vector<Event> events;
  std::vector<int64_t> stamps;  // of each frame offered
  int64_t last_now = 0;
  const auto poll = [&](int64_t now) {
    if (auto r = p.poll(now)) {
      EXPECT_EQ(r->utime, stamps[r->frame]);
      if (r->pose) EXPECT_NEAR(r->pose->p_W_B.x(), stamps[r->frame] * 1e-6, 1e-9);
      events.push_back(
          {r->frame, r->outcome, r->pose ? std::optional(r->pose->p_W_B) : std::nullopt});
    }
  };
  for (const Op& op : ops) {
    if (const auto* a = std::get_if<AddPose>(&op)) {
      p.add_pose(pose_at(a->utime));
      poll(last_now);
    } else if (const auto* f = std::get_if<AddFrame>(&op)) {
      const int id = static_cast<int>(stamps.size());
      stamps.push_back(f->utime);
      if (auto d = p.add_frame(id, f->utime, f->wait_from)) {
        EXPECT_EQ(d->outcome, PairingOutcome::kSuperseded);
        EXPECT_EQ(d->utime, stamps[id - 1]);  // only the frame offered last can be waiting
        events.push_back({id - 1, d->outcome, std::nullopt});
      }
      last_now = f->wait_from;
      poll(last_now);
    } else {
      last_now = std::get<Poll>(op).now;
      poll(last_now);
      if (repeat_polls) poll(last_now);  // a second poll at the same time decides nothing new
    }
  }
  *still_waiting = p.waiting_utime() ? 1 : 0;
  return events;
}

TEST(FramePosePairingProperty, OutputDependsOnlyOnTheInputSequence) {
  for (uint32_t seed = 1; seed <= 50; ++seed) {
    const auto ops = random_ops(seed);
    int w1 = 0, w2 = 0, w3 = 0;
    const auto a = run(ops, false, &w1);
    const auto b = run(ops, false, &w2);
    const auto c = run(ops, true, &w3);
    EXPECT_EQ(a, b) << "seed " << seed;
    EXPECT_EQ(a, c) << "seed " << seed << ": a repeated poll changed the output";
    EXPECT_EQ(w1, w3);
  }
}

TEST(FramePosePairingProperty, EveryFrameIsDecidedOnceInOrderWithItsOwnPose) {
  int n_with = 0, n_without = 0, n_superseded = 0;
  for (uint32_t seed = 1; seed <= 50; ++seed) {
    const auto ops = random_ops(seed);
    int n_frames = 0;
    for (const Op& op : ops) n_frames += std::holds_alternative<AddFrame>(op) ? 1 : 0;
    int waiting = 0;
    const auto events = run(ops, false, &waiting);
    ASSERT_EQ(static_cast<int>(events.size()) + waiting, n_frames) << "seed " << seed;
    for (size_t i = 0; i < events.size(); ++i) {
      EXPECT_EQ(events[i].frame, static_cast<int>(i)) << "seed " << seed;
      // A pose comes exactly with kWithPose, and it is the one at the frame's exposure (the
      // poses move at 1 m/s along x: x = stamp in seconds).
      EXPECT_EQ(events[i].p_W_B.has_value(), events[i].outcome == PairingOutcome::kWithPose);
      switch (events[i].outcome) {
        case PairingOutcome::kWithPose:
          ++n_with;
          break;
        case PairingOutcome::kSuperseded:
          ++n_superseded;
          break;
        default:
          ++n_without;
      }
    }
  }
  // The sequences exercise every branch.
  EXPECT_GT(n_with, 0);
  EXPECT_GT(n_without, 0);
  EXPECT_GT(n_superseded, 0);
}

}  // namespace
}  // namespace alight::vision
