#include "vision/node/inputs.hpp"

#include <cmath>
#include <opencv2/core.hpp>

namespace alight::vision {

namespace {
bool all_finite(const double* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}
}  // namespace

std::optional<PoseSample> mocap_pose_from_msg(const pose_t& m, std::string* error) {
  const auto refuse = [&](const std::string& why) -> std::optional<PoseSample> {
    if (error) *error = "pose " + std::to_string(m.utime) + ": " + why;
    return std::nullopt;
  };
  if (!all_finite(m.pos, 3)) return refuse("position not finite");
  if (!all_finite(m.vel, 3)) return refuse("velocity not finite");
  if (!all_finite(m.orientation, 4)) return refuse("orientation not finite");
  if (!all_finite(m.angular_velocity_B, 3)) return refuse("angular velocity not finite");
  const double norm =
      std::sqrt(m.orientation[0] * m.orientation[0] + m.orientation[1] * m.orientation[1] +
                m.orientation[2] * m.orientation[2] + m.orientation[3] * m.orientation[3]);
  if (!(std::abs(norm - 1.0) <= 0.01))
    return refuse("orientation quaternion of norm " + std::to_string(norm) + " (not unit)");
  return from_msg(m);
}

bool add_mocap_pose(const pose_t& msg, PoseBuffer& poses, const StampCheck& accept_stamp,
                    const RejectValue& reject, const std::string& channel) {
  std::string why;
  const auto pose = mocap_pose_from_msg(msg, &why);
  if (!pose) {
    reject(channel, why);
    return false;
  }
  if (!accept_stamp(channel, msg.utime)) return false;
  return poses.add(*pose);
}

FrameInput camera_frame(const image_t& msg, const StampCheck& accept_stamp,
                        const RejectValue& reject, const std::string& channel) {
  FrameInput out;
  if (!accept_stamp(channel, msg.utime)) return out;
  out.use = true;
  std::string error;
  out.image = image_from_msg(msg, true, &error);
  if (!out.image) reject(channel, "frame " + std::to_string(msg.utime) + ": " + error);
  return out;
}

std::optional<std::string> run_guarded(const std::function<void()>& work) {
  try {
    work();
  } catch (const cv::Exception& e) {
    return std::string("OpenCV: ") + e.what();
  } catch (const std::exception& e) {
    return std::string(e.what());
  } catch (...) {
    return std::string("unknown exception");
  }
  return std::nullopt;
}

}  // namespace alight::vision
