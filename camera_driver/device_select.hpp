#pragma once
// Which /dev/video node a configured device names. A path names itself; "usb:VVVV:PPPP[:SERIAL]"
// names a USB camera by identity, which survives re-plugging into another port (the node
// number and bus address do not). A UVC camera usually has two nodes (capture and metadata):
// every node of the matching device is a candidate, and the capture code keeps the one that
// can stream video.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "camera_driver/sys_io.hpp"

namespace alight::camera {

struct DeviceSpec {
  std::string path;  ///< set for a path spec
  bool usb = false;  ///< true for a usb:VVVV:PPPP[:SERIAL] spec
  uint16_t vendor_id = 0;
  uint16_t product_id = 0;
  std::string serial;        ///< "" matches any serial
  std::string text() const;  ///< the spec as written
};

/// Parses "/dev/videoN" (any absolute path) or "usb:VVVV:PPPP[:SERIAL]" (hex ids). nullopt and
/// *error (saying what is expected) for anything else.
std::optional<DeviceSpec> parse_device_spec(const std::string& text, std::string* error);

struct Candidates {
  std::vector<VideoNode> nodes;  ///< in node order; empty when nothing matched
  std::string error;             ///< why there is no choice (not found, or ambiguous)
  bool ambiguous = false;        ///< several cameras match (else: nothing matched)
};

/// The video nodes a spec may mean. Two distinct USB devices matching a spec without serial is
/// an error (which camera is which would depend on plug order), naming both serials.
Candidates candidate_nodes(const DeviceSpec& spec, const std::vector<VideoNode>& nodes);

std::string usb_id_text(uint16_t vendor_id, uint16_t product_id, const std::string& serial);

}  // namespace alight::camera
