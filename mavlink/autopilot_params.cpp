#include "mavlink/autopilot_params.hpp"

#include <cmath>
#include <cstring>

namespace alight::mavlink {

namespace {
bool bit_set(double v, int bit) {
  return std::isfinite(v) && v >= 0 && (static_cast<long>(v) >> bit & 1) != 0;
}
}  // namespace

std::vector<ParamExpectation> expected_params(const ParamContext& c) {
  std::vector<ParamExpectation> e;
  if (c.flavour == Flavour::kArdupilot) {
    const int sysid = c.own_sysid;
    e.push_back({"MAV_GCS_SYSID", [sysid](double v) { return std::lround(v) == sysid; },
                 std::to_string(sysid) + " (alight-mavlink's own_sysid)",
                 "the GCS failsafe (FS_GCS_ENABLE) watches another system's heartbeat, so the "
                 "vehicle is not landed when alight-mavlink dies"});
    e.push_back({"FS_GCS_ENABLE", [](double v) { return std::lround(v) == 5; }, "5 (Land)",
                 "ArduCopter has no offboard-loss failsafe: without it a vehicle whose "
                 "alight-mavlink died keeps hovering in GUIDED"});
    if (c.control == ControlMode::kAttitude) {
      e.push_back({"GUID_OPTIONS", [](double v) { return bit_set(v, 3); }, "bit 3 set (value 8)",
                   "SET_ATTITUDE_TARGET thrust is read as a climb rate, not as thrust"});
      e.push_back({"ATC_ANGLE_BOOST", [](double v) { return std::lround(v) == 0; }, "0",
                   "ArduCopter boosts alight's thrust by 1 / cos(tilt) a second time"});
    }
    if (c.mocap)
      e.push_back({"VISO_TYPE", [](double v) { return std::lround(v) == 1; }, "1 (MAVLink)",
                   "EKF3 does not take motion capture (ODOMETRY, ATT_POS_MOCAP)"});
  } else {
    e.push_back({"COM_OBL_RC_ACT", [](double v) { return std::lround(v) == 4; }, "4 (Land)",
                 "without a pilot's RC, Position / Altitude / Stabilized fall back to "
                 "NAV_RCL_ACT (Return by default) when alight goes silent"});
    e.push_back({"COM_OF_LOSS_T", [](double v) { return v > 0 && v <= 1.0; }, "<= 1 s",
                 "the offboard-loss failsafe waits longer than a fall lasts"});
    if (c.mocap)
      e.push_back({"EKF2_EV_CTRL", [](double v) { return v >= 1; }, "non-zero (15)",
                   "EKF2 does not fuse motion capture (ODOMETRY)"});
    if (c.control == ControlMode::kAttitude) {
      const double h = c.hover_thrust;
      e.push_back({"MPC_THR_HOVER", [h](double v) { return std::abs(v - h) <= 0.05; },
                   "within 0.05 of hover_thrust " + std::to_string(h),
                   "alight's thrust is normalised with another hover thrust than PX4's"});
    }
  }
  return e;
}

double param_number(Flavour flavour, const ParamValue& m) {
  if (flavour == Flavour::kPx4 && m.param_type == mav_param_type::kInt32) {
    int32_t i;
    std::memcpy(&i, &m.param_value, sizeof i);
    return i;
  }
  return m.param_value;
}

}  // namespace alight::mavlink
