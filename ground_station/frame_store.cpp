#include "ground_station/frame_store.hpp"

#include <chrono>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "common/image_msg.hpp"

namespace alight::ground_station {

std::optional<std::string> frame_to_jpeg(const image_t& frame, int quality, std::string* error) {
  if (frame.pixelformat == image_t::PIXEL_FORMAT_MJPEG) {
    // Passed through undecoded, but only a complete JPEG of a sane size (jpeg_info: header and
    // EOI checked, the same rules as image_from_msg) reaches the browser.
    if (!jpeg_info(frame.data.data(), frame.data.size(), error)) return std::nullopt;
    return std::string(frame.data.begin(), frame.data.end());
  }
  const auto image = image_from_msg(frame, false, error);  // never throws
  if (!image) return std::nullopt;
  std::vector<uint8_t> buf;
  bool encoded = false;
  try {
    encoded = cv::imencode(".jpg", image->pixels, buf, {cv::IMWRITE_JPEG_QUALITY, quality});
  } catch (const std::exception& e) {  // cv::Exception, bad_alloc: the frame is dropped
    if (error) *error = std::string("JPEG encoding failed: ") + e.what();
    return std::nullopt;
  }
  if (!encoded) {
    if (error) *error = "JPEG encoding failed";
    return std::nullopt;
  }
  return std::string(buf.begin(), buf.end());
}

void FrameStore::put(std::shared_ptr<const image_t> frame) {
  std::shared_ptr<const image_t> old;  // freed outside the lock
  {
    std::lock_guard<std::mutex> lock(mutex_);
    old = std::move(frame_);
    frame_ = std::move(frame);
    ++seq_;
  }
  arrived_.notify_all();
}

uint64_t FrameStore::seq() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return seq_;
}

void FrameStore::wake_all() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    shutting_down_ = true;
  }
  arrived_.notify_all();
}

std::optional<FrameStore::Jpeg> FrameStore::jpeg_after(uint64_t after_seq, double wait_s,
                                                       std::string* error) {
  std::shared_ptr<const image_t> frame;
  uint64_t seq = 0;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    arrived_.wait_for(lock, std::chrono::duration<double>(wait_s),
                      [&] { return seq_ > after_seq || shutting_down_; });
    frame = frame_;
    seq = seq_;
  }
  if (!frame) {
    if (error) *error = "no frame yet";
    return std::nullopt;
  }
  std::lock_guard<std::mutex> encode_lock(encode_mutex_);
  if (cached_.bytes && cached_.seq == seq) return cached_;
  auto bytes = frame_to_jpeg(*frame, jpeg_quality_, error);
  if (!bytes) return std::nullopt;
  cached_ = Jpeg{std::make_shared<const std::string>(std::move(*bytes)), seq, frame->utime,
                 frame->width, frame->height};
  return cached_;
}

}  // namespace alight::ground_station
