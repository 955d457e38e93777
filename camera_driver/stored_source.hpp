#pragma once
// Frames without a camera: a video file (OpenCV VideoCapture: AVI, MP4, ... as the installed
// FFmpeg / GStreamer backends decode them) or a folder of images in name order. Played at their
// own rate (FramePacer) or as fast as the consumer takes them.

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "camera_driver/convert.hpp"

namespace alight::camera {

/// --source: "camera" (the configured device), "file:PATH" or "folder:DIR".
struct SourceSpec {
  enum class Kind { kCamera, kVideoFile, kFolder };
  Kind kind = Kind::kCamera;
  std::string path;
};
std::optional<SourceSpec> parse_source(const std::string& text, std::string* error);

class StoredSource {
 public:
  virtual ~StoredSource() = default;
  /// Opens a file or folder source; nullptr and *error when it cannot be read or is empty.
  static std::unique_ptr<StoredSource> open(const SourceSpec& spec, OutputEncoding encoding,
                                            std::string* error);
  /// The next frame in `encoding`, or nullopt at the end (or on an unreadable frame, with
  /// *error set).
  virtual std::optional<cv::Mat> next(std::string* error) = 0;
  /// Moves past one frame without decoding it; false at the end.
  virtual bool skip() = 0;
  /// Back to the first frame (for --loop); false when the source cannot seek.
  virtual bool rewind() = 0;
  /// The source's own frame rate [Hz]; 0 when it has none (an image folder).
  virtual double fps() const = 0;
  /// Frames in the source, -1 when unknown.
  virtual int64_t frame_count() const = 0;
};

/// The image files of a folder (png, jpg, jpeg, bmp, pgm, ppm, tif, tiff), sorted by name.
std::vector<std::string> image_files(const std::string& dir);

/// Converts a decoded BGR or gray image to the output encoding.
cv::Mat to_encoding(const cv::Mat& image, OutputEncoding encoding);

/// Real-time pacing of a stored source: frame i is due at start + i / fps. A consumer that
/// falls behind is told to skip to the newest due frame instead of playing a backlog late.
class FramePacer {
 public:
  FramePacer(double fps, int64_t start_us);
  struct Plan {
    int64_t skip = 0;     ///< frames to skip before reading the next one
    int64_t wait_us = 0;  ///< time to wait before the next frame is due
  };
  /// What to do at `now_us` before reading frame index(); advances the index by skip + 1.
  Plan plan(int64_t now_us);
  int64_t index() const { return next_index_; }
  void restart(int64_t start_us);

 private:
  int64_t period_us_;
  int64_t start_us_;
  int64_t next_index_ = 0;
};

}  // namespace alight::camera
