#pragma once
// Conversions between LCM messages and domain structs: small free functions, tested without a
// network. Malformed input gives an error text, never a crash or a silently wrong image.

#include <alight/image_t.hpp>
#include <alight/pose_t.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "common/pose_buffer.hpp"

namespace alight {

PoseSample from_msg(const pose_t& msg);
pose_t to_msg(const PoseSample& pose, int64_t seq);
/// Validating form of from_msg for untrusted input: nullopt (and *why, when given) unless every
/// position, velocity, orientation and rate field is finite and the quaternion's norm is within
/// 0.01 of 1 (it is then normalised; a zero one would divide by zero). The stamp is left to the
/// node's StampGuard.
std::optional<PoseSample> pose_from_msg(const pose_t& msg, std::string* why);


/// A decoded camera frame.
struct Image {
  int64_t utime = 0;  ///< exposure time [us]
  int64_t seq = -1;   ///< capture sequence number ("seq" metadata), -1 when absent
  cv::Mat pixels;     ///< CV_8UC1 (mono8) or CV_8UC3 (BGR)
};

/// Decodes GRAY, RGB, BGR, RGBA, BGRA and MJPEG/JPEG frames. `mono` converts colour to mono8.
/// Returns nullopt and sets *error (naming the problem) for malformed or unsupported frames.
std::optional<Image> image_from_msg(const image_t& msg, bool mono, std::string* error);

/// Raw frame: mono8 as PIXEL_FORMAT_GRAY, 8-bit 3-channel as PIXEL_FORMAT_BGR.
image_t image_to_msg(const cv::Mat& pixels, int64_t utime, int64_t seq = -1);
/// JPEG-compressed frame (PIXEL_FORMAT_MJPEG), e.g. for VISION_DIAG.
image_t jpeg_image_to_msg(const cv::Mat& pixels, int64_t utime, int quality = 80);

void set_metadata_int(image_t& msg, const std::string& key, int64_t value);
std::optional<int64_t> metadata_int(const image_t& msg, const std::string& key);
void set_metadata_string(image_t& msg, const std::string& key, const std::string& value);
std::optional<std::string> metadata_string(const image_t& msg, const std::string& key);

}  // namespace alight
