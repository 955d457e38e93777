#include "camera_driver/device_select.hpp"

#include <cstdio>
#include <set>
#include <utility>

namespace alight::camera {

std::string usb_id_text(uint16_t vendor_id, uint16_t product_id, const std::string& serial) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%04x:%04x", vendor_id, product_id);
  return serial.empty() ? std::string(buf) : std::string(buf) + ":" + serial;
}

std::string DeviceSpec::text() const {
  return usb ? "usb:" + usb_id_text(vendor_id, product_id, serial) : path;
}

namespace {
bool parse_hex16(const std::string& s, uint16_t& out) {
  if (s.empty() || s.size() > 4) return false;
  unsigned v = 0;
  for (char c : s) {
    v <<= 4;
    if (c >= '0' && c <= '9')
      v |= static_cast<unsigned>(c - '0');
    else if (c >= 'a' && c <= 'f')
      v |= static_cast<unsigned>(c - 'a' + 10);
    else if (c >= 'A' && c <= 'F')
      v |= static_cast<unsigned>(c - 'A' + 10);
    else
      return false;
  }
  out = static_cast<uint16_t>(v);
  return true;
}
}  // namespace

std::optional<DeviceSpec> parse_device_spec(const std::string& text, std::string* error) {
  DeviceSpec spec;
  if (!text.empty() && text.front() == '/') {
    spec.path = text;
    return spec;
  }
  const std::string kUsb = "usb:";
  const std::string expected =
      "expected a device path (/dev/video0) or usb:VENDOR:PRODUCT[:SERIAL] with hex ids "
      "(usb:1e10:2004)";
  if (text.rfind(kUsb, 0) != 0) {
    if (error) *error = expected;
    return std::nullopt;
  }
  const std::string rest = text.substr(kUsb.size());
  const size_t c1 = rest.find(':');
  const size_t c2 = c1 == std::string::npos ? std::string::npos : rest.find(':', c1 + 1);
  const std::string vendor = rest.substr(0, c1);
  const std::string product =
      c1 == std::string::npos
          ? ""
          : rest.substr(c1 + 1, c2 == std::string::npos ? std::string::npos : c2 - c1 - 1);
  if (!parse_hex16(vendor, spec.vendor_id) || !parse_hex16(product, spec.product_id)) {
    if (error) *error = expected;
    return std::nullopt;
  }
  spec.usb = true;
  if (c2 != std::string::npos) spec.serial = rest.substr(c2 + 1);
  return spec;
}

Candidates candidate_nodes(const DeviceSpec& spec, const std::vector<VideoNode>& nodes) {
  Candidates out;
  if (!spec.usb) {
    VideoNode n;
    n.path = spec.path;
    for (const auto& known : nodes)
      if (known.path == spec.path) n = known;  // keeps its USB identity for a later reset
    out.nodes.push_back(n);
    return out;
  }
  std::set<std::pair<int, int>> devices;  // (bus, address) of every matching USB device
  std::vector<std::string> serials;
  for (const auto& n : nodes) {
    if (!n.is_usb || n.vendor_id != spec.vendor_id || n.product_id != spec.product_id) continue;
    if (!spec.serial.empty() && n.serial != spec.serial) continue;
    if (devices.insert({n.usb_bus, n.usb_address}).second)
      serials.push_back(n.serial.empty() ? "<no serial>" : n.serial);
    out.nodes.push_back(n);
  }
  if (out.nodes.empty()) {
    out.error = "no V4L2 device for USB camera " + spec.text() +
                " (is it plugged in? see alight-camera --list)";
  } else if (devices.size() > 1) {
    out.error = std::to_string(devices.size()) + " USB cameras match " + spec.text() + " (serials:";
    for (const auto& s : serials) out.error += " " + s;
    out.error += "); add the serial to the device spec";
    out.nodes.clear();
    out.ambiguous = true;
  }
  return out;
}

}  // namespace alight::camera
