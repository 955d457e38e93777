// Regressions of image_from_msg under hostile frames (issue 14): sizes that overflow 32-bit
// maths, JPEGs whose header asks for a huge image, JPEGs cut short. Each must be refused with a
// reason, never crash, throw or allocate the size the frame claims.

#include <gtest/gtest.h>

#include <algorithm>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <set>

#include "common/image_msg.hpp"

namespace alight {
namespace {

cv::Mat noise(int w, int h, int type, uint32_t seed) {
  cv::Mat m(h, w, type);
  std::mt19937 rng(seed);
  for (size_t i = 0; i < m.total() * m.elemSize(); ++i) m.data[i] = static_cast<uint8_t>(rng());
  return m;
}

image_t jpeg_msg(const cv::Mat& px, bool progressive = false, int restart_interval = 0) {
  image_t m = jpeg_image_to_msg(px, 7, 90);
  if (progressive || restart_interval > 0) {
    m.data.clear();
    cv::imencode(".jpg", px, m.data,
                 {cv::IMWRITE_JPEG_QUALITY, 90, cv::IMWRITE_JPEG_PROGRESSIVE, progressive ? 1 : 0,
                  cv::IMWRITE_JPEG_RST_INTERVAL, restart_interval});
    m.size = static_cast<int32_t>(m.data.size());
  }
  return m;
}

// Offset of the first frame header (SOF0/SOF2) marker in an encoder's output.
size_t sof_offset(const std::vector<uint8_t>& d) {
  for (size_t i = 0; i + 1 < d.size(); ++i)
    if (d[i] == 0xFF && (d[i + 1] == 0xC0 || d[i + 1] == 0xC2)) return i;
  ADD_FAILURE() << "no SOF marker";
  return 0;
}

TEST(ImageDecodeRegression, RgbWidthThatOverflowsInt32IsRefusedNotFatal) {
  // width * 3 = 0x100000002 wrapped to 2 in int32: a row_stride of 2 passed the check and the
  // frame reached cv::Mat / cvtColor with 1.4 G pixels per row behind 2 bytes of data.
  image_t m{};
  m.utime = 1;
  m.width = 0x55555556;
  m.height = 1;
  m.row_stride = 2;
  m.pixelformat = image_t::PIXEL_FORMAT_RGB;
  m.data = {1, 2};
  m.size = 2;
  std::string err;
  EXPECT_FALSE(image_from_msg(m, true, &err));
  EXPECT_FALSE(err.empty());
  EXPECT_FALSE(image_from_msg(m, false, &err));
  m.pixelformat = image_t::PIXEL_FORMAT_RGBA;
  m.width = 0x40000001;  // x 4 wraps to 4
  m.row_stride = 4;
  m.data = {1, 2, 3, 4};
  m.size = 4;
  EXPECT_FALSE(image_from_msg(m, false, &err));
}

TEST(ImageDecodeRegression, RawImageBeyondTheDeclaredBoundIsRefused) {
  image_t m{};
  m.utime = 1;
  m.width = 8193;  // kMaxImageSide + 1
  m.height = 1;
  m.row_stride = m.width;
  m.pixelformat = image_t::PIXEL_FORMAT_GRAY;
  m.data.assign(m.width, 9);
  m.size = m.width;
  std::string err;
  EXPECT_FALSE(image_from_msg(m, true, &err));
  EXPECT_NE(err.find("exceeds"), std::string::npos) << err;
  // The bound itself is accepted.
  m.width = m.row_stride = m.size = 8192;
  m.data.assign(m.width, 9);
  const auto img = image_from_msg(m, true, &err);
  ASSERT_TRUE(img) << err;
  EXPECT_EQ(img->pixels.cols, 8192);
}

TEST(ImageDecodeRegression, OversizeJpegIsRefusedFromItsHeaderBeforeDecoding) {
  // A few hundred bytes whose frame header says 12000x12000: libjpeg allocated and decoded
  // 144 M pixels (padding the missing data) before any size check looked at the result.
  image_t m = jpeg_msg(cv::Mat(16, 16, CV_8UC1, cv::Scalar(128)));
  const size_t sof = sof_offset(m.data);
  for (size_t k : {sof + 5, sof + 7}) {  // height, width (big-endian)
    m.data[k] = 12000 >> 8;
    m.data[k + 1] = 12000 & 0xff;
  }
  m.width = 0;  // "unknown": the header is all there is to go by
  m.height = 0;
  ASSERT_LT(m.data.size(), 1000u);
  std::string err;
  EXPECT_FALSE(image_from_msg(m, true, &err));
  EXPECT_NE(err.find("12000x12000"), std::string::npos) << err;
  EXPECT_FALSE(image_from_msg(m, false, &err));
}

TEST(ImageDecodeRegression, JpegCutAnywhereBeforeItsEndIsRefused) {
  // cv::imdecode accepts a JPEG cut to a third: libjpeg warns and pads the missing rows grey.
  // Every cut point of baseline, restart-marker and progressive encodings, colour and mono.
  struct Case {
    const char* name;
    image_t msg;
  };
  const std::vector<Case> cases = {
      {"baseline colour", jpeg_msg(noise(160, 120, CV_8UC3, 1))},
      {"baseline mono", jpeg_msg(noise(160, 120, CV_8UC1, 2))},
      {"restart markers", jpeg_msg(noise(160, 120, CV_8UC3, 3), false, 2)},
      {"progressive", jpeg_msg(noise(160, 120, CV_8UC3, 4), true)},
  };
  for (const auto& c : cases) {
    std::string err;
    ASSERT_TRUE(image_from_msg(c.msg, true, &err)) << c.name << ": " << err;
    const size_t n = c.msg.data.size();
    // Every byte of the headers and of the tail, and about 400 cuts in between.
    std::set<size_t> cuts;
    for (size_t k = 1; k < std::min<size_t>(n, 700); ++k) cuts.insert(k);
    for (size_t k = n > 64 ? n - 64 : 1; k < n; ++k) cuts.insert(k);
    for (size_t k = 1; k < n; k += std::max<size_t>(1, n / 400)) cuts.insert(k);
    cuts.insert(n / 3);
    int accepted = 0;
    for (size_t cut : cuts) {
      image_t t = c.msg;
      t.data.resize(cut);
      t.size = static_cast<int32_t>(cut);
      if (image_from_msg(t, true, &err)) {
        ++accepted;
        ADD_FAILURE() << c.name << ": cut at " << cut << " of " << n << " bytes accepted";
        if (accepted > 5) break;
      }
    }
    EXPECT_EQ(accepted, 0) << c.name;
  }
}

TEST(ImageDecodeRegression, JpegCutToAThirdIsRefusedAsTruncated) {
  image_t m = jpeg_msg(noise(320, 240, CV_8UC1, 5));
  m.data.resize(m.data.size() / 3);
  m.size = static_cast<int32_t>(m.data.size());
  std::string err;
  EXPECT_FALSE(image_from_msg(m, true, &err));
  EXPECT_NE(err.find("truncated"), std::string::npos) << err;
}

TEST(ImageDecodeTest, CompleteJpegWithPaddingAfterItsEndIsAccepted) {
  // Some UVC cameras deliver MJPEG buffers padded with zeros after EOI.
  const cv::Mat px = noise(64, 48, CV_8UC1, 6);
  image_t m = jpeg_msg(px);
  m.data.resize(m.data.size() + 100, 0);
  m.size = static_cast<int32_t>(m.data.size());
  std::string err;
  const auto img = image_from_msg(m, true, &err);
  ASSERT_TRUE(img) << err;
  EXPECT_EQ(img->pixels.size(), px.size());
}

TEST(ImageDecodeTest, JpegDisagreeingWithTheMessageSizeIsRefusedBeforeDecoding) {
  image_t m = jpeg_msg(noise(64, 48, CV_8UC1, 7));
  m.width = 48;
  m.height = 64;
  std::string err;
  EXPECT_FALSE(image_from_msg(m, true, &err));
  EXPECT_NE(err.find("64x48"), std::string::npos) << err;
}

TEST(ImageDecodeTest, JpegInfoReadsTheHeaderOfEveryEncoding) {
  std::string err;
  const image_t mono = jpeg_msg(noise(160, 120, CV_8UC1, 8));
  auto info = jpeg_info(mono.data.data(), mono.data.size(), &err);
  ASSERT_TRUE(info) << err;
  EXPECT_EQ(info->width, 160);
  EXPECT_EQ(info->height, 120);
  EXPECT_EQ(info->components, 1);
  EXPECT_EQ(info->scans, 1);
  const image_t prog = jpeg_msg(noise(100, 30, CV_8UC3, 9), true);
  info = jpeg_info(prog.data.data(), prog.data.size(), &err);
  ASSERT_TRUE(info) << err;
  EXPECT_EQ(info->width, 100);
  EXPECT_EQ(info->height, 30);
  EXPECT_EQ(info->components, 3);
  EXPECT_GT(info->scans, 1);
  const image_t rst = jpeg_msg(noise(100, 30, CV_8UC3, 10), false, 1);
  ASSERT_TRUE(jpeg_info(rst.data.data(), rst.data.size(), &err)) << err;
}

TEST(ImageDecodeTest, JpegInfoRefusesMalformedHeaders) {
  std::string err;
  const image_t ok = jpeg_msg(noise(32, 32, CV_8UC1, 11));
  const size_t sof = sof_offset(ok.data);
  {
    image_t m = ok;  // 12-bit samples
    m.data[sof + 4] = 12;
    EXPECT_FALSE(jpeg_info(m.data.data(), m.data.size(), &err));
  }
  {
    image_t m = ok;  // height 0 (to be defined by a DNL segment: not supported)
    m.data[sof + 5] = m.data[sof + 6] = 0;
    EXPECT_FALSE(jpeg_info(m.data.data(), m.data.size(), &err));
  }
  {
    image_t m = ok;  // a segment length running past the end
    m.data[sof + 2] = 0xFF;
    EXPECT_FALSE(jpeg_info(m.data.data(), m.data.size(), &err));
  }
  {
    image_t m = ok;  // lossless (SOF3) instead of baseline
    m.data[sof + 1] = 0xC3;
    EXPECT_FALSE(jpeg_info(m.data.data(), m.data.size(), &err));
    EXPECT_NE(err.find("SOF3"), std::string::npos) << err;
  }
  const uint8_t soi_eoi[] = {0xFF, 0xD8, 0xFF, 0xD9};
  EXPECT_FALSE(jpeg_info(soi_eoi, sizeof soi_eoi, &err));
  EXPECT_FALSE(jpeg_info(soi_eoi, 0, &err));
}

}  // namespace
}  // namespace alight
