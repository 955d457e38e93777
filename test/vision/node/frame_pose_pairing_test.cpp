// The vision node's frame-to-pose policy (vision/node/frame_pose_pairing.hpp): known answers for
// each way a pose can come (after the frame, before it, never, in a gap, before the history),
// frames queueing behind one that waits, and properties over random input sequences: every frame
// decided once, in order, with its own pose, and the output a function of the input sequence.

#include "vision/node/frame_pose_pairing.hpp"

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
  EXPECT_FALSE(p.poll());
  p.add_pose(pose_at(0));
  EXPECT_FALSE(p.poll());
  EXPECT_FALSE(p.waiting_utime());
  EXPECT_EQ(p.waiting(), 0u);
}

TEST(FramePosePairing, PoseAlreadyThereGoesAtOnceInterpolated) {
  Pairing p({}, kMaxWaitUs);
  for (int64_t t = 0; t <= 30'000; t += 10'000) p.add_pose(pose_at(t));
  p.add_frame("f15", 15'000);
  const auto r = p.poll();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->frame, "f15");
  EXPECT_EQ(r->utime, 15'000);
  EXPECT_EQ(r->outcome, PairingOutcome::kWithPose);
  EXPECT_EQ(r->pose_status, Status::kOk);
  ASSERT_TRUE(r->pose);
  EXPECT_EQ(r->pose->utime, 15'000);
  EXPECT_NEAR(r->pose->p_W_B.x(), 0.015, 1e-12);
  EXPECT_FALSE(p.poll());  // decided once
  EXPECT_EQ(p.counts().with_pose, 1u);
}

TEST(FramePosePairing, WaitsForThePoseAfterTheExposure) {
  Pairing p({}, kMaxWaitUs);
  p.add_pose(pose_at(0));
  p.add_pose(pose_at(10'000));
  p.add_frame("f", 15'000);
  EXPECT_FALSE(p.poll());
  EXPECT_EQ(p.waiting_utime(), 15'000);
  p.add_pose(pose_at(20'000));
  const auto r = p.poll();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->outcome, PairingOutcome::kWithPose);
  ASSERT_TRUE(r->pose);
  EXPECT_NEAR(r->pose->p_W_B.x(), 0.015, 1e-12);
}

TEST(FramePosePairing, LaterFramesQueueBehindTheWaitingOneAndGoInOrder) {
  // Motion capture 10 ms late: a frame or two arrive before the pose after the first exposure.
  Pairing p({}, kMaxWaitUs);
  p.add_pose(pose_at(0));
  p.add_frame("a", 15'000);
  p.add_frame("b", 48'000);
  EXPECT_FALSE(p.poll());
  EXPECT_EQ(p.waiting(), 2u);
  for (int64_t t = 10'000; t <= 40'000; t += 10'000) p.add_pose(pose_at(t));
  auto r = p.poll();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->frame, "a");
  EXPECT_EQ(r->outcome, PairingOutcome::kWithPose);
  EXPECT_FALSE(p.poll());  // b still needs a pose after 48 ms
  p.add_pose(pose_at(50'000));
  r = p.poll();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->frame, "b");
  ASSERT_TRUE(r->pose);
  EXPECT_NEAR(r->pose->p_W_B.x(), 0.048, 1e-12);
  EXPECT_EQ(p.counts().with_pose, 2u);
}

TEST(FramePosePairing, PoseThatNeverComesTimesOutWhenTheCameraRunsOnWithoutIt) {
  Pairing p({}, kMaxWaitUs);
  p.add_pose(pose_at(0));
  p.add_pose(pose_at(10'000));
  p.add_frame("f", 15'000);
  // The wait is measured in the exposures of later frames, never on a clock: however long the
  // caller polls, f waits until a frame kMaxWaitUs after it has arrived.
  p.add_frame("g", 15'000 + kMaxWaitUs - 1);
  for (int i = 0; i < 3; ++i) EXPECT_FALSE(p.poll());
  p.add_frame("h", 15'000 + kMaxWaitUs);
  const auto r = p.poll();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->frame, "f");
  EXPECT_EQ(r->outcome, PairingOutcome::kPoseTimedOut);
  EXPECT_EQ(r->pose_status, Status::kAfterNewest);
  EXPECT_FALSE(r->pose);
  EXPECT_FALSE(p.poll());  // g has waited 1 us of exposure time
  EXPECT_EQ(p.counts().timed_out, 1u);
  EXPECT_EQ(p.waiting(), 2u);
}

TEST(FramePosePairing, NoPoseAtAllTimesOutFrameAfterFrame) {
  Pairing p({}, kMaxWaitUs);
  std::vector<std::string> out;
  for (int k = 0; k < 20; ++k) {
    p.add_frame("f" + std::to_string(k), k * 50'000);
    while (auto r = p.poll()) {
      EXPECT_EQ(r->outcome, PairingOutcome::kPoseTimedOut);
      EXPECT_EQ(r->pose_status, Status::kEmpty);
      out.push_back(r->frame);
    }
  }
  // Each frame goes once a frame 200 ms (4 frames) after it has come: 16 of 20, in order.
  ASSERT_EQ(out.size(), 16u);
  for (size_t i = 0; i < out.size(); ++i) EXPECT_EQ(out[i], "f" + std::to_string(i));
}

TEST(FramePosePairing, ZeroWaitReleasesAtOnce) {
  Pairing p({}, 0);
  p.add_pose(pose_at(0));
  p.add_frame("f", 15'000);
  const auto r = p.poll();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->outcome, PairingOutcome::kPoseTimedOut);
}

TEST(FramePosePairing, ExposureBeforeTheHistoryGoesWithoutPoseAtOnce) {
  Pairing p({}, kMaxWaitUs);
  p.add_pose(pose_at(100'000));
  p.add_pose(pose_at(110'000));
  p.add_frame("old", 50'000);
  const auto r = p.poll();
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
  p.add_frame("f", 150'000);
  const auto r = p.poll();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->outcome, PairingOutcome::kPoseUnavailable);
  EXPECT_EQ(r->pose_status, Status::kGap);
}

TEST(FramePosePairing, AFullQueueSendsTheOldestOnWithoutAPose) {
  // Frames whose stamps never move on (a camera stuck on one stamp) cannot time out: the bound
  // on the queue does.
  Pairing p({}, kMaxWaitUs, 3);
  p.add_pose(pose_at(0));
  for (int k = 0; k < 3; ++k) p.add_frame("f" + std::to_string(k), 15'000);
  EXPECT_FALSE(p.poll());
  p.add_frame("f3", 15'000);
  const auto r = p.poll();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->frame, "f0");
  EXPECT_EQ(r->outcome, PairingOutcome::kQueueFull);
  EXPECT_FALSE(r->pose);
  EXPECT_FALSE(p.poll());
  EXPECT_EQ(p.waiting(), 3u);
  EXPECT_EQ(p.counts().queue_full, 1u);
}

TEST(FramePosePairing, ArrivalOrderNotStampOrderDecidesTheOrder) {
  // A frame offered after another but exposed earlier waits behind it: the node's stamp guard
  // is what refuses frames going back in time, not this policy.
  Pairing p({}, kMaxWaitUs);
  for (int64_t t = 0; t <= 20'000; t += 10'000) p.add_pose(pose_at(t));
  p.add_frame("late", 35'000);
  p.add_frame("early", 5'000);
  EXPECT_FALSE(p.poll());
  for (int64_t t = 30'000; t <= 40'000; t += 10'000) p.add_pose(pose_at(t));
  auto r = p.poll();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->frame, "late");
  r = p.poll();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->frame, "early");
  EXPECT_EQ(r->outcome, PairingOutcome::kWithPose);
}

TEST(FramePosePairing, PosesAddedOutOfOrderAreUsedInTimeOrder) {
  Pairing p({}, kMaxWaitUs);
  p.add_pose(pose_at(20'000));
  p.add_pose(pose_at(0));
  p.add_pose(pose_at(10'000));
  p.add_frame("f", 5'000);
  const auto r = p.poll();
  ASSERT_TRUE(r);
  ASSERT_TRUE(r->pose);
  EXPECT_NEAR(r->pose->p_W_B.x(), 0.005, 1e-12);
}

TEST(FramePosePairing, OutcomesHaveNames) {
  for (const auto o : {PairingOutcome::kWithPose, PairingOutcome::kPoseTimedOut,
                       PairingOutcome::kPoseUnavailable, PairingOutcome::kQueueFull})
    EXPECT_NE(std::string(to_string(o)), "?");
}

// --- Properties over random input sequences -------------------------------------------------

struct AddPose {
  int64_t utime;
};
struct AddFrame {
  int64_t utime;
};
using Op = std::variant<AddPose, AddFrame>;

// Motion capture at 100 Hz with dropouts, frames at 30 Hz stamped around the poses, in random
// interleavings: the situations the node meets.
std::vector<Op> random_ops(uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<Op> ops;
  int64_t pose_t = 0, frame_t = 0;
  for (int i = 0; i < 400; ++i) {
    if (std::uniform_int_distribution<int>(0, 2)(rng) < 2) {
      pose_t += std::uniform_int_distribution<int>(0, 9)(rng) == 0 ? 250'000 : 10'000;
      ops.push_back(AddPose{pose_t});
    } else {
      frame_t += 33'333;
      ops.push_back(AddFrame{frame_t});
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

// polls_per_step: how often the caller polls after each input (a busy node polls once and
// drains; a test may poll again): the output must not depend on it.
std::vector<Event> run(const std::vector<Op>& ops, int polls_per_step, size_t* still_waiting) {
  FramePosePairing<int> p({}, kMaxWaitUs, 8);
  std::vector<Event> events;
  std::vector<int64_t> stamps;  // of each frame offered
  const auto drain = [&] {
    for (int k = 0; k < polls_per_step; ++k) {
      while (auto r = p.poll()) {
        EXPECT_EQ(r->utime, stamps[r->frame]);
        if (r->pose) {
          EXPECT_NEAR(r->pose->p_W_B.x(), stamps[r->frame] * 1e-6, 1e-9);
        }
        events.push_back(
            {r->frame, r->outcome, r->pose ? std::optional(r->pose->p_W_B) : std::nullopt});
      }
    }
  };
  for (const Op& op : ops) {
    if (const auto* a = std::get_if<AddPose>(&op)) {
      p.add_pose(pose_at(a->utime));
    } else {
      const int id = static_cast<int>(stamps.size());
      stamps.push_back(std::get<AddFrame>(op).utime);
      p.add_frame(id, stamps.back());
    }
    drain();
  }
  *still_waiting = p.waiting();
  return events;
}

TEST(FramePosePairingProperty, OutputDependsOnlyOnTheInputSequence) {
  for (uint32_t seed = 1; seed <= 50; ++seed) {
    const auto ops = random_ops(seed);
    size_t w1 = 0, w2 = 0, w3 = 0;
    const auto a = run(ops, 1, &w1);
    const auto b = run(ops, 1, &w2);
    const auto c = run(ops, 3, &w3);
    EXPECT_EQ(a, b) << "seed " << seed;
    EXPECT_EQ(a, c) << "seed " << seed << ": polling more often changed the output";
    EXPECT_EQ(w1, w3);
  }
}

TEST(FramePosePairingProperty, EveryFrameIsDecidedOnceInOrderWithItsOwnPose) {
  int n_with = 0, n_without = 0;
  for (uint32_t seed = 1; seed <= 50; ++seed) {
    const auto ops = random_ops(seed);
    int n_frames = 0;
    for (const Op& op : ops) n_frames += std::holds_alternative<AddFrame>(op) ? 1 : 0;
    size_t waiting = 0;
    const auto events = run(ops, 1, &waiting);
    // None dropped: every frame offered is either decided or still waiting.
    ASSERT_EQ(events.size() + waiting, static_cast<size_t>(n_frames)) << "seed " << seed;
    EXPECT_LE(waiting, 8u);
    for (size_t i = 0; i < events.size(); ++i) {
      EXPECT_EQ(events[i].frame, static_cast<int>(i)) << "seed " << seed;
      // A pose comes exactly with kWithPose, and it is the one at the frame's exposure (the
      // poses move at 1 m/s along x: x = stamp in seconds).
      EXPECT_EQ(events[i].p_W_B.has_value(), events[i].outcome == PairingOutcome::kWithPose);
      (events[i].outcome == PairingOutcome::kWithPose ? n_with : n_without)++;
    }
  }
  // The sequences exercise both branches.
  EXPECT_GT(n_with, 0);
  EXPECT_GT(n_without, 0);
}

}  // namespace
}  // namespace alight::vision
