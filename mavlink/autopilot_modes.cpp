#include "mavlink/autopilot_modes.hpp"

#include <iterator>

#include "mavlink/messages.hpp"

namespace alight::mavlink {

namespace {

std::string px4_name(uint32_t custom) {
  using namespace px4_mode;
  switch (main_mode(custom)) {
    case kManual:
      return "MANUAL";
    case kAltctl:
      return "ALTCTL";
    case kPosctl:
      return "POSCTL";
    case kAcro:
      return "ACRO";
    case kOffboard:
      return "OFFBOARD";
    case kStabilized:
      return "STABILIZED";
    case kRattitude:
      return "RATTITUDE";
    case kTermination:
      return "TERMINATION";
    case kAltitudeCruise:
      return "ALTITUDE_CRUISE";
    case kAuto:
      switch (sub_mode(custom)) {
        case auto_sub::kReady:
          return "AUTO.READY";
        case auto_sub::kTakeoff:
          return "AUTO.TAKEOFF";
        case auto_sub::kLoiter:
          return "AUTO.LOITER";
        case auto_sub::kMission:
          return "AUTO.MISSION";
        case auto_sub::kRtl:
          return "AUTO.RTL";
        case auto_sub::kLand:
          return "AUTO.LAND";
        case auto_sub::kFollowTarget:
          return "AUTO.FOLLOW_TARGET";
        case auto_sub::kPrecland:
          return "AUTO.PRECLAND";
        case auto_sub::kVtolTakeoff:
          return "AUTO.VTOL_TAKEOFF";
        default:
          if (sub_mode(custom) >= auto_sub::kExternal1 && sub_mode(custom) <= auto_sub::kExternal8)
            return "EXTERNAL" + std::to_string(sub_mode(custom) - auto_sub::kExternal1 + 1);
          return "AUTO(" + std::to_string(sub_mode(custom)) + ")";
      }
    default:
      return "MODE(" + std::to_string(custom) + ")";
  }
}

std::string copter_name(uint32_t custom) {
  // ArduCopter/mode.h (Mode::Number) and each mode's name() (ArduCopter/mode.h); SMART_RTL and
  // AUTO_RTL are spelt with an underscore, as ground stations show them.
  static constexpr const char* kNames[] = {
      "STABILIZE", "ACRO",       "ALT_HOLD",     "AUTO",      "GUIDED",   "LOITER",
      "RTL",       "CIRCLE",     nullptr,        "LAND",      nullptr,    "DRIFT",
      nullptr,     "SPORT",      "FLIP",         "AUTOTUNE",  "POSHOLD",  "BRAKE",
      "THROW",     "AVOID_ADSB", "GUIDED_NOGPS", "SMART_RTL", "FLOWHOLD", "FOLLOW",
      "ZIGZAG",    "SYSTEMID",   "AUTOROTATE",   "AUTO_RTL",  "TURTLE"};
  if (custom < std::size(kNames) && kNames[custom]) return kNames[custom];
  return "MODE(" + std::to_string(custom) + ")";
}

}  // namespace

std::string mode_name(Flavour flavour, uint32_t custom_mode) {
  return flavour == Flavour::kPx4 ? px4_name(custom_mode) : copter_name(custom_mode);
}

uint32_t fly_custom_mode(Flavour flavour, ControlMode control) {
  if (flavour == Flavour::kPx4) return px4_mode::custom_mode(px4_mode::kOffboard);
  return control == ControlMode::kAttitude ? copter_mode::kGuidedNoGps : copter_mode::kGuided;
}

bool is_fly_mode(Flavour flavour, ControlMode control, uint32_t custom_mode) {
  // PX4 leaves the sub mode byte of OFFBOARD at 0, but only the main mode names the mode.
  if (flavour == Flavour::kPx4) return px4_mode::main_mode(custom_mode) == px4_mode::kOffboard;
  return custom_mode == fly_custom_mode(flavour, control);
}

uint32_t land_custom_mode(Flavour flavour) {
  if (flavour == Flavour::kPx4)
    return px4_mode::custom_mode(px4_mode::kAuto, px4_mode::auto_sub::kLand);
  return copter_mode::kLand;
}

bool is_land_mode(Flavour flavour, uint32_t custom_mode) {
  if (flavour == Flavour::kArdupilot) return custom_mode == copter_mode::kLand;
  return px4_mode::main_mode(custom_mode) == px4_mode::kAuto &&
         (px4_mode::sub_mode(custom_mode) == px4_mode::auto_sub::kLand ||
          px4_mode::sub_mode(custom_mode) == px4_mode::auto_sub::kPrecland);
}

SetModeParams set_mode_params(Flavour flavour, uint32_t custom_mode) {
  SetModeParams p;
  p.param1 = mav_mode_flag::kCustomModeEnabled;
  if (flavour == Flavour::kPx4) {
    p.param2 = px4_mode::main_mode(custom_mode);
    p.param3 = px4_mode::sub_mode(custom_mode);
  } else {
    p.param2 = static_cast<float>(custom_mode);
  }
  return p;
}

}  // namespace alight::mavlink
