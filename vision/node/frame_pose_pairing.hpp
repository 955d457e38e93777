#pragma once
// Which camera frame the vision processes, and with which motion-capture pose (paper 3.1.3,
// eq. 3: the scale of the homography's translation comes from the poses at the two exposures,
// so a frame is worth processing only with the pose at its own exposure time).
//
// The policy alight-vision runs, as a pure class so the in-process closed loop
// (test/autonomy/closed_loop.cpp) runs the same one and tests can drive it: no LCM, no clock.
// Every frame is processed, in the order it arrived, and what becomes of it depends only on the
// sequence of frames and poses offered (a replay through lcm-logplayer gives the same
// output on a loaded machine as live; an earlier policy let a newer frame displace one still
// waiting for its pose and timed the wait on the wall clock, so how busy the machine was decided
// which frames were processed):
//  - frames queue in arrival order; only the oldest can be decided, the others wait behind it
//    (the pipeline tracks its reference frame forward in time);
//  - it goes with its pose as soon as the buffer can interpolate one at its exposure
//    (PoseBuffer::lookup is kOk);
//  - when the buffer can never give one (the exposure is before its history or in a gap larger
//    than max_gap_s; poses come in time order) it goes without a pose at once (kPoseUnavailable);
//  - while the newest pose is still older than the exposure (or there is none yet) it waits, on
//    sensor time: until a frame exposed max_wait_us or more after it has arrived (motion capture
//    is late or lost while the camera runs on), then it goes without a pose (kPoseTimedOut: the
//    pipeline reports REASON_NO_POSE);
//  - at most max_queued frames wait; one more sends the oldest on without a pose (kQueueFull),
//    a bound on memory for stamps that never move on.

#include <algorithm>
#include <cassert>
#include <cstdint>
#include <deque>
#include <optional>
#include <utility>

#include "common/pose_buffer.hpp"

namespace alight::vision {

/// What became of a frame offered to FramePosePairing.
enum class PairingOutcome {
  kWithPose,         ///< to be processed with the pose at its exposure
  kPoseTimedOut,     ///< to be processed without a pose: none came while the camera ran on
  kPoseUnavailable,  ///< to be processed without a pose: the buffer can never give one
  kQueueFull,        ///< to be processed without a pose: too many frames waiting behind it
};
const char* to_string(PairingOutcome outcome);

/// The decision for the oldest waiting frame, given the pose buffer's answer at its exposure and
/// how far the newest frame's exposure is past its own (sensor time) [us]; nullopt: keep waiting.
std::optional<PairingOutcome> judge_waiting_frame(PoseBuffer::Status status, int64_t waited_us,
                                                  int64_t max_wait_us);

/// Frame is the caller's payload (the node's decoded image, the closed loop's rendered frame);
/// it is moved in and handed back, never looked at.
template <class Frame>
class FramePosePairing {
 public:
  /// A decided frame: process `frame` (stamped `utime`) with `pose` (nullopt: without one).
  struct Ready {
    Frame frame;
    int64_t utime = 0;               ///< the frame's exposure time [us]
    std::optional<PoseSample> pose;  ///< interpolated at `utime`; set iff kWithPose
    PairingOutcome outcome = PairingOutcome::kWithPose;
    PoseBuffer::Status pose_status = PoseBuffer::Status::kOk;  ///< the lookup that decided it
  };
  struct Counts {
    uint64_t with_pose = 0, timed_out = 0, unavailable = 0, queue_full = 0;
  };

  /// max_wait_us: longest wait for a pose, in exposure time of the frames that arrive meanwhile
  /// [us]; max_queued: frames that may wait at once (>= 1).
  FramePosePairing(const PoseBufferParams& pose_params, int64_t max_wait_us, size_t max_queued = 64)
      : poses_(pose_params), max_wait_us_(max_wait_us), max_queued_(max_queued) {
    assert(max_queued_ >= 1);
  }

  /// Adds a motion-capture sample (PoseBuffer::add: false when older than its history).
  bool add_pose(const PoseSample& pose) { return poses_.add(pose); }
  /// The pose history, for inserting through a validating path (vision/node/inputs.hpp
  /// add_mocap_pose) and for inspection.
  PoseBuffer& poses() { return poses_; }
  const PoseBuffer& poses() const { return poses_; }

  /// Queues a frame exposed at `frame_utime` behind those already waiting.
  void add_frame(Frame frame, int64_t frame_utime) {
    newest_frame_utime_ = seen_frame_ ? std::max(newest_frame_utime_, frame_utime) : frame_utime;
    seen_frame_ = true;
    queue_.push_back(Waiting{std::move(frame), frame_utime});
  }

  /// The oldest waiting frame once it is decided (it then leaves the queue); nullopt while it
  /// waits or when none does. Call until nullopt after every add_pose / add_frame: the answer
  /// depends only on what was added, so calling more often changes nothing.
  std::optional<Ready> poll() {
    if (queue_.empty()) return std::nullopt;
    Waiting& head = queue_.front();
    PoseSample pose;
    const PoseBuffer::Status status = poses_.lookup(head.utime, &pose);
    auto outcome = judge_waiting_frame(status, newest_frame_utime_ - head.utime, max_wait_us_);
    if (!outcome && queue_.size() > max_queued_) outcome = PairingOutcome::kQueueFull;
    if (!outcome) return std::nullopt;
    Ready r{std::move(head.frame), head.utime, std::nullopt, *outcome, status};
    queue_.pop_front();
    switch (*outcome) {
      case PairingOutcome::kWithPose:
        r.pose = pose;
        ++counts_.with_pose;
        break;
      case PairingOutcome::kPoseTimedOut:
        ++counts_.timed_out;
        break;
      case PairingOutcome::kPoseUnavailable:
        ++counts_.unavailable;
        break;
      case PairingOutcome::kQueueFull:
        ++counts_.queue_full;
        break;
    }
    return r;
  }

  /// Exposure time of the oldest waiting frame, if one waits.
  std::optional<int64_t> waiting_utime() const {
    return queue_.empty() ? std::nullopt : std::optional<int64_t>(queue_.front().utime);
  }
  size_t waiting() const { return queue_.size(); }
  const Counts& counts() const { return counts_; }
  int64_t max_wait_us() const { return max_wait_us_; }

 private:
  struct Waiting {
    Frame frame;
    int64_t utime;
  };
  PoseBuffer poses_;
  int64_t max_wait_us_;
  size_t max_queued_;
  std::deque<Waiting> queue_;
  bool seen_frame_ = false;
  int64_t newest_frame_utime_ = 0;  ///< newest exposure among the frames offered [us]
  Counts counts_;
};

}  // namespace alight::vision
