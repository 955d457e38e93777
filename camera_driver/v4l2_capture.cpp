// V4L2 streaming I/O with memory-mapped buffers (Linux Media Infrastructure API, "Streaming
// I/O (Memory Mapping)", VIDIOC_REQBUFS / QUERYBUF / QBUF / DQBUF / STREAMON), one state machine
// over the SysIo boundary.

#include "camera_driver/v4l2_capture.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

namespace alight::camera {

const char* to_string(CaptureError error) {
  switch (error) {
    case CaptureError::kNone:
      return "ok";
    case CaptureError::kNotFound:
      return "not found";
    case CaptureError::kBusy:
      return "busy";
    case CaptureError::kPermissionDenied:
      return "permission denied";
    case CaptureError::kAmbiguous:
      return "ambiguous";
    case CaptureError::kNotCapture:
      return "not a capture device";
    case CaptureError::kFormatRejected:
      return "format rejected";
    case CaptureError::kDeviceLost:
      return "device lost";
    case CaptureError::kIo:
      return "I/O error";
  }
  return "?";
}

namespace {

// Classifies an errno from open or from the first configuring ioctls, with advice a user can
// act on.
Status classify(int err, const std::string& path, const std::string& what) {
  Status s;
  switch (err) {
    case ENOENT:
    case ENODEV:
    case ENXIO:
      s.error = CaptureError::kNotFound;
      s.message = path + ": no such device (" + what + ": " + std::strerror(err) +
                  "); is the camera plugged in? `alight-camera --list` shows what is connected";
      break;
    case EBUSY:
      s.error = CaptureError::kBusy;
      s.message = path + ": device busy (" + what + ": " + std::strerror(err) +
                  "); another process is streaming from it (`fuser " + path + "` names it)";
      break;
    case EACCES:
    case EPERM:
      s.error = CaptureError::kPermissionDenied;
      s.message = path + ": permission denied (" + what + ": " + std::strerror(err) +
                  "); add the user to group 'video' (sudo usermod -aG video $USER, then log in "
                  "again) or install a udev rule for the camera";
      break;
    default:
      s.error = CaptureError::kIo;
      s.message = path + ": " + what + " failed: " + std::strerror(err);
  }
  return s;
}

double fps_of(const v4l2_fract& tpf) {
  return tpf.numerator > 0 ? static_cast<double>(tpf.denominator) / tpf.numerator : 0.0;
}

}  // namespace

std::vector<Mode> enumerate_modes(SysIo& io, int fd) {
  std::vector<Mode> modes;
  for (uint32_t fi = 0;; ++fi) {
    v4l2_fmtdesc desc{};
    desc.index = fi;
    desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (io.ioctl(fd, VIDIOC_ENUM_FMT, &desc) < 0) break;
    const std::string description(reinterpret_cast<const char*>(desc.description));
    bool any_size = false;
    for (uint32_t si = 0;; ++si) {
      v4l2_frmsizeenum size{};
      size.index = si;
      size.pixel_format = desc.pixelformat;
      if (io.ioctl(fd, VIDIOC_ENUM_FRAMESIZES, &size) < 0) break;
      any_size = true;
      Mode m;
      m.fourcc = desc.pixelformat;
      m.description = description;
      if (size.type != V4L2_FRMSIZE_TYPE_DISCRETE) {
        const auto& s = size.stepwise;
        m.size_range = std::to_string(s.min_width) + "x" + std::to_string(s.min_height) + ".." +
                       std::to_string(s.max_width) + "x" + std::to_string(s.max_height);
        modes.push_back(m);
        break;  // a stepwise size is the only entry (index 0)
      }
      m.width = static_cast<int>(size.discrete.width);
      m.height = static_cast<int>(size.discrete.height);
      for (uint32_t ii = 0;; ++ii) {
        v4l2_frmivalenum ival{};
        ival.index = ii;
        ival.pixel_format = desc.pixelformat;
        ival.width = size.discrete.width;
        ival.height = size.discrete.height;
        if (io.ioctl(fd, VIDIOC_ENUM_FRAMEINTERVALS, &ival) < 0) break;
        if (ival.type != V4L2_FRMIVAL_TYPE_DISCRETE) break;
        m.fps.push_back(fps_of(ival.discrete));
      }
      modes.push_back(m);
    }
    if (!any_size) {
      Mode m;
      m.fourcc = desc.pixelformat;
      m.description = description;
      m.size_range = "sizes not enumerable";
      modes.push_back(m);
    }
  }
  return modes;
}

V4l2Capture::V4l2Capture(SysIo& io, CaptureConfig config) : io_(io), config_(std::move(config)) {}

V4l2Capture::~V4l2Capture() { close(); }

Status V4l2Capture::fail(CaptureError error, const std::string& message) {
  close();
  return Status{error, message};
}

Status V4l2Capture::open() {
  close();
  warnings_.clear();
  const Candidates candidates = candidate_nodes(config_.device, io_.video_nodes());
  if (candidates.nodes.empty())
    return Status{candidates.ambiguous ? CaptureError::kAmbiguous : CaptureError::kNotFound,
                  candidates.error};
  // A USB camera's first node that streams video wins; for a path the one candidate decides.
  Status last;
  for (const auto& node : candidates.nodes) {
    last = open_node(node);
    if (last.ok() || last.error != CaptureError::kNotCapture) return last;
  }
  return last;
}

Status V4l2Capture::open_node(const VideoNode& node) {
  node_ = node;
  const int fd = io_.open(node.path, O_RDWR | O_NONBLOCK);
  if (fd < 0) return classify(-fd, node.path, "open");
  fd_ = fd;

  v4l2_capability cap{};
  if (const int r = io_.ioctl(fd_, VIDIOC_QUERYCAP, &cap); r < 0) {
    const Status s = r == -ENOTTY ? Status{CaptureError::kNotCapture,
                                           node.path + ": not a V4L2 device (VIDIOC_QUERYCAP)"}
                                  : classify(-r, node.path, "VIDIOC_QUERYCAP");
    return fail(s.error, s.message);
  }
  const uint32_t caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  if (!(caps & V4L2_CAP_VIDEO_CAPTURE) || !(caps & V4L2_CAP_STREAMING))
    return fail(CaptureError::kNotCapture,
                node.path + " (" + reinterpret_cast<const char*>(cap.card) +
                    ") is not a video capture device with streaming I/O");
  format_ = NegotiatedFormat{};
  format_.path = node.path;
  if (Status s = negotiate(); !s.ok()) return fail(s.error, s.message);
  set_controls();
  if (Status s = start_streaming(); !s.ok()) return fail(s.error, s.message);
  return Status{};
}

Status V4l2Capture::negotiate() {
  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = static_cast<uint32_t>(config_.width);
  fmt.fmt.pix.height = static_cast<uint32_t>(config_.height);
  fmt.fmt.pix.pixelformat = fourcc(config_.format);
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  if (const int r = io_.ioctl(fd_, VIDIOC_S_FMT, &fmt); r < 0)
    return classify(-r, node_.path, "VIDIOC_S_FMT " + to_string(config_.format));
  // S_FMT never fails for an unsupported format: it substitutes one it has.
  const auto got = pixel_format_from_fourcc(fmt.fmt.pix.pixelformat);
  if (!got || *got != config_.format) {
    std::string offered;
    for (const auto& m : enumerate_modes(io_, fd_)) {
      const std::string f = fourcc_text(m.fourcc);
      if (offered.find(f) == std::string::npos) offered += (offered.empty() ? "" : ", ") + f;
    }
    return Status{CaptureError::kFormatRejected,
                  node_.path + ": pixel format " + to_string(config_.format) +
                      " is not offered (the driver answered " +
                      fourcc_text(fmt.fmt.pix.pixelformat) + "; offered: " + offered + ")"};
  }
  format_.format = *got;
  format_.width = static_cast<int>(fmt.fmt.pix.width);
  format_.height = static_cast<int>(fmt.fmt.pix.height);
  format_.stride = static_cast<int>(fmt.fmt.pix.bytesperline);
  if (format_.stride == 0)  // compressed formats report 0; raw ones must not
    format_.stride = format_.width * (config_.format == PixelFormat::kYuyv ? 2 : 1);
  if (format_.width != config_.width || format_.height != config_.height)
    warnings_.push_back(node_.path + ": asked for " + std::to_string(config_.width) + "x" +
                        std::to_string(config_.height) + ", the driver gave " +
                        std::to_string(format_.width) + "x" + std::to_string(format_.height));

  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  parm.parm.capture.timeperframe.numerator = 1000;
  parm.parm.capture.timeperframe.denominator =
      static_cast<uint32_t>(std::lround(config_.fps * 1000.0));
  if (io_.ioctl(fd_, VIDIOC_S_PARM, &parm) == 0 &&
      (parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME)) {
    format_.fps = fps_of(parm.parm.capture.timeperframe);
    if (std::abs(format_.fps - config_.fps) > 0.01 * config_.fps)
      warnings_.push_back(node_.path + ": asked for " + std::to_string(config_.fps) +
                          " fps, the driver gave " + std::to_string(format_.fps));
  } else {
    warnings_.push_back(node_.path + ": the driver does not set the frame rate (VIDIOC_S_PARM)");
  }
  return Status{};
}

void V4l2Capture::set_controls() {
  // Controls are best effort: a camera without manual exposure still streams, with a warning.
  // Each returns the value set, nullopt when it could not be.
  exposure_us_.reset();
  auto set = [&](uint32_t id, int value, const char* name) -> std::optional<int> {
    v4l2_queryctrl q{};
    q.id = id;
    if (io_.ioctl(fd_, VIDIOC_QUERYCTRL, &q) < 0 || (q.flags & V4L2_CTRL_FLAG_DISABLED)) {
      warnings_.push_back(node_.path + ": no control " + name);
      return std::nullopt;
    }
    int v = value;
    if (v < q.minimum || v > q.maximum) {
      v = std::clamp(v, q.minimum, q.maximum);
      warnings_.push_back(node_.path + ": " + name + " " + std::to_string(value) + " is outside [" +
                          std::to_string(q.minimum) + ", " + std::to_string(q.maximum) +
                          "], using " + std::to_string(v));
    }
    v4l2_control c{id, v};
    if (io_.ioctl(fd_, VIDIOC_S_CTRL, &c) < 0) {
      warnings_.push_back(node_.path + ": setting " + name + " failed");
      return std::nullopt;
    }
    return v;
  };
  if (config_.exposure_us > 0) {
    const auto manual = set(V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL, "exposure_auto");
    // V4L2_CID_EXPOSURE_ABSOLUTE counts 100 us units.
    const auto units = set(V4L2_CID_EXPOSURE_ABSOLUTE,
                           std::max(1, (config_.exposure_us + 50) / 100), "exposure_absolute");
    if (manual && units) exposure_us_ = int64_t{*units} * 100;
  } else {
    set(V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_APERTURE_PRIORITY, "exposure_auto");
  }
  if (config_.gain >= 0) {
    set(V4L2_CID_AUTOGAIN, 0, "autogain");
    set(V4L2_CID_GAIN, config_.gain, "gain");
  }
}

Status V4l2Capture::start_streaming() {
  v4l2_requestbuffers req{};
  req.count = static_cast<uint32_t>(config_.buffer_count);
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  if (const int r = io_.ioctl(fd_, VIDIOC_REQBUFS, &req); r < 0)
    return classify(-r, node_.path, "VIDIOC_REQBUFS");
  // With one buffer the driver has nowhere to write while we convert: every frame would drop.
  if (req.count < 2)
    return Status{CaptureError::kIo, node_.path + ": the driver granted " +
                                         std::to_string(req.count) + " buffer(s), 2 needed"};
  buffers_.assign(req.count, Buffer{});
  for (uint32_t i = 0; i < req.count; ++i) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = i;
    if (const int r = io_.ioctl(fd_, VIDIOC_QUERYBUF, &b); r < 0)
      return classify(-r, node_.path, "VIDIOC_QUERYBUF");
    void* p = io_.mmap(b.length, fd_, static_cast<off_t>(b.m.offset));
    if (!p)
      return Status{CaptureError::kIo,
                    node_.path + ": mmap of buffer " + std::to_string(i) + " failed"};
    buffers_[i] = Buffer{p, b.length};
    if (const int r = io_.ioctl(fd_, VIDIOC_QBUF, &b); r < 0)
      return classify(-r, node_.path, "VIDIOC_QBUF");
  }
  format_.buffers = static_cast<int>(req.count);
  v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (const int r = io_.ioctl(fd_, VIDIOC_STREAMON, &type); r < 0)
    return classify(-r, node_.path, "VIDIOC_STREAMON");
  streaming_ = true;
  last_sequence_ = -1;  // the kernel numbers frames from 0 at every STREAMON
  // A new stream's timestamps owe nothing to the last one's (a device with its own clock, a
  // re-enumerated USB camera): judging them against the old stream dropped every frame.
  last_returned_us_ = -1;
  return Status{};
}

void V4l2Capture::close() {
  if (fd_ < 0) return;
  if (streaming_) {
    v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    io_.ioctl(fd_, VIDIOC_STREAMOFF, &type);  // fails harmlessly with ENODEV after an unplug
    streaming_ = false;
  }
  for (auto& b : buffers_)
    if (b.start) io_.munmap(b.start, b.length);
  buffers_.clear();
  // Buffers must be unmapped before they can be freed; after an unplug this fails, harmlessly.
  v4l2_requestbuffers req{};
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  io_.ioctl(fd_, VIDIOC_REQBUFS, &req);
  io_.close(fd_);
  fd_ = -1;
}

bool V4l2Capture::requeue(uint32_t index) {
  v4l2_buffer b{};
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  b.index = index;
  return io_.ioctl(fd_, VIDIOC_QBUF, &b) >= 0;
}

GrabResult V4l2Capture::grab(int timeout_ms) {
  GrabResult out;
  if (fd_ < 0) {
    out.status = GrabStatus::kError;
    out.message = "grab() on a closed device";
    return out;
  }
  const int revents = io_.poll(fd_, timeout_ms);
  if (revents < 0) {
    out.status = GrabStatus::kError;
    out.message = node_.path + ": poll failed: " + std::strerror(-revents);
    return out;
  }
  if (revents == 0) return out;  // timeout
  // Whatever poll said (POLLIN, or POLLERR after an unplug), DQBUF tells what happened.

  // Drain every completed buffer, keep the newest. Gaps are counted over all of them, so a
  // frame skipped here is never mistaken for one the kernel dropped.
  std::optional<v4l2_buffer> newest;
  uint32_t dropped = 0, skipped = 0, bad = 0;
  for (;;) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    const int r = io_.ioctl(fd_, VIDIOC_DQBUF, &b);
    if (r == -EAGAIN) break;
    if (r < 0) {
      if (newest) requeue(newest->index);
      out.status = (r == -ENODEV || r == -ENXIO) ? GrabStatus::kDeviceLost : GrabStatus::kError;
      out.message = node_.path +
                    (out.status == GrabStatus::kDeviceLost ? ": device disconnected (VIDIOC_DQBUF: "
                                                           : ": VIDIOC_DQBUF failed (") +
                    std::strerror(-r) + ")";
      return out;
    }
    const int64_t seq = b.sequence;
    if (last_sequence_ >= 0 && seq > last_sequence_ + 1)
      dropped += static_cast<uint32_t>(seq - last_sequence_ - 1);
    if (last_sequence_ < 0 && seq > 0) dropped += static_cast<uint32_t>(seq);
    last_sequence_ = seq;
    const int64_t stamp_us = timeval_us(b.timestamp);
    if ((b.flags & V4L2_BUF_FLAG_ERROR) || b.index >= buffers_.size()) {
      ++bad;
      requeue(b.index);
      continue;
    }
    if (last_returned_us_ >= 0 && stamp_us <= last_returned_us_) {
      ++counters_.stale;  // older than what the consumer already has: never delivered as new
      requeue(b.index);
      continue;
    }
    if (newest) {
      ++skipped;
      requeue(newest->index);
    }
    newest = b;
  }
  counters_.dropped += dropped;
  counters_.skipped += skipped;
  counters_.bad_frames += bad;
  if (!newest) {
    if (bad > 0) {
      out.status = GrabStatus::kBadFrame;
      out.message = node_.path + ": " + std::to_string(bad) + " buffer(s) flagged as corrupt";
    } else {
      ++counters_.empty_wakeups;
    }
    return out;
  }

  const v4l2_buffer& b = *newest;
  RawFrameView view;
  view.data = static_cast<const uint8_t*>(buffers_[b.index].start);
  view.bytes = std::min<size_t>(b.bytesused, buffers_[b.index].length);
  view.width = format_.width;
  view.height = format_.height;
  view.stride = format_.stride;
  view.format = format_.format;
  Frame frame;
  std::string error;
  const bool converted = convert_frame(view, config_.encoding, frame.pixels, &error);
  const bool requeued = requeue(b.index);
  if (!converted) {
    ++counters_.bad_frames;
    out.status = GrabStatus::kBadFrame;
    out.message = node_.path + ": frame " + std::to_string(b.sequence) + ": " + error;
    return out;
  }
  frame.buffer_mono_us = timeval_us(b.timestamp);
  frame.stamp_source = stamp_source_from_flags(b.flags);
  frame.monotonic_clock =
      (b.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
  frame.sequence = b.sequence;
  frame.dropped = dropped;
  frame.skipped = skipped;
  last_returned_us_ = frame.buffer_mono_us;
  ++counters_.frames;
  out.status = GrabStatus::kFrame;
  out.frame = std::move(frame);
  if (!requeued) out.message = node_.path + ": VIDIOC_QBUF failed; the next grab will tell why";
  return out;
}

}  // namespace alight::camera
