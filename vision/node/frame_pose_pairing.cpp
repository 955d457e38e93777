#include "vision/node/frame_pose_pairing.hpp"

namespace alight::vision {

const char* to_string(PairingOutcome outcome) {
  switch (outcome) {
    case PairingOutcome::kWithPose:
      return "with pose";
    case PairingOutcome::kPoseTimedOut:
      return "no pose in time";
    case PairingOutcome::kPoseUnavailable:
      return "no pose for its stamp";
    case PairingOutcome::kQueueFull:
      return "too many frames waiting";
  }
  return "?";
}

std::optional<PairingOutcome> judge_waiting_frame(PoseBuffer::Status status, int64_t waited_us,
                                                  int64_t max_wait_us) {
  switch (status) {
    case PoseBuffer::Status::kOk:
      return PairingOutcome::kWithPose;
    case PoseBuffer::Status::kEmpty:
    case PoseBuffer::Status::kAfterNewest:
      // The pose after the exposure may still come, unless the camera ran on max_wait_us
      // without it.
      if (waited_us < max_wait_us) return std::nullopt;
      return PairingOutcome::kPoseTimedOut;
    case PoseBuffer::Status::kBeforeHistory:
    case PoseBuffer::Status::kGap:
      // Poses come in time order (a stamp going backwards is refused at the node's input), so
      // later ones neither fill a gap already bracketed nor reach before the oldest held.
      return PairingOutcome::kPoseUnavailable;
  }
  return PairingOutcome::kPoseUnavailable;
}

}  // namespace alight::vision
