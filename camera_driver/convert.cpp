#include "camera_driver/convert.hpp"

#include <linux/videodev2.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace alight::camera {

uint32_t fourcc(PixelFormat format) {
  switch (format) {
    case PixelFormat::kGrey:
      return V4L2_PIX_FMT_GREY;
    case PixelFormat::kYuyv:
      return V4L2_PIX_FMT_YUYV;
    case PixelFormat::kMjpeg:
      return V4L2_PIX_FMT_MJPEG;
  }
  return 0;
}

std::optional<PixelFormat> pixel_format_from_fourcc(uint32_t code) {
  switch (code) {
    case V4L2_PIX_FMT_GREY:
      return PixelFormat::kGrey;
    case V4L2_PIX_FMT_YUYV:
      return PixelFormat::kYuyv;
    case V4L2_PIX_FMT_MJPEG:
      return PixelFormat::kMjpeg;
    case V4L2_PIX_FMT_JPEG:
      return PixelFormat::kMjpeg;  // some UVC drivers label MJPEG so
    default:
      return std::nullopt;
  }
}

std::optional<PixelFormat> parse_pixel_format(const std::string& name) {
  if (name == "GREY" || name == "GRAY") return PixelFormat::kGrey;
  if (name == "YUYV") return PixelFormat::kYuyv;
  if (name == "MJPEG" || name == "MJPG") return PixelFormat::kMjpeg;
  return std::nullopt;
}

std::string to_string(PixelFormat format) {
  switch (format) {
    case PixelFormat::kGrey:
      return "GREY";
    case PixelFormat::kYuyv:
      return "YUYV";
    case PixelFormat::kMjpeg:
      return "MJPEG";
  }
  return "?";
}

std::optional<OutputEncoding> parse_output_encoding(const std::string& name) {
  if (name == "mono8") return OutputEncoding::kMono8;
  if (name == "rgb8") return OutputEncoding::kRgb8;
  if (name == "bgr8") return OutputEncoding::kBgr8;
  return std::nullopt;
}

std::string to_string(OutputEncoding encoding) {
  switch (encoding) {
    case OutputEncoding::kMono8:
      return "mono8";
    case OutputEncoding::kRgb8:
      return "rgb8";
    case OutputEncoding::kBgr8:
      return "bgr8";
  }
  return "?";
}

std::string fourcc_text(uint32_t code) {
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((code >> (8 * i)) & 0xff);
    s += (c >= 32 && c < 127) ? c : '?';
  }
  return s;
}

namespace {
bool fail(std::string* error, const std::string& text) {
  if (error) *error = text;
  return false;
}

// Raw formats: the buffer must hold `height` rows of `stride` bytes (the last row may end at
// width * bytes_per_pixel; drivers do not pad after it).
bool check_raw(const RawFrameView& f, int bytes_per_pixel, std::string* error) {
  if (f.width <= 0 || f.height <= 0 || !f.data)
    return fail(error, "frame " + std::to_string(f.width) + "x" + std::to_string(f.height) +
                           " has no pixels");
  if (f.stride < f.width * bytes_per_pixel)
    return fail(error, "bytesperline " + std::to_string(f.stride) + " < width " +
                           std::to_string(f.width) + " x " + std::to_string(bytes_per_pixel));
  const size_t needed = static_cast<size_t>(f.stride) * (f.height - 1) +
                        static_cast<size_t>(f.width) * bytes_per_pixel;
  if (f.bytes < needed)
    return fail(error, to_string(f.format) + " buffer holds " + std::to_string(f.bytes) +
                           " bytes, " + std::to_string(needed) + " needed for " +
                           std::to_string(f.width) + "x" + std::to_string(f.height));
  return true;
}
}  // namespace

bool convert_frame(const RawFrameView& f, OutputEncoding encoding, cv::Mat& out,
                   std::string* error) {
  switch (f.format) {
    case PixelFormat::kGrey: {
      if (!check_raw(f, 1, error)) return false;
      const cv::Mat view(f.height, f.width, CV_8UC1, const_cast<uint8_t*>(f.data),
                         static_cast<size_t>(f.stride));
      if (encoding == OutputEncoding::kMono8) {
        view.copyTo(out);  // the buffer goes back to the kernel right after this
      } else {
        cv::cvtColor(view, out, cv::COLOR_GRAY2BGR);  // identical channels: order is moot
      }
      return true;
    }
    case PixelFormat::kYuyv: {
      if (!check_raw(f, 2, error)) return false;
      if (f.width % 2 != 0) return fail(error, "YUYV width " + std::to_string(f.width) + " is odd");
      const cv::Mat view(f.height, f.width, CV_8UC2, const_cast<uint8_t*>(f.data),
                         static_cast<size_t>(f.stride));
      const int code = encoding == OutputEncoding::kMono8  ? cv::COLOR_YUV2GRAY_YUYV
                       : encoding == OutputEncoding::kRgb8 ? cv::COLOR_YUV2RGB_YUYV
                                                           : cv::COLOR_YUV2BGR_YUYV;
      cv::cvtColor(view, out, code);
      return true;
    }
    case PixelFormat::kMjpeg: {
      if (!f.data || f.bytes < 4) return fail(error, "MJPEG buffer is empty");
      const cv::Mat stream(1, static_cast<int>(f.bytes), CV_8UC1, const_cast<uint8_t*>(f.data));
      const int flags =
          encoding == OutputEncoding::kMono8 ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR;
      cv::Mat decoded = cv::imdecode(stream, flags);
      if (decoded.empty())
        return fail(error,
                    "MJPEG frame of " + std::to_string(f.bytes) + " bytes could not be decoded");
      if (decoded.cols != f.width || decoded.rows != f.height)
        return fail(error, "MJPEG frame decodes to " + std::to_string(decoded.cols) + "x" +
                               std::to_string(decoded.rows) + ", the format says " +
                               std::to_string(f.width) + "x" + std::to_string(f.height));
      if (encoding == OutputEncoding::kRgb8) {
        cv::cvtColor(decoded, out, cv::COLOR_BGR2RGB);
      } else {
        out = decoded;
      }
      return true;
    }
  }
  return fail(error, "unknown pixel format");
}

}  // namespace alight::camera
