#include "common/image_msg.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace alight {

namespace {
bool fail(std::string* error, const std::string& text) {
  if (error) *error = text;
  return false;
}

std::string size_text(int64_t width, int64_t height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// Checks the raw-format fields against the bounds and the data size before any pixel is
// touched. All products in 64 bits: an RGB frame 0x55555556 wide made `width * 3` wrap to 2 in
// int32 and passed.
bool check_raw(const image_t& m, int bytes_per_pixel, std::string* error) {
  if (m.width <= 0 || m.height <= 0)
    return fail(error, "image size " + size_text(m.width, m.height) + " is not positive");
  if (m.width > kMaxImageSide || m.height > kMaxImageSide)
    return fail(error, "image size " + size_text(m.width, m.height) + " exceeds " +
                           size_text(kMaxImageSide, kMaxImageSide));
  const int64_t row_bytes = int64_t{m.width} * bytes_per_pixel;
  if (int64_t{m.row_stride} < row_bytes)
    return fail(error, "row_stride " + std::to_string(m.row_stride) + " < width x " +
                           std::to_string(bytes_per_pixel) + " bytes");
  const int64_t needed = int64_t{m.row_stride} * m.height;
  if (static_cast<int64_t>(m.size) != static_cast<int64_t>(m.data.size()) || m.size < needed)
    return fail(error, "data holds " + std::to_string(m.data.size()) + " bytes (size field " +
                           std::to_string(m.size) + "), " + std::to_string(needed) + " needed");
  return true;
}

uint16_t be16(const uint8_t* p) { return static_cast<uint16_t>((p[0] << 8) | p[1]); }

bool is_sof(uint8_t code) {
  // SOF0..SOF15 are 0xC0..0xCF except DHT (C4), JPG (C8) and DAC (CC).
  return code >= 0xC0 && code <= 0xCF && code != 0xC4 && code != 0xC8 && code != 0xCC;
}

std::string hex_byte(uint8_t b) {
  static const char* digits = "0123456789ABCDEF";
  return std::string("0x") + digits[b >> 4] + digits[b & 15];
}

std::optional<Image> decode_jpeg(const image_t& m, bool mono, Image img, std::string* error) {
  if (static_cast<int64_t>(m.size) != static_cast<int64_t>(m.data.size()) || m.data.empty()) {
    fail(error, "JPEG frame with size field " + std::to_string(m.size) + " and " +
                    std::to_string(m.data.size()) + " data bytes");
    return std::nullopt;
  }
  std::string why;
  const auto info = jpeg_info(m.data.data(), m.data.size(), &why);
  if (!info) {
    fail(error, why);
    return std::nullopt;
  }
  if (m.width > 0 && (info->width != m.width || info->height != m.height)) {
    fail(error, "JPEG is " + size_text(info->width, info->height) + " but the message says " +
                    size_text(m.width, m.height));
    return std::nullopt;
  }
  // The orientation is the camera's: an EXIF tag must not rotate (and resize) the frame.
  const int flags =
      (mono ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR) | cv::IMREAD_IGNORE_ORIENTATION;
  const cv::Mat bytes(1, static_cast<int>(m.data.size()), CV_8U,
                      const_cast<uint8_t*>(m.data.data()));
  img.pixels = cv::imdecode(bytes, flags);
  if (img.pixels.empty()) {
    fail(error, "JPEG data could not be decoded");
    return std::nullopt;
  }
  if (img.pixels.cols != info->width || img.pixels.rows != info->height) {
    fail(error, "JPEG decoded to " + size_text(img.pixels.cols, img.pixels.rows) +
                    " but its header says " + size_text(info->width, info->height));
    return std::nullopt;
  }
  return img;
}

std::optional<Image> decode_image(const image_t& m, bool mono, std::string* error) {
  Image img;
  img.utime = m.utime;
  img.seq = metadata_int(m, "seq").value_or(-1);
  if (const auto exposure_us = metadata_int(m, "exposure_us")) {
    if (*exposure_us <= 0 || *exposure_us > kMaxExposureUs) {
      fail(error, "exposure_us metadata of " + std::to_string(*exposure_us) + " is outside (0, " +
                      std::to_string(kMaxExposureUs) + "] us");
      return std::nullopt;
    }
    img.exposure_s = double(*exposure_us) * 1e-6;
  }
  if (const auto line_delay_ns = metadata_int(m, "line_delay_ns")) {
    if (*line_delay_ns <= 0 || *line_delay_ns > kMaxLineDelayNs) {
      fail(error, "line_delay_ns metadata of " + std::to_string(*line_delay_ns) +
                      " is outside (0, " + std::to_string(kMaxLineDelayNs) + "] ns");
      return std::nullopt;
    }
    img.line_delay_s = double(*line_delay_ns) * 1e-9;
  }
  if (static_cast<int64_t>(m.data.size()) > kMaxImageBytes) {
    fail(error, "image data of " + std::to_string(m.data.size()) + " bytes exceeds " +
                    std::to_string(kMaxImageBytes));
    return std::nullopt;
  }
  // Raw formats: bytes per pixel, and the cvtColor codes to BGR and to mono (-1: none needed).
  struct Raw {
    int bpp, to_bgr, to_gray;
  };
  Raw raw{};
  switch (m.pixelformat) {
    case image_t::PIXEL_FORMAT_GRAY:
      raw = {1, cv::COLOR_GRAY2BGR, -1};
      break;
    case image_t::PIXEL_FORMAT_BGR:
      raw = {3, -1, cv::COLOR_BGR2GRAY};
      break;
    case image_t::PIXEL_FORMAT_RGB:
      raw = {3, cv::COLOR_RGB2BGR, cv::COLOR_RGB2GRAY};
      break;
    case image_t::PIXEL_FORMAT_BGRA:
      raw = {4, cv::COLOR_BGRA2BGR, cv::COLOR_BGRA2GRAY};
      break;
    case image_t::PIXEL_FORMAT_RGBA:
      raw = {4, cv::COLOR_RGBA2BGR, cv::COLOR_RGBA2GRAY};
      break;
    case image_t::PIXEL_FORMAT_MJPEG:
      return decode_jpeg(m, mono, std::move(img), error);
    default:
      fail(error, "unsupported pixel format " + std::to_string(m.pixelformat));
      return std::nullopt;
  }
  if (!check_raw(m, raw.bpp, error)) return std::nullopt;
  const cv::Mat view(m.height, m.width, CV_8UC(raw.bpp), const_cast<uint8_t*>(m.data.data()),
                     static_cast<size_t>(m.row_stride));
  const int code = mono ? raw.to_gray : raw.to_bgr;
  if (code >= 0) {
    cv::cvtColor(view, img.pixels, code);
  } else {
    img.pixels = view.clone();  // the message's buffer does not outlive the callback
  }
  return img;
}
}  // namespace

std::optional<JpegInfo> jpeg_info(const uint8_t* data, size_t size, std::string* error) {
  const auto refuse = [&](const std::string& why) -> std::optional<JpegInfo> {
    fail(error, "JPEG " + why);
    return std::nullopt;
  };
  const auto truncated = [&]() {
    return refuse("truncated: its " + std::to_string(size) + " bytes end before the EOI marker");
  };
  if (size < 2 || data[0] != 0xFF || data[1] != 0xD8) return refuse("without a start (SOI) marker");
  JpegInfo info;
  bool have_frame = false;
  size_t pos = 2;
  for (;;) {
    if (pos >= size) return truncated();
    if (data[pos] != 0xFF) return refuse("without a marker at byte " + std::to_string(pos));
    while (pos < size && data[pos] == 0xFF) ++pos;  // fill bytes may precede any marker
    if (pos >= size) return truncated();
    const uint8_t code = data[pos++];
    if (code == 0xD9) {  // EOI
      if (info.scans == 0) return refuse("ends (EOI) before any scan");
      return info;
    }
    if (code == 0xD8 || code == 0x00) return refuse("with a misplaced marker " + hex_byte(code));
    if ((code >= 0xD0 && code <= 0xD7) || code == 0x01) continue;  // RSTn, TEM: no length
    if (size - pos < 2) return truncated();
    const size_t length = be16(data + pos);  // counts its own two bytes
    if (length < 2)
      return refuse("segment " + hex_byte(code) + " with length " + std::to_string(length));
    if (size - pos < length) return truncated();
    const uint8_t* seg = data + pos + 2;
    const size_t seg_bytes = length - 2;
    pos += length;
    if (is_sof(code)) {
      if (have_frame) return refuse("with a second frame header");
      if (code != 0xC0 && code != 0xC1 && code != 0xC2)
        return refuse("coding process SOF" + std::to_string(code - 0xC0) +
                      " is not supported (baseline, extended or progressive only)");
      if (seg_bytes < 6) return refuse("frame header too short");
      const int precision = seg[0];
      info.height = be16(seg + 1);
      info.width = be16(seg + 3);
      info.components = seg[5];
      if (precision != 8)
        return refuse("with " + std::to_string(precision) + "-bit samples (8 supported)");
      if (info.width == 0 || info.height == 0)
        return refuse("size " + size_text(info.width, info.height) + " is not positive");
      if (info.width > kMaxImageSide || info.height > kMaxImageSide)
        return refuse("size " + size_text(info.width, info.height) + " exceeds " +
                      size_text(kMaxImageSide, kMaxImageSide));
      if (info.components != 1 && info.components != 3)
        return refuse("with " + std::to_string(info.components) + " components (1 or 3)");
      if (seg_bytes != 6 + 3 * static_cast<size_t>(info.components))
        return refuse("frame header of " + std::to_string(seg_bytes) + " bytes for " +
                      std::to_string(info.components) + " components");
      have_frame = true;
    } else if (code == 0xDA) {  // SOS: its header, then entropy-coded data up to the next marker
      if (!have_frame) return refuse("scan before the frame header");
      if (++info.scans > kMaxJpegScans)
        return refuse("with more than " + std::to_string(kMaxJpegScans) + " scans");
      for (;;) {
        const void* ff = pos < size ? std::memchr(data + pos, 0xFF, size - pos) : nullptr;
        if (!ff) return truncated();
        const size_t at = static_cast<size_t>(static_cast<const uint8_t*>(ff) - data);
        size_t next = at + 1;
        while (next < size && data[next] == 0xFF) ++next;
        if (next >= size) return truncated();
        const uint8_t c = data[next];
        if (c == 0x00 || (c >= 0xD0 && c <= 0xD7)) {  // stuffed 0xFF byte, restart marker
          pos = next + 1;
          continue;
        }
        pos = at;  // a real marker: the segment walk takes over
        break;
      }
    }
  }
}

std::optional<Image> image_from_msg(const image_t& m, bool mono, std::string* error) {
  // Everything is validated before OpenCV sees it; this is the last line, so that no input
  // can make a node throw out of a callback (OpenCV asserts, out of memory).
  try {
    return decode_image(m, mono, error);
  } catch (const cv::Exception& e) {
    fail(error, std::string("OpenCV refused the image: ") + e.what());
  } catch (const std::exception& e) {
    fail(error, std::string("image decoding failed: ") + e.what());
  }
  return std::nullopt;
}

image_t image_to_msg(const cv::Mat& pixels, int64_t utime, int64_t seq) {
  CV_Assert(pixels.type() == CV_8UC1 || pixels.type() == CV_8UC3);
  image_t m{};
  m.utime = utime;
  m.width = pixels.cols;
  m.height = pixels.rows;
  m.row_stride = pixels.cols * static_cast<int>(pixels.elemSize());
  m.pixelformat = pixels.channels() == 1 ? int32_t{image_t::PIXEL_FORMAT_GRAY}
                                         : int32_t{image_t::PIXEL_FORMAT_BGR};
  m.data.resize(static_cast<size_t>(m.row_stride) * m.height);
  for (int r = 0; r < pixels.rows; ++r)
    std::memcpy(m.data.data() + static_cast<size_t>(r) * m.row_stride, pixels.ptr(r), m.row_stride);
  m.size = static_cast<int32_t>(m.data.size());
  m.nmetadata = 0;
  if (seq >= 0) set_metadata_int(m, "seq", seq);
  return m;
}

image_t jpeg_image_to_msg(const cv::Mat& pixels, int64_t utime, int quality) {
  image_t m{};
  m.utime = utime;
  m.width = pixels.cols;
  m.height = pixels.rows;
  m.row_stride = 0;
  m.pixelformat = image_t::PIXEL_FORMAT_MJPEG;
  cv::imencode(".jpg", pixels, m.data, {cv::IMWRITE_JPEG_QUALITY, quality});
  m.size = static_cast<int32_t>(m.data.size());
  m.nmetadata = 0;
  return m;
}

namespace {
image_metadata_t* find_entry(image_t& m, const std::string& key) {
  for (auto& e : m.metadata)
    if (e.key == key) return &e;
  m.metadata.emplace_back();
  m.metadata.back().key = key;
  m.nmetadata = static_cast<int32_t>(m.metadata.size());
  return &m.metadata.back();
}
const image_metadata_t* find_entry(const image_t& m, const std::string& key) {
  for (const auto& e : m.metadata)
    if (e.key == key) return &e;
  return nullptr;
}
}  // namespace

void set_metadata_int(image_t& m, const std::string& key, int64_t value) {
  image_metadata_t* e = find_entry(m, key);
  e->value.resize(8);
  for (int i = 0; i < 8; ++i)
    e->value[i] = static_cast<uint8_t>((static_cast<uint64_t>(value) >> (8 * i)) & 0xff);
  e->n = 8;
}

void set_exposure_metadata(image_t& m, double exposure_s) {
  set_metadata_int(m, "exposure_us", std::max<int64_t>(1, std::llround(exposure_s * 1e6)));
}

std::optional<int64_t> metadata_int(const image_t& m, const std::string& key) {
  const image_metadata_t* e = find_entry(m, key);
  if (!e || e->n != 8 || e->value.size() != 8) return std::nullopt;
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<uint64_t>(e->value[i]) << (8 * i);
  return static_cast<int64_t>(v);
}

void set_metadata_string(image_t& m, const std::string& key, const std::string& value) {
  image_metadata_t* e = find_entry(m, key);
  e->value.assign(value.begin(), value.end());
  e->n = static_cast<int32_t>(e->value.size());
}

std::optional<std::string> metadata_string(const image_t& m, const std::string& key) {
  const image_metadata_t* e = find_entry(m, key);
  if (!e || e->n != static_cast<int32_t>(e->value.size())) return std::nullopt;
  return std::string(e->value.begin(), e->value.end());
}

}  // namespace alight
