#pragma once
// The autopilots' flight modes as HEARTBEAT.custom_mode encodes them, and how MAV_CMD_DO_SET_MODE
// asks for one (mavlink.io/en/messages/common.html#MAV_CMD_DO_SET_MODE: param1 base mode with
// MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, param2 custom mode, param3 custom sub mode).
//
// PX4 (src/modules/commander/px4_custom_mode.h): custom_mode = main_mode << 16 | sub_mode << 24;
// main modes MANUAL 1, ALTCTL 2, POSCTL 3, AUTO 4, ACRO 5, OFFBOARD 6, STABILIZED 7, RATTITUDE 8;
// AUTO sub modes READY 1, TAKEOFF 2, LOITER 3, MISSION 4, RTL 5, LAND 6, FOLLOW_TARGET 8,
// PRECLAND 9, VTOL_TAKEOFF 10, EXTERNAL1..8 11..18. ArduCopter (ArduCopter/mode.h,
// Mode::Number): custom_mode is the mode number, 0 STABILIZE to 28 TURTLE (8, 10 and 12 unused).
//
// alight flies in OFFBOARD on PX4, and in GUIDED_NOGPS (attitude setpoints) or GUIDED (position
// setpoints) on ArduPilot.

#include <cstdint>
#include <string>

namespace alight::mavlink {

enum class Flavour { kPx4, kArdupilot };

/// How the setpoints go to the autopilot: attitude + normalised thrust (SET_ATTITUDE_TARGET) or a
/// local position (SET_POSITION_TARGET_LOCAL_NED) for the autopilot's own position controller.
enum class ControlMode { kAttitude, kPosition };

namespace px4_mode {
inline constexpr uint8_t kManual = 1, kAltctl = 2, kPosctl = 3, kAuto = 4, kAcro = 5, kOffboard = 6,
                         kStabilized = 7, kRattitude = 8, kSimple = 9, kTermination = 10,
                         kAltitudeCruise = 11;
namespace auto_sub {
inline constexpr uint8_t kReady = 1, kTakeoff = 2, kLoiter = 3, kMission = 4, kRtl = 5, kLand = 6,
                         kFollowTarget = 8, kPrecland = 9, kVtolTakeoff = 10, kExternal1 = 11,
                         kExternal8 = 18;
}
/// HEARTBEAT.custom_mode of a PX4 main / sub mode.
constexpr uint32_t custom_mode(uint8_t main_mode, uint8_t sub_mode = 0) {
  return (uint32_t{main_mode} << 16) | (uint32_t{sub_mode} << 24);
}
constexpr uint8_t main_mode(uint32_t custom) { return static_cast<uint8_t>(custom >> 16); }
constexpr uint8_t sub_mode(uint32_t custom) { return static_cast<uint8_t>(custom >> 24); }
}  // namespace px4_mode

namespace copter_mode {
inline constexpr uint32_t kStabilize = 0, kAcro = 1, kAltHold = 2, kAuto = 3, kGuided = 4,
                          kLoiter = 5, kRtl = 6, kCircle = 7, kLand = 9, kDrift = 11, kSport = 13,
                          kFlip = 14, kAutotune = 15, kPosHold = 16, kBrake = 17, kThrow = 18,
                          kAvoidAdsb = 19, kGuidedNoGps = 20, kSmartRtl = 21, kFlowHold = 22,
                          kFollow = 23, kZigZag = 24, kSystemId = 25, kAutorotate = 26,
                          kAutoRtl = 27, kTurtle = 28;
}

/// The mode's name as the autopilot's ground stations show it ("OFFBOARD", "AUTO.LAND",
/// "GUIDED_NOGPS"); "MODE(n)" for one alight does not know.
std::string mode_name(Flavour flavour, uint32_t custom_mode);

/// The custom mode alight flies in with this autopilot and control mode.
uint32_t fly_custom_mode(Flavour flavour, ControlMode control);
/// Whether `custom_mode` is that mode.
bool is_fly_mode(Flavour flavour, ControlMode control, uint32_t custom_mode);
/// The autopilot's own landing mode (PX4 AUTO.LAND, ArduCopter LAND).
uint32_t land_custom_mode(Flavour flavour);
bool is_land_mode(Flavour flavour, uint32_t custom_mode);

/// DO_SET_MODE's param2 and param3 for a custom mode.
struct SetModeParams {
  float param1 = 0, param2 = 0, param3 = 0;
};
SetModeParams set_mode_params(Flavour flavour, uint32_t custom_mode);

/// ARM_DISARM's param2 that forces a disarm in the air (both autopilots: 21196).
inline constexpr float kForceDisarmMagic = 21196.0f;

}  // namespace alight::mavlink
