#pragma once
// `alight-camera --list`: USB cameras (libusb), the V4L2 nodes each one carries (sysfs), and
// every mode those nodes offer (VIDIOC_ENUM_FMT / FRAMESIZES / FRAMEINTERVALS).

#include <string>

#include "camera_driver/sys_io.hpp"

namespace alight::camera {

/// The listing as text; "no USB cameras found" (plus any non-USB V4L2 nodes) when there is none.
std::string list_cameras(SysIo& io);

}  // namespace alight::camera
