#include "camera_driver/device_list.hpp"

#include <fcntl.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <sstream>

#include "camera_driver/device_select.hpp"
#include "camera_driver/v4l2_capture.hpp"

namespace alight::camera {

namespace {
void list_modes(SysIo& io, const std::string& path, std::ostringstream& out) {
  const int fd = io.open(path, O_RDWR | O_NONBLOCK);
  if (fd < 0) {
    out << "      (cannot open: " << std::strerror(-fd) << ")\n";
    return;
  }
  const auto modes = enumerate_modes(io, fd);
  io.close(fd);
  if (modes.empty()) out << "      (no capture formats: metadata or output node)\n";
  for (const auto& m : modes) {
    out << "      " << fourcc_text(m.fourcc) << " ";
    if (m.width > 0) {
      out << m.width << "x" << m.height;
    } else {
      out << m.size_range;
    }
    if (!m.fps.empty()) {
      out << " @";
      for (size_t i = 0; i < m.fps.size(); ++i) {
        char buf[32];
        std::snprintf(buf, sizeof(buf), "%s%g", i ? ", " : " ", m.fps[i]);
        out << buf;
      }
      out << " fps";
    }
    out << "  (" << m.description << ")\n";
  }
}
}  // namespace

std::string list_cameras(SysIo& io) {
  std::ostringstream out;
  const auto cams = io.usb_cameras();
  const auto nodes = io.video_nodes();
  if (cams.empty()) out << "no USB cameras found\n";
  for (const auto& c : cams) {
    // libusb needs permission to read the serial string; sysfs does not.
    std::string serial = c.serial;
    for (const auto& n : nodes)
      if (serial.empty() && n.is_usb && n.usb_bus == c.bus && n.usb_address == c.address)
        serial = n.serial;
    out << usb_id_text(c.vendor_id, c.product_id, serial);
    if (!c.product.empty()) out << "  " << c.product;
    out << "  (bus " << c.bus << " address " << c.address << ")\n";
    bool any = false;
    for (const auto& n : nodes) {
      if (!n.is_usb || n.usb_bus != c.bus || n.usb_address != c.address) continue;
      any = true;
      out << "    " << n.path << "  " << n.name << "\n";
      list_modes(io, n.path, out);
    }
    if (!any)
      out << "    no V4L2 node (not a UVC camera, or its driver is not loaded; Point Grey USB 2 "
             "cameras such as the Firefly MV need libdc1394 / FlyCapture, not V4L2)\n";
  }
  bool header = false;
  for (const auto& n : nodes) {
    if (n.is_usb) continue;
    if (!header) out << "other V4L2 nodes:\n";
    header = true;
    out << "    " << n.path << "  " << n.name << "\n";
    list_modes(io, n.path, out);
  }
  return out.str();
}

}  // namespace alight::camera
