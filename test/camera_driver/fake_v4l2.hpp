#pragma once
// A scripted V4L2 device behind the SysIo boundary that answers as the kernel's videobuf2 /
// UVC stack does, so the tests drive the real capture code:
//  - open: ENOENT while unplugged, or a scripted EBUSY / EACCES;
//  - VIDIOC_QUERYCAP with device_caps; VIDIOC_S_FMT snaps to the nearest offered size and
//    substitutes the first offered format for an unknown one (it never fails for that);
//  - VIDIOC_REQBUFS / QUERYBUF / mmap by offset / QBUF / DQBUF with the kernel's rules (EINVAL
//    for a buffer queued twice, EBUSY for REQBUFS while streaming or mapped, EAGAIN from a
//    non-blocking DQBUF with nothing done);
//  - frames: the "sensor" fills the oldest queued buffer with a monotonic timestamp and the next
//    sequence number; with no buffer queued the frame is lost and the sequence number skips,
//    exactly how real drops show up;
//  - unplug: every call on an open descriptor fails with ENODEV, poll reports POLLERR|POLLHUP,
//    the node disappears (open gives ENOENT) until replug().

#include <linux/videodev2.h>

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "camera_driver/sys_io.hpp"

namespace alight::camera::testing {

struct FakeFormat {
  uint32_t fourcc = V4L2_PIX_FMT_GREY;
  std::vector<std::pair<int, int>> sizes = {{640, 480}};
};

class FakeV4l2 final : public SysIo {
 public:
  struct Device {
    std::string path = "/dev/video0";
    std::string card = "Fake Camera";
    bool present = true;
    int open_errno = 0;     ///< scripted failure of open (EBUSY, EACCES)
    int reqbufs_errno = 0;  ///< scripted failure of REQBUFS (EBUSY: another streamer)
    uint32_t device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
    std::vector<FakeFormat> formats = {FakeFormat{}};
    uint32_t max_buffers = 8;
    double fps = 30.0;
    bool has_exposure = true;
    VideoNode node;  ///< sysfs identity reported by video_nodes()
  };

  /// Adds a device; returns its index for the calls below.
  int add_device(Device d);

  // --- the sensor and the cable ---------------------------------------------------------------
  /// The sensor finishes a frame at time t [us monotonic]: fills the oldest queued buffer with
  /// `bytes` (truncated to the buffer), or loses the frame when no buffer is queued. Returns
  /// true if a buffer was filled.
  bool emit_frame(int dev, int64_t t_us, const std::vector<uint8_t>& bytes, bool error = false);
  /// The driver loses n frames without touching a buffer (the sequence number still advances).
  void lose_frames(int dev, uint32_t n) { devices_[dev].sequence += n; }
  void unplug(int dev);
  void replug(int dev);
  /// The next `n` polls report POLLIN although no buffer is done (spurious wake-ups).
  void spurious_wakeups(int dev, int n) { devices_[dev].spurious = n; }
  /// Called when poll would time out, with the device index: the test may emit frames there
  /// (time passing while the driver waits).
  std::function<void(int)> on_idle_poll;

  // --- what the driver did ----------------------------------------------------------------------
  int open_descriptors() const;
  int mapped_buffers() const { return mapped_; }
  bool streaming(int dev) const { return devices_.at(dev).streaming; }
  int queued(int dev) const { return static_cast<int>(devices_.at(dev).queued.size()); }
  std::map<uint32_t, int32_t> controls(int dev) const { return devices_.at(dev).controls; }
  int resets() const { return resets_; }
  uint32_t sequence(int dev) const { return devices_.at(dev).sequence; }

  // --- SysIo
  // --------------------------------------------------------------------------------------
  int open(const std::string& path, int flags) override;
  void close(int fd) override;
  int ioctl(int fd, unsigned long request, void* arg) override;
  void* mmap(size_t length, int fd, off_t offset) override;
  void munmap(void* addr, size_t length) override;
  int poll(int fd, int timeout_ms) override;
  std::vector<VideoNode> video_nodes() override;
  std::vector<UsbCamera> usb_cameras() override;
  std::string usb_reset(int bus, int address) override;

 private:
  struct Buf {
    std::vector<uint8_t> mem;
    bool queued = false, done = false;
    v4l2_buffer info{};
    int maps = 0;
  };
  struct State : Device {
    // Format in force.
    uint32_t fourcc = 0;
    int width = 0, height = 0, stride = 0, sizeimage = 0;
    uint32_t tpf_num = 1, tpf_den = 30;
    std::vector<Buf> bufs;
    std::deque<uint32_t> queued;  ///< indices, oldest first (the driver fills in this order)
    std::deque<uint32_t> done;
    bool streaming = false;
    uint32_t sequence = 0;
    int spurious = 0;
    int owner_fd = -1;  ///< the descriptor that allocated buffers
    std::map<uint32_t, int32_t> controls;
  };
  int device_of(int fd) const;
  void apply_format(State& s, v4l2_pix_format& pix);
  void free_buffers(State& s);

  std::vector<State> devices_;
  std::deque<Buf> graveyard_;  ///< buffers of a vanished device instance, still mapped
  std::map<int, int> fds_;     ///< fd -> device index (or -1 once its device vanished)
  std::map<int, bool> fd_dead_;
  int next_fd_ = 10;
  int mapped_ = 0;
  int resets_ = 0;
};

}  // namespace alight::camera::testing
