#include "link/payload.hpp"

#include <alight/attitude_cmd_t.hpp>
#include <alight/autonomy_status_t.hpp>
#include <alight/autopilot_status_t.hpp>
#include <alight/baro_t.hpp>
#include <alight/image_t.hpp>
#include <alight/imu_t.hpp>
#include <alight/node_status_t.hpp>
#include <alight/operator_cmd_t.hpp>
#include <alight/platform_motion_t.hpp>
#include <alight/platform_truth_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/position_setpoint_t.hpp>
#include <alight/process_status_t.hpp>
#include <alight/range_t.hpp>
#include <alight/sim_control_t.hpp>
#include <alight/sim_truth_t.hpp>
#include <alight/state_estimate_t.hpp>
#include <alight/target_t.hpp>
#include <alight/vision_timing_t.hpp>
#include <map>

#include "common/bus_trailer.hpp"
#include "common/channels.hpp"
#include "common/decode.hpp"

namespace alight::link {

namespace {

using Check = bool (*)(std::span<const uint8_t>);

template <class Msg>
bool decodes(std::span<const uint8_t> payload) {
  Msg msg;
  return decode_message(msg, payload.data(), payload.size());
}

const std::map<std::string, Check>& checks() {
  static const std::map<std::string, Check> kChecks = {
      {"attitude_cmd_t", decodes<attitude_cmd_t>},
      {"autonomy_status_t", decodes<autonomy_status_t>},
      {"autopilot_status_t", decodes<autopilot_status_t>},
      {"baro_t", decodes<baro_t>},
      {"image_t", decodes<image_t>},
      {"imu_t", decodes<imu_t>},
      {"node_status_t", decodes<node_status_t>},
      {"operator_cmd_t", decodes<operator_cmd_t>},
      {"platform_truth_t", decodes<platform_truth_t>},
      {"platform_motion_t", decodes<platform_motion_t>},
      {"pose_t", decodes<pose_t>},
      {"position_setpoint_t", decodes<position_setpoint_t>},
      {"process_status_t", decodes<process_status_t>},
      {"range_t", decodes<range_t>},
      {"sim_control_t", decodes<sim_control_t>},
      {"sim_truth_t", decodes<sim_truth_t>},
      {"state_estimate_t", decodes<state_estimate_t>},
      {"target_t", decodes<target_t>},
      {"vision_timing_t", decodes<vision_timing_t>}};
  return kChecks;
}

}  // namespace

bool valid_payload(const std::string& channel, std::span<const uint8_t> payload) {
  // decode_message would take a trailer at the end for the bus's and decode what is in front of
  // it; a payload never has one (the sender's Node split it off), so one there is not ours.
  if (bus::has_trailer(payload.data(), payload.size())) return false;
  const auto it = checks().find(channels::message_type(channel));
  return it != checks().end() && it->second(payload);
}

}  // namespace alight::link
