#pragma once
// The system-call boundary of the camera driver: every call that touches the kernel's V4L2
// interface, sysfs or libusb goes through SysIo, so the capture state machine above it runs
// unchanged against a real camera (LinuxSysIo) or against a scripted device in the tests.
//
// The calls keep the kernel's conventions on purpose (negative return and errno-style codes,
// the <linux/videodev2.h> structs passed to ioctl) so that the fake has to behave as the kernel
// does and the capture code cannot rely on anything a real driver would not give it.

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace alight::camera {

/// A V4L2 device node and, when it hangs off a USB device, that device's identity (from sysfs).
struct VideoNode {
  std::string path;  ///< /dev/videoN
  std::string name;  ///< sysfs name of the node (driver's card name)
  bool is_usb = false;
  uint16_t vendor_id = 0;   ///< USB idVendor
  uint16_t product_id = 0;  ///< USB idProduct
  std::string serial;       ///< USB iSerial string ("" when the device has none)
  int usb_bus = -1;         ///< USB bus number (for libusb reset)
  int usb_address = -1;     ///< USB device address on that bus
};

/// A USB device with a video-class interface, as libusb enumerates it.
struct UsbCamera {
  uint16_t vendor_id = 0;
  uint16_t product_id = 0;
  std::string serial;   ///< "" when unreadable (e.g. no permission) or absent
  std::string product;  ///< product string, "" when unreadable
  int bus = -1;
  int address = -1;
};

class SysIo {
 public:
  virtual ~SysIo() = default;

  /// open(2): a file descriptor, or -errno (ENOENT, EBUSY, EACCES, ...).
  virtual int open(const std::string& path, int flags) = 0;
  virtual void close(int fd) = 0;
  /// ioctl(2): 0 (or the ioctl's non-negative result), or -errno (EAGAIN, ENODEV, EINVAL, ...).
  /// Interrupted calls (EINTR) are retried inside, never returned.
  virtual int ioctl(int fd, unsigned long request, void* arg) = 0;
  /// mmap(2) of a device buffer with PROT_READ|PROT_WRITE, MAP_SHARED: the mapping, or nullptr.
  virtual void* mmap(size_t length, int fd, off_t offset) = 0;
  virtual void munmap(void* addr, size_t length) = 0;
  /// poll(2) for POLLIN on one descriptor: the revents bits (0 on timeout), or -errno.
  virtual int poll(int fd, int timeout_ms) = 0;

  /// Every /dev/video* node with its USB parent's identity (sysfs).
  virtual std::vector<VideoNode> video_nodes() = 0;
  /// libusb: devices with a video-class interface.
  virtual std::vector<UsbCamera> usb_cameras() = 0;
  /// libusb_reset_device on the device at bus / address: "" on success, else the reason.
  virtual std::string usb_reset(int bus, int address) = 0;
};

/// The real kernel and libusb.
std::unique_ptr<SysIo> make_linux_sys_io();

}  // namespace alight::camera
