#pragma once
// Pixel-format conversion of one captured V4L2 buffer into the published encoding. The formats
// are those of the paper's camera class (section 4.1: a 640x480 monochrome USB camera) and of
// common UVC webcams: GREY (8-bit luma), YUYV (4:2:2, Y0 U Y1 V) and MJPEG (one JPEG per frame).
// Conversions are OpenCV's (cvtColor, imdecode); the wrapper checks every size against the
// buffer before a pixel is read, so a short or corrupt buffer is an error, never a crash.

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

namespace alight::camera {

enum class PixelFormat { kGrey, kYuyv, kMjpeg };
/// mono8: one byte per pixel; rgb8 / bgr8: three bytes per pixel in that order.
enum class OutputEncoding { kMono8, kRgb8, kBgr8 };

/// The V4L2 FourCC (V4L2_PIX_FMT_GREY, _YUYV, _MJPEG).
uint32_t fourcc(PixelFormat format);
std::optional<PixelFormat> pixel_format_from_fourcc(uint32_t fourcc);
/// "GREY" (or "GRAY"), "YUYV", "MJPEG" (or "MJPG"), case-sensitive as V4L2 spells them.
std::optional<PixelFormat> parse_pixel_format(const std::string& name);
std::string to_string(PixelFormat format);
std::optional<OutputEncoding> parse_output_encoding(const std::string& name);
std::string to_string(OutputEncoding encoding);
/// The four characters of a FourCC, for messages ("YUYV").
std::string fourcc_text(uint32_t fourcc);

/// One captured buffer as the driver negotiated it (VIDIOC_S_FMT's answer).
struct RawFrameView {
  const uint8_t* data = nullptr;
  size_t bytes = 0;  ///< bytesused of the buffer
  int width = 0;     ///< [px]
  int height = 0;    ///< [px]
  int stride = 0;    ///< bytesperline (ignored for MJPEG)
  PixelFormat format = PixelFormat::kGrey;
};

/// Converts into `out` (reusing its allocation when the size matches). Returns false and sets
/// *error when the buffer is too short or the JPEG cannot be decoded or has another size.
bool convert_frame(const RawFrameView& frame, OutputEncoding encoding, cv::Mat& out,
                   std::string* error);

}  // namespace alight::camera
