#include "common/channels.hpp"

#include <algorithm>
#include <cctype>
#include <map>

namespace alight {

namespace channels {
bool single_publisher(const std::string& name) {
  return name != kNodeStatus && name != kOperatorCmd;
}

bool is_known(const std::string& name) {
  return std::any_of(kAll.begin(), kAll.end(), [&](const char* c) { return name == c; });
}

std::string message_type(const std::string& name) {
  static const std::map<std::string, std::string> kTypes = {
      {kCamera, "image_t"},
      {kFlowCamera, "image_t"},
      {kMocapPose, "pose_t"},
      {kImu, "imu_t"},
      {kRange, "range_t"},
      {kBaro, "baro_t"},
      {kStateEstimate, "state_estimate_t"},
      {kEstimatePose, "pose_t"},
      {kVisionTarget, "target_t"},
      {kVisionTiming, "vision_timing_t"},
      {kVisionPlatform, "platform_motion_t"},
      {kVisionDiag, "image_t"},
      {kOperatorCmd, "operator_cmd_t"},
      {kAutonomyStatus, "autonomy_status_t"},
      {kPositionSetpoint, "position_setpoint_t"},
      {kAttitudeCmd, "attitude_cmd_t"},
      {kSimTruth, "sim_truth_t"},
      {kSimPlatform, "platform_truth_t"},
      {kSimControl, "sim_control_t"},
      {kProcessStatus, "process_status_t"},
      {kNodeStatus, "node_status_t"},
      {kAutopilotPose, "pose_t"},
      {kAutopilotStatus, "autopilot_status_t"}};
  const auto it = kTypes.find(name);
  return it == kTypes.end() ? "" : it->second;
}
}  // namespace channels

namespace {

// LCM_MAX_CHANNEL_NAME_LENGTH in lcm/lcm.h.
constexpr size_t kMaxChannelNameLength = 63;

std::string known_list() {
  std::string s;
  for (const char* c : channels::kAll) s += (s.empty() ? "" : ", ") + std::string(c);
  return s;
}

// A subscription takes the name as a regular expression: only characters that match themselves.
bool usable_name(const std::string& name) {
  return !name.empty() && name.size() <= kMaxChannelNameLength &&
         std::all_of(name.begin(), name.end(), [](unsigned char c) {
           return std::isalnum(c) || c == '_' || c == '-' || c == '/';
         });
}

}  // namespace

ChannelRemap parse_remaps(const std::vector<std::string>& args) {
  ChannelRemap remap;
  for (const std::string& arg : args) {
    const std::string where = "--remap '" + arg + "': ";
    const auto eq = arg.find('=');
    if (eq == std::string::npos || arg.find('=', eq + 1) != std::string::npos)
      throw RemapError(where + "expected FROM=TO (e.g. CAMERA=CAMERA_LEFT)");
    const std::string from = arg.substr(0, eq), to = arg.substr(eq + 1);
    if (from.empty() || to.empty())
      throw RemapError(where + "expected FROM=TO with both names given (e.g. CAMERA=CAMERA_LEFT)");
    if (!channels::is_known(from))
      throw RemapError(where + "unknown channel '" + from + "' (known: " + known_list() + ")");
    if (!usable_name(to))
      throw RemapError(where + "'" + to +
                       "' is not a usable channel name (letters, digits, '_', '-', '/'; at most " +
                       std::to_string(kMaxChannelNameLength) + " characters)");
    const auto it = remap.to_.find(from);
    if (it != remap.to_.end() && it->second != to)
      throw RemapError(where + from + " is already remapped to " + it->second);
    remap.to_[from] = to;
  }
  // Two channels on one name would mix message types on it. One exception: a channel remapped
  // onto another known channel of the same type that keeps its own name, to read that one in
  // its place (alight-vision --remap MOCAP_POSE=ESTIMATE_POSE flies on the onboard estimate).
  const auto reads_in_place_of = [&](const std::string& a, const std::string& b) {
    const bool a_moved = remap(a) != a, b_moved = remap(b) != b;
    const std::string& kept = a_moved ? b : a;
    return a_moved != b_moved && remap(a) == remap(b) && remap(kept) == kept &&
           channels::message_type(a) == channels::message_type(b);
  };
  std::map<std::string, std::string> owner;  // name on LCM -> channel
  for (const char* c : channels::kAll) {
    const std::string name = remap(c);
    const auto [it, fresh] = owner.emplace(name, c);
    if (!fresh && !reads_in_place_of(it->second, c))
      throw RemapError("--remap: " + it->second + " and " + c + " would both be on channel " +
                       name + ": two channels cannot share one name");
  }
  return remap;
}

}  // namespace alight
