// The real system-call boundary: V4L2 through open/ioctl/mmap/poll, device identity through
// sysfs, enumeration and reset through libusb-1.0. Nothing here decides anything; the capture
// state machine (v4l2_capture.cpp) does.

#include <fcntl.h>
#include <libusb.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <fstream>

#include "camera_driver/sys_io.hpp"

namespace alight::camera {

namespace {
namespace fs = std::filesystem;

std::string read_line(const fs::path& p) {
  std::ifstream in(p);
  std::string s;
  std::getline(in, s);
  return s;
}

int read_int(const fs::path& p, int base) {
  const std::string s = read_line(p);
  if (s.empty()) return -1;
  try {
    return std::stoi(s, nullptr, base);
  } catch (const std::exception&) {
    return -1;
  }
}

// Walks up from a video node's sysfs device to the USB device that carries it (the first
// ancestor with an idVendor file).
void fill_usb_identity(const fs::path& device_link, VideoNode& node) {
  std::error_code ec;
  fs::path p = fs::canonical(device_link, ec);
  if (ec) return;
  for (; !p.empty() && p != p.root_path(); p = p.parent_path()) {
    if (!fs::exists(p / "idVendor", ec)) continue;
    node.is_usb = true;
    node.vendor_id = static_cast<uint16_t>(read_int(p / "idVendor", 16));
    node.product_id = static_cast<uint16_t>(read_int(p / "idProduct", 16));
    node.serial = read_line(p / "serial");
    node.usb_bus = read_int(p / "busnum", 10);
    node.usb_address = read_int(p / "devnum", 10);
    return;
  }
}

// Point Grey (FLIR) USB 2 cameras such as the paper's Firefly MV are not UVC devices: they are
// listed so the user learns why no V4L2 node appears for them.
constexpr uint16_t kPointGreyVendor = 0x1e10;

class LinuxSysIo final : public SysIo {
 public:
  LinuxSysIo() {
    if (libusb_init(&usb_) != 0) usb_ = nullptr;
  }
  ~LinuxSysIo() override {
    if (usb_) libusb_exit(usb_);
  }

  int open(const std::string& path, int flags) override {
    const int fd = ::open(path.c_str(), flags);
    return fd >= 0 ? fd : -errno;
  }
  void close(int fd) override { ::close(fd); }
  int ioctl(int fd, unsigned long request, void* arg) override {
    int r;
    do {
      r = ::ioctl(fd, request, arg);
    } while (r < 0 && errno == EINTR);
    return r >= 0 ? r : -errno;
  }
  void* mmap(size_t length, int fd, off_t offset) override {
    void* p = ::mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, offset);
    return p == MAP_FAILED ? nullptr : p;
  }
  void munmap(void* addr, size_t length) override { ::munmap(addr, length); }
  int poll(int fd, int timeout_ms) override {
    pollfd p{fd, POLLIN, 0};
    int r;
    do {
      r = ::poll(&p, 1, timeout_ms);
    } while (r < 0 && errno == EINTR);
    if (r < 0) return -errno;
    return r == 0 ? 0 : p.revents;
  }

  std::vector<VideoNode> video_nodes() override {
    std::vector<VideoNode> out;
    std::error_code ec;
    const fs::path cls("/sys/class/video4linux");
    if (!fs::exists(cls, ec)) return out;
    for (const auto& entry : fs::directory_iterator(cls, ec)) {
      const std::string base = entry.path().filename().string();
      if (base.rfind("video", 0) != 0) continue;
      VideoNode node;
      node.path = "/dev/" + base;
      node.name = read_line(entry.path() / "name");
      fill_usb_identity(entry.path() / "device", node);
      out.push_back(node);
    }
    std::sort(out.begin(), out.end(), [](const VideoNode& a, const VideoNode& b) {
      return a.path.size() != b.path.size() ? a.path.size() < b.path.size() : a.path < b.path;
    });
    return out;
  }

  std::vector<UsbCamera> usb_cameras() override {
    std::vector<UsbCamera> out;
    if (!usb_) return out;
    libusb_device** list = nullptr;
    const ssize_t n = libusb_get_device_list(usb_, &list);
    for (ssize_t i = 0; i < n; ++i) {
      libusb_device* dev = list[i];
      libusb_device_descriptor desc{};
      if (libusb_get_device_descriptor(dev, &desc) != 0) continue;
      if (!has_video_interface(dev) && desc.idVendor != kPointGreyVendor) continue;
      UsbCamera cam;
      cam.vendor_id = desc.idVendor;
      cam.product_id = desc.idProduct;
      cam.bus = libusb_get_bus_number(dev);
      cam.address = libusb_get_device_address(dev);
      libusb_device_handle* h = nullptr;
      if (libusb_open(dev, &h) == 0) {  // strings need the device opened (and permission)
        cam.serial = descriptor_string(h, desc.iSerialNumber);
        cam.product = descriptor_string(h, desc.iProduct);
        libusb_close(h);
      }
      out.push_back(cam);
    }
    if (list) libusb_free_device_list(list, 1);
    return out;
  }

  std::string usb_reset(int bus, int address) override {
    if (!usb_) return "libusb could not be initialised";
    libusb_device** list = nullptr;
    const ssize_t n = libusb_get_device_list(usb_, &list);
    std::string result =
        "no USB device at bus " + std::to_string(bus) + " address " + std::to_string(address);
    for (ssize_t i = 0; i < n; ++i) {
      libusb_device* dev = list[i];
      if (libusb_get_bus_number(dev) != bus || libusb_get_device_address(dev) != address) continue;
      libusb_device_handle* h = nullptr;
      int r = libusb_open(dev, &h);
      if (r == 0) {
        r = libusb_reset_device(h);
        libusb_close(h);
      }
      // LIBUSB_ERROR_NOT_FOUND after a reset means the device re-enumerated: that is success.
      result = (r == 0 || r == LIBUSB_ERROR_NOT_FOUND) ? "" : libusb_strerror(r);
      break;
    }
    if (list) libusb_free_device_list(list, 1);
    return result;
  }

 private:
  static bool has_video_interface(libusb_device* dev) {
    libusb_config_descriptor* cfg = nullptr;
    if (libusb_get_active_config_descriptor(dev, &cfg) != 0 &&
        libusb_get_config_descriptor(dev, 0, &cfg) != 0)
      return false;
    bool video = false;
    for (int i = 0; i < cfg->bNumInterfaces && !video; ++i)
      for (int a = 0; a < cfg->interface[i].num_altsetting && !video; ++a)
        video = cfg->interface[i].altsetting[a].bInterfaceClass == LIBUSB_CLASS_VIDEO;
    libusb_free_config_descriptor(cfg);
    return video;
  }
  static std::string descriptor_string(libusb_device_handle* h, uint8_t index) {
    if (index == 0) return "";
    unsigned char buf[256];
    const int r = libusb_get_string_descriptor_ascii(h, index, buf, sizeof(buf));
    return r > 0 ? std::string(reinterpret_cast<char*>(buf), static_cast<size_t>(r)) : "";
  }

  libusb_context* usb_ = nullptr;
};
}  // namespace

std::unique_ptr<SysIo> make_linux_sys_io() { return std::make_unique<LinuxSysIo>(); }

}  // namespace alight::camera
