#pragma once
// Camera frames to and from image_t: decoding, encoding and the metadata entries. A library of
// its own (alight_image_msgs), so that only the programs that handle frames link OpenCV's image
// codecs, which load about 130 shared libraries at start-up. Malformed input gives an error
// text, never a crash or a silently wrong image.

#include <alight/image_t.hpp>
#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

namespace alight {

/// A decoded camera frame.
struct Image {
  int64_t utime = 0;  ///< exposure time [us]
  int64_t seq = -1;   ///< capture sequence number ("seq" metadata), -1 when absent
  /// exposure time ("exposure_us" metadata, (0, kMaxExposureUs]) [s]; nullopt when absent
  std::optional<double> exposure_s;
  /// A rolling shutter's row-to-row delay ("line_delay_ns" metadata, (0, kMaxLineDelayNs]) [s]:
  /// row v was exposed utime + v x line_delay_s; nullopt when absent (a global shutter, or a
  /// camera that does not say).
  std::optional<double> line_delay_s;
  cv::Mat pixels;  ///< CV_8UC1 (mono8) or CV_8UC3 (BGR)
};

/// Largest image side image_from_msg accepts [px]. 8192 covers every camera alight flies (the
/// Firefly MV's 640x480 up to 4K sensors) and bounds a decoded frame at 8192 x 8192 x 3 bytes
/// = 192 MiB, so no message, however crafted, makes a node allocate more.
inline constexpr int kMaxImageSide = 8192;
/// Largest image_t data buffer accepted [bytes]: a raw 8192 x 8192 BGRA frame (256 MiB).
inline constexpr int64_t kMaxImageBytes = int64_t{kMaxImageSide} * kMaxImageSide * 4;
/// Longest exposure an "exposure_us" metadata entry may give [us]: one second, longer than any
/// exposure a flying camera takes; beyond it (or <= 0) the frame is malformed.
inline constexpr int64_t kMaxExposureUs = 1'000'000;
/// Longest row-to-row delay a "line_delay_ns" entry may give [ns]: 1 ms, a 0.5 s readout of
/// 480 rows, far slower than any sensor; beyond it (or <= 0) the frame is malformed.
inline constexpr int64_t kMaxLineDelayNs = 1'000'000;
/// Most scans a JPEG may have (a progressive JPEG has about 10; each scan costs a pass over the
/// whole image, so thousands of tiny scans would make a small message expensive to decode).
inline constexpr int kMaxJpegScans = 100;

/// What a JPEG's headers say, read without decoding it.
struct JpegInfo {
  int width = 0;       ///< [px]
  int height = 0;      ///< [px]
  int components = 0;  ///< 1 (grey) or 3 (colour)
  int scans = 0;       ///< SOS segments (1 for baseline, several for progressive)
};

/// Walks a JPEG's marker segments (ITU-T T.81 annex B) without decoding any pixel: the stream
/// must start with SOI, have one baseline, extended or progressive frame header (SOF0/1/2) with
/// 8-bit samples, 1 or 3 components and a size within kMaxImageSide before its first scan, and
/// end with EOI after its last scan. A stream cut anywhere before its EOI is refused, which
/// libjpeg (through cv::imdecode) is not: it pads a truncated scan with grey and returns it.
/// Bytes after EOI are ignored (some cameras pad their frames). Never reads outside [data,
/// data + size).
std::optional<JpegInfo> jpeg_info(const uint8_t* data, size_t size, std::string* error);

/// Decodes GRAY, RGB, BGR, RGBA, BGRA and MJPEG/JPEG frames. `mono` converts colour to mono8.
/// Returns nullopt and sets *error (naming the problem) for malformed, truncated, oversize
/// (beyond kMaxImageSide / kMaxImageBytes) or unsupported frames, and for an "exposure_us"
/// outside (0, kMaxExposureUs]; never throws (OpenCV's
/// exceptions, bad_alloc included, become an error text). A JPEG's size is read from its header
/// (jpeg_info) before it is decoded.
std::optional<Image> image_from_msg(const image_t& msg, bool mono, std::string* error);

/// Raw frame: mono8 as PIXEL_FORMAT_GRAY, 8-bit 3-channel as PIXEL_FORMAT_BGR.
image_t image_to_msg(const cv::Mat& pixels, int64_t utime, int64_t seq = -1);
/// JPEG-compressed frame (PIXEL_FORMAT_MJPEG), e.g. for VISION_DIAG.
image_t jpeg_image_to_msg(const cv::Mat& pixels, int64_t utime, int quality = 80);

void set_metadata_int(image_t& msg, const std::string& key, int64_t value);
/// The frame's exposure time [s] as "exposure_us" metadata (Image::exposure_s once decoded), in
/// whole microseconds and at least 1: image_from_msg refuses a frame that says it had none.
void set_exposure_metadata(image_t& msg, double exposure_s);
std::optional<int64_t> metadata_int(const image_t& msg, const std::string& key);
void set_metadata_string(image_t& msg, const std::string& key, const std::string& value);
std::optional<std::string> metadata_string(const image_t& msg, const std::string& key);

}  // namespace alight
