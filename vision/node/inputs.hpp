#pragma once
// The alight-vision node's input boundary, as functions the node calls and tests can
// drive with their own stamp judge and clock. Every input is untrusted: a refused message is
// counted through the node's callbacks (NODE_STATUS rejected_values / rejected_stamps) and
// never reaches the pose buffer or the pipeline; nothing here throws.

#include <alight/image_t.hpp>
#include <alight/pose_t.hpp>
#include <functional>
#include <optional>
#include <string>

#include "common/channels.hpp"
#include "common/image_msg.hpp"
#include "common/msg_convert.hpp"
#include "common/pose_buffer.hpp"

namespace alight::vision {

/// Node::accept_stamp: true when the stamp of a message on `channel` may be used.
using StampCheck = std::function<bool(const std::string& channel, int64_t utime)>;
/// Node::reject_value: counts and logs a message a conversion refused.
using RejectValue = std::function<void(const std::string& channel, const std::string& why)>;

/// A motion-capture pose checked for use: every field finite and the quaternion of unit norm
/// (within 1 %, then normalised as from_msg does); nullopt and *error otherwise.
std::optional<PoseSample> mocap_pose_from_msg(const pose_t& msg, std::string* error);

/// MOCAP_POSE: values first (a NaN pose must not move the stamp guard), then the stamp (a pose
/// an hour ahead would otherwise push every later pose out of the buffer's history window, so
/// that every frame after it went without a pose), then the buffer. True when added.
bool add_mocap_pose(const pose_t& msg, PoseBuffer& poses, const StampCheck& accept_stamp,
                    const RejectValue& reject, const std::string& channel = channels::kMocapPose);

/// What became of a CAMERA message.
struct FrameInput {
  bool use = false;            ///< false: the stamp was refused, drop the message silently
  std::optional<Image> image;  ///< the decoded frame; nullopt with use = true: a bad image,
                               ///< still reported downstream (REASON_BAD_IMAGE) at its stamp
};

/// CAMERA: the stamp first (a frame from an hour ahead is not reported at all), then the safe
/// decode (image_from_msg, mono); a frame that does not decode is counted through `reject`.
FrameInput camera_frame(const image_t& msg, const StampCheck& accept_stamp,
                        const RejectValue& reject, const std::string& channel = channels::kCamera);

/// Runs one frame's work; an exception out of it (cv::Exception from OpenCV, bad_alloc, any
/// std::exception) is returned as its text instead of ending the node. nullopt: it ran through.
std::optional<std::string> run_guarded(const std::function<void()>& work);

}  // namespace alight::vision
