#include "fake_v4l2.hpp"

#include <poll.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

namespace alight::camera::testing {

namespace {
constexpr size_t kPage = 4096;
size_t page_round(size_t n) { return (n + kPage - 1) / kPage * kPage; }
}  // namespace

int FakeV4l2::add_device(Device d) {
  State s;
  static_cast<Device&>(s) = d;
  if (s.node.path.empty()) s.node.path = d.path;
  s.tpf_den = static_cast<uint32_t>(d.fps);
  devices_.push_back(std::move(s));
  return static_cast<int>(devices_.size()) - 1;
}

int FakeV4l2::device_of(int fd) const {
  auto it = fds_.find(fd);
  return it == fds_.end() ? -1 : it->second;
}

int FakeV4l2::open_descriptors() const { return static_cast<int>(fds_.size()); }

int FakeV4l2::open(const std::string& path, int /*flags*/) {
  for (size_t i = 0; i < devices_.size(); ++i) {
    State& s = devices_[i];
    if (s.path != path) continue;
    if (!s.present) return -ENOENT;
    if (s.open_errno) return -s.open_errno;
    const int fd = next_fd_++;
    fds_[fd] = static_cast<int>(i);
    fd_dead_[fd] = false;
    return fd;
  }
  return -ENOENT;
}

void FakeV4l2::close(int fd) {
  const int d = device_of(fd);
  if (d < 0) std::abort();  // closing a descriptor twice is a driver bug the tests must catch
  State& s = devices_[d];
  if (!fd_dead_[fd] && s.owner_fd == fd) {
    // Closing the owner stops streaming and frees unmapped buffers, as vb2 does.
    s.streaming = false;
    s.queued.clear();
    s.done.clear();
    free_buffers(s);
  }
  fds_.erase(fd);
  fd_dead_.erase(fd);
}

void FakeV4l2::free_buffers(State& s) {
  for (const auto& b : s.bufs)
    if (b.maps > 0) return;  // the kernel keeps mapped memory alive; so does the fake
  s.bufs.clear();
  s.owner_fd = -1;
}

void FakeV4l2::apply_format(State& s, v4l2_pix_format& pix) {
  const FakeFormat* f = &s.formats.front();  // S_FMT substitutes, it does not refuse
  for (const auto& cand : s.formats)
    if (cand.fourcc == pix.pixelformat) f = &cand;
  std::pair<int, int> best = f->sizes.front();
  long best_d = -1;
  for (const auto& sz : f->sizes) {
    const long d = std::labs(static_cast<long>(sz.first) - static_cast<long>(pix.width)) +
                   std::labs(static_cast<long>(sz.second) - static_cast<long>(pix.height));
    if (best_d < 0 || d < best_d) best = sz, best_d = d;
  }
  pix.pixelformat = f->fourcc;
  pix.width = static_cast<uint32_t>(best.first);
  pix.height = static_cast<uint32_t>(best.second);
  pix.field = V4L2_FIELD_NONE;
  const int bpp = f->fourcc == V4L2_PIX_FMT_YUYV ? 2 : 1;
  pix.bytesperline = f->fourcc == V4L2_PIX_FMT_MJPEG ? 0 : static_cast<uint32_t>(best.first * bpp);
  pix.sizeimage = static_cast<uint32_t>(best.first * best.second * bpp);
  s.fourcc = pix.pixelformat;
  s.width = best.first;
  s.height = best.second;
  s.stride = static_cast<int>(pix.bytesperline);
  s.sizeimage = static_cast<int>(pix.sizeimage);
}

int FakeV4l2::ioctl(int fd, unsigned long request, void* arg) {
  const int d = device_of(fd);
  if (d < 0) return -EBADF;
  if (fd_dead_[fd]) return -ENODEV;
  State& s = devices_[d];
  switch (request) {
    case VIDIOC_QUERYCAP: {
      auto* c = static_cast<v4l2_capability*>(arg);
      std::memset(c, 0, sizeof(*c));
      std::strncpy(reinterpret_cast<char*>(c->driver), "fakevideo", sizeof(c->driver) - 1);
      std::strncpy(reinterpret_cast<char*>(c->card), s.card.c_str(), sizeof(c->card) - 1);
      c->device_caps = s.device_caps;
      c->capabilities = s.device_caps | V4L2_CAP_DEVICE_CAPS;
      return 0;
    }
    case VIDIOC_ENUM_FMT: {
      auto* f = static_cast<v4l2_fmtdesc*>(arg);
      if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || f->index >= s.formats.size()) return -EINVAL;
      f->pixelformat = s.formats[f->index].fourcc;
      std::snprintf(reinterpret_cast<char*>(f->description), sizeof(f->description),
                    "fake %c%c%c%c", f->pixelformat & 0xff, (f->pixelformat >> 8) & 0xff,
                    (f->pixelformat >> 16) & 0xff, (f->pixelformat >> 24) & 0xff);
      return 0;
    }
    case VIDIOC_ENUM_FRAMESIZES: {
      auto* z = static_cast<v4l2_frmsizeenum*>(arg);
      for (const auto& f : s.formats) {
        if (f.fourcc != z->pixel_format) continue;
        if (z->index >= f.sizes.size()) return -EINVAL;
        z->type = V4L2_FRMSIZE_TYPE_DISCRETE;
        z->discrete.width = static_cast<uint32_t>(f.sizes[z->index].first);
        z->discrete.height = static_cast<uint32_t>(f.sizes[z->index].second);
        return 0;
      }
      return -EINVAL;
    }
    case VIDIOC_ENUM_FRAMEINTERVALS: {
      auto* iv = static_cast<v4l2_frmivalenum*>(arg);
      if (iv->index > 0) return -EINVAL;
      iv->type = V4L2_FRMIVAL_TYPE_DISCRETE;
      iv->discrete.numerator = 1;
      iv->discrete.denominator = static_cast<uint32_t>(s.fps);
      return 0;
    }
    case VIDIOC_S_FMT:
    case VIDIOC_TRY_FMT: {
      auto* f = static_cast<v4l2_format*>(arg);
      if (f->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return -EINVAL;
      if (request == VIDIOC_S_FMT && (s.streaming || !s.bufs.empty())) return -EBUSY;
      State scratch = s;
      apply_format(request == VIDIOC_S_FMT ? s : scratch, f->fmt.pix);
      return 0;
    }
    case VIDIOC_G_FMT: {
      auto* f = static_cast<v4l2_format*>(arg);
      f->fmt.pix.pixelformat = s.fourcc;
      f->fmt.pix.width = static_cast<uint32_t>(s.width);
      f->fmt.pix.height = static_cast<uint32_t>(s.height);
      f->fmt.pix.bytesperline = static_cast<uint32_t>(s.stride);
      f->fmt.pix.sizeimage = static_cast<uint32_t>(s.sizeimage);
      return 0;
    }
    case VIDIOC_S_PARM: {
      auto* p = static_cast<v4l2_streamparm*>(arg);
      if (p->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return -EINVAL;
      // One discrete interval: whatever is asked, the device's rate is what it gets.
      p->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
      p->parm.capture.timeperframe.numerator = 1;
      p->parm.capture.timeperframe.denominator = static_cast<uint32_t>(s.fps);
      return 0;
    }
    case VIDIOC_QUERYCTRL: {
      auto* q = static_cast<v4l2_queryctrl*>(arg);
      const uint32_t id = q->id;
      std::memset(q, 0, sizeof(*q));
      q->id = id;
      if (id == V4L2_CID_EXPOSURE_AUTO && s.has_exposure) {
        q->type = V4L2_CTRL_TYPE_MENU, q->minimum = 0, q->maximum = 3;
      } else if (id == V4L2_CID_EXPOSURE_ABSOLUTE && s.has_exposure) {
        q->type = V4L2_CTRL_TYPE_INTEGER, q->minimum = 1, q->maximum = 5000;
      } else if (id == V4L2_CID_GAIN) {
        q->type = V4L2_CTRL_TYPE_INTEGER, q->minimum = 0, q->maximum = 255;
      } else {
        return -EINVAL;
      }
      return 0;
    }
    case VIDIOC_S_CTRL: {
      auto* c = static_cast<v4l2_control*>(arg);
      s.controls[c->id] = c->value;
      return 0;
    }
    case VIDIOC_REQBUFS: {
      auto* r = static_cast<v4l2_requestbuffers*>(arg);
      if (r->type != V4L2_BUF_TYPE_VIDEO_CAPTURE || r->memory != V4L2_MEMORY_MMAP) return -EINVAL;
      if (s.reqbufs_errno) return -s.reqbufs_errno;
      if (s.owner_fd >= 0 && s.owner_fd != fd) return -EBUSY;
      if (s.streaming) return -EBUSY;
      for (const auto& b : s.bufs)
        if (b.maps > 0) return -EBUSY;
      s.bufs.clear();
      s.queued.clear();
      s.done.clear();
      if (r->count == 0) {
        s.owner_fd = -1;
        return 0;
      }
      r->count = std::min(r->count, s.max_buffers);
      s.bufs.resize(r->count);
      for (uint32_t i = 0; i < r->count; ++i) {
        Buf& b = s.bufs[i];
        b.mem.assign(static_cast<size_t>(s.sizeimage), 0);
        b.info = v4l2_buffer{};
        b.info.index = i;
        b.info.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
        b.info.memory = V4L2_MEMORY_MMAP;
        b.info.length = static_cast<uint32_t>(s.sizeimage);
        b.info.m.offset = static_cast<uint32_t>(i * page_round(static_cast<size_t>(s.sizeimage)));
      }
      s.owner_fd = fd;
      return 0;
    }
    case VIDIOC_QUERYBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (b->index >= s.bufs.size()) return -EINVAL;
      *b = s.bufs[b->index].info;
      return 0;
    }
    case VIDIOC_QBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (b->index >= s.bufs.size() || b->memory != V4L2_MEMORY_MMAP) return -EINVAL;
      Buf& buf = s.bufs[b->index];
      if (buf.queued || buf.done) return -EINVAL;  // already owned by the driver
      buf.queued = true;
      s.queued.push_back(b->index);
      return 0;
    }
    case VIDIOC_DQBUF: {
      auto* b = static_cast<v4l2_buffer*>(arg);
      if (!s.streaming) return -EINVAL;
      if (s.done.empty()) return -EAGAIN;  // the capture code opens O_NONBLOCK
      const uint32_t i = s.done.front();
      s.done.pop_front();
      s.bufs[i].done = false;
      *b = s.bufs[i].info;
      return 0;
    }
    case VIDIOC_STREAMON:
      if (s.bufs.empty()) return -EINVAL;
      s.streaming = true;
      s.sequence = 0;
      return 0;
    case VIDIOC_STREAMOFF:
      s.streaming = false;
      for (auto& b : s.bufs) b.queued = b.done = false;  // all buffers return to the user
      s.queued.clear();
      s.done.clear();
      return 0;
    default:
      return -ENOTTY;
  }
}

void* FakeV4l2::mmap(size_t length, int fd, off_t offset) {
  const int d = device_of(fd);
  if (d < 0 || fd_dead_[fd]) return nullptr;
  for (auto& b : devices_[d].bufs) {
    if (b.info.m.offset == static_cast<uint32_t>(offset) && length <= b.mem.size()) {
      ++b.maps;
      ++mapped_;
      return b.mem.data();
    }
  }
  return nullptr;
}

void FakeV4l2::munmap(void* addr, size_t /*length*/) {
  for (auto& s : devices_)
    for (auto& b : s.bufs)
      if (b.mem.data() == addr && b.maps > 0) {
        --b.maps;
        --mapped_;
        return;
      }
  for (auto& b : graveyard_)
    if (b.mem.data() == addr && b.maps > 0) {
      --b.maps;
      --mapped_;
      return;
    }
  std::abort();  // unmapping something never mapped
}

int FakeV4l2::poll(int fd, int /*timeout_ms*/) {
  const int d = device_of(fd);
  if (d < 0) return POLLNVAL;
  if (fd_dead_[fd]) return POLLERR | POLLHUP;
  State& s = devices_[d];
  if (!s.streaming) return POLLERR;  // vb2: polling a queue that is not streaming
  if (s.spurious > 0) {
    --s.spurious;
    return POLLIN | POLLRDNORM;
  }
  if (s.done.empty() && on_idle_poll) on_idle_poll(d);
  if (fd_dead_[fd]) return POLLERR | POLLHUP;  // the hook may have unplugged it
  return s.done.empty() ? 0 : (POLLIN | POLLRDNORM);
}

bool FakeV4l2::emit_frame(int dev, int64_t t_us, const std::vector<uint8_t>& bytes, bool error) {
  State& s = devices_[dev];
  if (!s.present || !s.streaming) return false;
  const uint32_t seq = s.sequence++;
  if (s.queued.empty()) return false;  // no buffer to write into: the frame is lost
  const uint32_t i = s.queued.front();
  s.queued.pop_front();
  Buf& b = s.bufs[i];
  const size_t n = std::min(bytes.size(), b.mem.size());
  std::memcpy(b.mem.data(), bytes.data(), n);
  b.queued = false;
  b.done = true;
  b.info.bytesused = static_cast<uint32_t>(n);
  b.info.sequence = seq;
  b.info.timestamp.tv_sec = t_us / 1000000;
  b.info.timestamp.tv_usec = t_us % 1000000;
  b.info.flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_SOE |
                 V4L2_BUF_FLAG_DONE | (error ? V4L2_BUF_FLAG_ERROR : 0u);
  s.done.push_back(i);
  return true;
}

void FakeV4l2::unplug(int dev) {
  State& s = devices_[dev];
  s.present = false;
  s.streaming = false;
  s.queued.clear();
  s.done.clear();
  for (auto& [fd, d] : fds_)
    if (d == dev) fd_dead_[fd] = true;
}

void FakeV4l2::replug(int dev) {
  State& s = devices_[dev];
  s.present = true;
  s.sequence = 0;
  // A new device instance: old buffers live on only while still mapped by the old process.
  for (auto& b : s.bufs)
    if (b.maps > 0) graveyard_.push_back(std::move(b));
  s.bufs.clear();
  s.queued.clear();
  s.done.clear();
  s.owner_fd = -1;
}

std::vector<VideoNode> FakeV4l2::video_nodes() {
  std::vector<VideoNode> out;
  for (const auto& s : devices_)
    if (s.present) out.push_back(s.node);
  return out;
}

std::vector<UsbCamera> FakeV4l2::usb_cameras() {
  std::vector<UsbCamera> out;
  for (const auto& s : devices_) {
    if (!s.present || !s.node.is_usb) continue;
    bool seen = false;
    for (const auto& c : out)
      seen = seen || (c.bus == s.node.usb_bus && c.address == s.node.usb_address);
    if (seen) continue;
    out.push_back(UsbCamera{s.node.vendor_id, s.node.product_id, s.node.serial, s.card,
                            s.node.usb_bus, s.node.usb_address});
  }
  return out;
}

std::string FakeV4l2::usb_reset(int bus, int address) {
  ++resets_;
  for (size_t i = 0; i < devices_.size(); ++i) {
    const State& s = devices_[i];
    if (s.present && s.node.is_usb && s.node.usb_bus == bus && s.node.usb_address == address) {
      unplug(static_cast<int>(i));  // a reset re-enumerates: open descriptors die
      replug(static_cast<int>(i));
      return "";
    }
  }
  return "no USB device at bus " + std::to_string(bus) + " address " + std::to_string(address);
}

}  // namespace alight::camera::testing
