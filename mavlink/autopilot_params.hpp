#pragma once
// The autopilot parameters alight-mavlink's behaviour relies on, per autopilot and control mode,
// as the autopilots define them (ArduPilot 4.7.0-dev 90700977c5: ArduCopter/Parameters.cpp,
// libraries/GCS_MAVLink/GCS.cpp, libraries/AC_AttitudeControl/AC_AttitudeControl.cpp,
// libraries/AP_VisualOdom/AP_VisualOdom.cpp; PX4 release/1.18 83c4f4e580:
// src/modules/commander/commander_params.yaml, src/modules/mc_pos_control/
// multicopter_position_control_params.yaml, src/modules/ekf2/params_external_vision.yaml). The
// bridge reads each at link-up (PARAM_REQUEST_READ) and reports the ones missing or set
// otherwise; config/autopilot/*.parm and *.params set them all. Pure.

#include <functional>
#include <string>
#include <vector>

#include "mavlink/autopilot_modes.hpp"
#include "mavlink/messages.hpp"

namespace alight::mavlink {

struct ParamExpectation {
  std::string name;  ///< as the autopilot names it (16 characters at most)
  std::function<bool(double)> ok;
  std::string want;  ///< what ok() accepts, for the report ("5 (Land)", "bit 3 set")
  std::string why;   ///< what goes wrong otherwise
};

struct ParamContext {
  Flavour flavour = Flavour::kPx4;
  ControlMode control = ControlMode::kAttitude;
  int own_sysid = 1;
  bool mocap = true;          ///< motion capture goes to the autopilot's estimator
  double hover_thrust = 0.5;  ///< the bridge's hover_thrust
};

/// The parameters to check, in the order they are read.
std::vector<ParamExpectation> expected_params(const ParamContext& c);

/// PARAM_VALUE's number: ArduPilot sends every type as a float value; PX4 sends INT32
/// parameters bytewise in the float's bits (MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE,
/// src/modules/mavlink/mavlink_parameters.cpp).
double param_number(Flavour flavour, const ParamValue& m);

namespace mav_param_type {
inline constexpr uint8_t kInt32 = 6, kReal32 = 9;
}

}  // namespace alight::mavlink
