#pragma once
// The newest frame of one video channel, handed from the LCM thread to any number of web
// clients. The LCM thread only swaps a pointer (never encodes, never waits for a client); JPEG
// encoding of raw frames happens at most once per frame, on the first client thread that asks.
// Memory is bounded by design: one raw frame and one JPEG per channel, however many clients.

#include <alight/image_t.hpp>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

namespace alight::ground_station {

class FrameStore {
 public:
  explicit FrameStore(int jpeg_quality = 75) : jpeg_quality_(jpeg_quality) {}

  /// LCM thread: the newest frame (ownership moves in; O(1) under a short lock).
  void put(std::shared_ptr<const image_t> frame);

  struct Jpeg {
    std::shared_ptr<const std::string> bytes;
    uint64_t seq = 0;   ///< 1 for the first frame put, counting up
    int64_t utime = 0;  ///< exposure time of the frame
    int width = 0, height = 0;
  };
  /// Client threads: the newest frame as JPEG, waiting up to `wait_s` for one newer than
  /// `after_seq`. nullopt when no frame has arrived yet, or it cannot be decoded (`error`).
  std::optional<Jpeg> jpeg_after(uint64_t after_seq, double wait_s, std::string* error = nullptr);
  uint64_t seq() const;
  /// Wakes all waiting clients (shutdown).
  void wake_all();

 private:
  int jpeg_quality_;
  mutable std::mutex mutex_;
  std::condition_variable arrived_;
  std::shared_ptr<const image_t> frame_;
  uint64_t seq_ = 0;
  bool shutting_down_ = false;

  std::mutex encode_mutex_;  // one encoder per channel; other clients wait and share its result
  Jpeg cached_;
};

/// JPEG bytes of a frame: MJPEG frames pass through, raw frames are encoded.
std::optional<std::string> frame_to_jpeg(const image_t& frame, int quality, std::string* error);

}  // namespace alight::ground_station
