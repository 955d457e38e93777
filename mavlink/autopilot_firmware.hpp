#pragma once
// What an autopilot's firmware version says about the messages it takes: read from its
// AUTOPILOT_VERSION (flight_sw_version: major, minor, patch, FIRMWARE_VERSION_TYPE from the most
// significant byte down; standard.xml). A feature is used only on the versions whose source was
// read to take it; an unknown version gets what every version takes.

#include <cstdint>
#include <string>

#include "mavlink/autopilot_modes.hpp"

namespace alight::mavlink {

struct FirmwareVersion {
  int major = 0, minor = 0, patch = 0;
  uint8_t type = 0;  ///< FIRMWARE_VERSION_TYPE: 0 dev, 64 alpha, 128 beta, 192 rc, 255 official

  static FirmwareVersion from_flight_sw_version(uint32_t v);
  /// "4.5.7", "1.15.0-rc", "4.7.0-dev".
  std::string str() const;
  bool operator==(const FirmwareVersion&) const = default;
};

/// Whether SET_POSITION_TARGET_LOCAL_NED's acceleration, given with a position and a velocity, is
/// taken as their feed-forward:
/// - ArduCopter from 4.1.0 (rc and official builds): ArduCopter/GCS_Mavlink.cpp's
///   set_destination_posvelaccel, from the Guided rework of 2021-05 (Copter 4.1.0-beta6's
///   "Guided mode acceleration control"). Before it the handler dropped the whole message when
///   any acceleration was given ("exit immediately if acceleration provided"): sending one to an
///   older ArduCopter would stop the position stream.
/// - PX4 from 1.12.0: the OFFBOARD rework of 2021-03 publishes the message as the trajectory
///   setpoint, whose acceleration the multicopter position controller adds as feed-forward
///   (src/modules/mavlink/mavlink_receiver.cpp); before it the offboard flight task passed it on
///   as "not supported yet".
bool takes_position_target_accel(Flavour flavour, const FirmwareVersion& version);

}  // namespace alight::mavlink
