#pragma once
// Which camera frame the vision processes, and with which motion-capture pose (paper 3.1.3,
// eq. 3: the scale of the homography's translation comes from the poses at the two exposures,
// so a frame is worth processing only with the pose at its own exposure time).
//
// The policy alight-vision runs, as a pure class so the in-process closed loop
// (test/autonomy/closed_loop.cpp) runs the same one and tests can drive it: no LCM, no clock.
// The caller feeds poses and frames with their stamps and asks, with its own clock, whether the
// waiting frame is decided:
//  - one frame waits at a time; a newer frame that arrives first takes its place and the older
//    one is dropped (kSuperseded): the newest view is the one worth the processing time, and the
//    node already takes only the newest frame off LCM when it falls behind (Node::on_latest);
//  - the frame goes with its pose as soon as the buffer can interpolate one at its exposure
//    (PoseBuffer::lookup is kOk);
//  - while the newest pose is still older than the exposure (or there is none yet) the frame
//    waits, at most max_wait_us of the caller's clock counted from when it was offered; then it
//    goes without a pose (kPoseTimedOut: the pipeline reports REASON_NO_POSE);
//  - when the buffer can never give one (the exposure is before its history or in a gap larger
//    than max_gap_s; poses come in time order) it goes without a pose at once
//    (kPoseUnavailable).
// The output depends only on the sequence of calls and their arguments.

#include <cstdint>
#include <optional>
#include <utility>

#include "common/pose_buffer.hpp"

namespace alight::vision {

/// What became of a frame offered to FramePosePairing.
enum class PairingOutcome {
  kWithPose,         ///< to be processed with the pose at its exposure
  kPoseTimedOut,     ///< to be processed without a pose: none after its exposure in time
  kPoseUnavailable,  ///< to be processed without a pose: the buffer can never give one
  kSuperseded,       ///< dropped unprocessed: a newer frame arrived before its pose
};
const char* to_string(PairingOutcome outcome);

/// The decision for a waiting frame, given the pose buffer's answer at its exposure and how long
/// it has waited (caller's clock); nullopt: keep waiting.
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
  /// A frame dropped unprocessed.
  struct Dropped {
    int64_t utime = 0;  ///< the frame's exposure time [us]
    PairingOutcome outcome = PairingOutcome::kSuperseded;
  };
  struct Counts {
    uint64_t with_pose = 0, timed_out = 0, unavailable = 0, superseded = 0;
  };

  /// max_wait_us: longest wait for a pose after the exposure, on the caller's clock [us].
  FramePosePairing(const PoseBufferParams& pose_params, int64_t max_wait_us)
      : poses_(pose_params), max_wait_us_(max_wait_us) {}

  /// Adds a motion-capture sample (PoseBuffer::add: false when older than its history).
  bool add_pose(const PoseSample& pose) { return poses_.add(pose); }
  /// The pose history, for inserting through a validating path (vision/inputs.hpp
  /// add_mocap_pose) and for inspection.
  PoseBuffer& poses() { return poses_; }
  const PoseBuffer& poses() const { return poses_; }

  /// Offers a frame exposed at `frame_utime`; its wait for a pose is counted from
  /// `wait_from_utime` on the clock later passed to poll(). Returns the frame it displaced.
  std::optional<Dropped> add_frame(Frame frame, int64_t frame_utime, int64_t wait_from_utime) {
    std::optional<Dropped> dropped;
    if (waiting_) {
      dropped = Dropped{waiting_->utime, PairingOutcome::kSuperseded};
      ++counts_.superseded;
    }
    waiting_.emplace(Waiting{std::move(frame), frame_utime, wait_from_utime});
    return dropped;
  }

  /// The waiting frame once it is decided (then it no longer waits); nullopt while it waits or
  /// when none does. Call after every add_pose / add_frame and periodically, so a frame whose
  /// pose never comes is released once max_wait_us has passed.
  std::optional<Ready> poll(int64_t now_utime) {
    if (!waiting_) return std::nullopt;
    PoseSample pose;
    const PoseBuffer::Status status = poses_.lookup(waiting_->utime, &pose);
    const auto outcome =
        judge_waiting_frame(status, now_utime - waiting_->wait_from_utime, max_wait_us_);
    if (!outcome) return std::nullopt;
    Ready r{std::move(waiting_->frame), waiting_->utime, std::nullopt, *outcome, status};
    waiting_.reset();
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
      case PairingOutcome::kSuperseded:  // only add_frame() supersedes
        break;
    }
    return r;
  }

  /// Exposure time of the waiting frame, if one waits.
  std::optional<int64_t> waiting_utime() const {
    return waiting_ ? std::optional<int64_t>(waiting_->utime) : std::nullopt;
  }
  const Counts& counts() const { return counts_; }
  int64_t max_wait_us() const { return max_wait_us_; }

 private:
  struct Waiting {
    Frame frame;
    int64_t utime;
    int64_t wait_from_utime;
  };
  PoseBuffer poses_;
  int64_t max_wait_us_;
  std::optional<Waiting> waiting_;
  Counts counts_;
};

}  // namespace alight::vision
