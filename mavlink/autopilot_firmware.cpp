#include "mavlink/autopilot_firmware.hpp"

#include <tuple>

#include "mavlink/messages.hpp"

namespace alight::mavlink {

FirmwareVersion FirmwareVersion::from_flight_sw_version(uint32_t v) {
  FirmwareVersion f;
  f.major = static_cast<int>(v >> 24);
  f.minor = static_cast<int>((v >> 16) & 0xff);
  f.patch = static_cast<int>((v >> 8) & 0xff);
  f.type = static_cast<uint8_t>(v & 0xff);
  return f;
}

std::string FirmwareVersion::str() const {
  std::string s = std::to_string(major) + "." + std::to_string(minor) + "." + std::to_string(patch);
  using namespace firmware_version_type;
  if (type == kOfficial) return s;
  if (type >= kRc) return s + "-rc";
  if (type >= kBeta) return s + "-beta";
  if (type >= kAlpha) return s + "-alpha";
  return s + "-dev";
}

bool takes_position_target_accel(Flavour flavour, const FirmwareVersion& v) {
  const auto mmp = std::tie(v.major, v.minor, v.patch);
  if (flavour == Flavour::kArdupilot) {
    // 4.1.0's dev and beta builds are older than the rework or not known to hold it.
    if (mmp == std::make_tuple(4, 1, 0)) return v.type >= firmware_version_type::kRc;
    return mmp > std::make_tuple(4, 1, 0);
  }
  return mmp >= std::make_tuple(1, 12, 0);
}

}  // namespace alight::mavlink
