#include "common/msg_convert.hpp"

#include <cmath>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace alight {

PoseSample from_msg(const pose_t& m) {
  PoseSample s;
  s.utime = m.utime;
  s.p_W_B = Vector3d(m.pos[0], m.pos[1], m.pos[2]);
  s.v_W_B = Vector3d(m.vel[0], m.vel[1], m.vel[2]);
  s.q_WB = quat_from_wxyz(m.orientation);
  s.omega_B = Vector3d(m.angular_velocity_B[0], m.angular_velocity_B[1], m.angular_velocity_B[2]);
  return s;
}

pose_t to_msg(const PoseSample& s, int64_t seq) {
  pose_t m{};
  m.utime = s.utime;
  m.seq = seq;
  for (int i = 0; i < 3; ++i) {
    m.pos[i] = s.p_W_B[i];
    m.vel[i] = s.v_W_B[i];
    m.angular_velocity_B[i] = s.omega_B[i];
  }
  quat_to_wxyz(s.q_WB, m.orientation);
  m.status = pose_t::STATUS_OK;
  return m;
}

std::optional<PoseSample> pose_from_msg(const pose_t& m, std::string* why) {
  const auto refuse = [&](const std::string& text) -> std::optional<PoseSample> {
    if (why) *why = text;
    return std::nullopt;
  };
  const auto all_finite = [](const double* v, int n) {
    for (int i = 0; i < n; ++i)
      if (!std::isfinite(v[i])) return false;
    return true;
  };
  if (!all_finite(m.pos, 3)) return refuse("pose: non-finite position");
  if (!all_finite(m.vel, 3)) return refuse("pose: non-finite velocity");
  if (!all_finite(m.orientation, 4)) return refuse("pose: non-finite orientation");
  if (!all_finite(m.angular_velocity_B, 3)) return refuse("pose: non-finite angular velocity");
  const double q_norm = std::sqrt(m.orientation[0] * m.orientation[0] +
                                  m.orientation[1] * m.orientation[1] +
                                  m.orientation[2] * m.orientation[2] +
                                  m.orientation[3] * m.orientation[3]);
  // Not a rotation: a sender's bug or a corrupted message, never renormalised into one.
  if (!(std::abs(q_norm - 1.0) <= 0.01))
    return refuse("pose: orientation quaternion norm " + std::to_string(q_norm) + " is not 1");
  return from_msg(m);
}

namespace {
bool fail(std::string* error, const std::string& text) {
  if (error) *error = text;
  return false;
}

// Checks the raw-format fields against the data size before any pixel is touched.
bool check_raw(const image_t& m, int bytes_per_pixel, std::string* error) {
  if (m.width <= 0 || m.height <= 0)
    return fail(error, "image size " + std::to_string(m.width) + "x" + std::to_string(m.height) +
                           " is not positive");
  if (m.row_stride < m.width * bytes_per_pixel)
    return fail(error, "row_stride " + std::to_string(m.row_stride) + " < width x " +
                           std::to_string(bytes_per_pixel) + " bytes");
  const int64_t needed = static_cast<int64_t>(m.row_stride) * m.height;
  if (m.size != static_cast<int32_t>(m.data.size()) || m.size < needed)
    return fail(error, "data holds " + std::to_string(m.data.size()) + " bytes (size field " +
                           std::to_string(m.size) + "), " + std::to_string(needed) + " needed");
  return true;
}
}  // namespace

std::optional<Image> image_from_msg(const image_t& m, bool mono, std::string* error) {
  Image img;
  img.utime = m.utime;
  img.seq = metadata_int(m, "seq").value_or(-1);
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
    case image_t::PIXEL_FORMAT_MJPEG: {
      if (m.size != static_cast<int32_t>(m.data.size()) || m.data.empty()) {
        fail(error, "JPEG frame with size field " + std::to_string(m.size) + " and " +
                        std::to_string(m.data.size()) + " data bytes");
        return std::nullopt;
      }
      img.pixels = cv::imdecode(m.data, mono ? cv::IMREAD_GRAYSCALE : cv::IMREAD_COLOR);
      if (img.pixels.empty()) {
        fail(error, "JPEG data could not be decoded");
        return std::nullopt;
      }
      if (m.width > 0 && (img.pixels.cols != m.width || img.pixels.rows != m.height)) {
        fail(error, "JPEG is " + std::to_string(img.pixels.cols) + "x" +
                        std::to_string(img.pixels.rows) + " but the message says " +
                        std::to_string(m.width) + "x" + std::to_string(m.height));
        return std::nullopt;
      }
      return img;
    }
    default:
      fail(error, "unsupported pixel format " + std::to_string(m.pixelformat));
      return std::nullopt;
  }
  if (!check_raw(m, raw.bpp, error)) return std::nullopt;
  const cv::Mat view(m.height, m.width, CV_8UC(raw.bpp), const_cast<uint8_t*>(m.data.data()),
                     m.row_stride);
  const int code = mono ? raw.to_gray : raw.to_bgr;
  if (code >= 0) {
    cv::cvtColor(view, img.pixels, code);
  } else {
    img.pixels = view.clone();  // the message's buffer does not outlive the callback
  }
  return img;
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
