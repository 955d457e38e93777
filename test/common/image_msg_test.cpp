#include "common/image_msg.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <opencv2/imgproc.hpp>

namespace alight {
namespace {

cv::Mat gradient(int w, int h) {
  cv::Mat m(h, w, CV_8UC1);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) m.at<uint8_t>(r, c) = static_cast<uint8_t>((r * 3 + c * 7) & 0xff);
  return m;
}

image_t encode_decode(const image_t& in) {
  std::vector<uint8_t> buf(in.getEncodedSize());
  EXPECT_EQ(in.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  image_t out;
  EXPECT_EQ(out.decode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  return out;
}

TEST(ImageMsgTest, MonoImageRoundTripThroughLcmEncoding) {
  const cv::Mat px = gradient(640, 480);
  const image_t msg = encode_decode(image_to_msg(px, 99, 7));
  EXPECT_EQ(msg.pixelformat, image_t::PIXEL_FORMAT_GRAY);
  EXPECT_EQ(metadata_int(msg, "seq"), 7);
  std::string err;
  const auto img = image_from_msg(msg, true, &err);
  ASSERT_TRUE(img) << err;
  EXPECT_EQ(img->utime, 99);
  EXPECT_EQ(img->seq, 7);
  EXPECT_EQ(cv::norm(img->pixels, px, cv::NORM_INF), 0.0);
}

// The exposure a camera publishes reaches the vision's blur guard; a frame without one says
// nothing, and one that gives an impossible exposure is refused with the value named.
TEST(ImageMsgTest, ExposureMetadataIsReadAndCheckedAtTheBoundary) {
  image_t msg = image_to_msg(gradient(64, 48), 99, 7);
  std::string err;
  EXPECT_EQ(image_from_msg(msg, true, &err)->exposure_s, std::nullopt);
  set_metadata_int(msg, "exposure_us", 8000);
  const auto img = image_from_msg(encode_decode(msg), true, &err);
  ASSERT_TRUE(img) << err;
  ASSERT_TRUE(img->exposure_s);
  EXPECT_DOUBLE_EQ(*img->exposure_s, 0.008);
  // The writers' helper: whole microseconds, never 0.
  set_exposure_metadata(msg, 0.0123456);
  EXPECT_EQ(metadata_int(msg, "exposure_us"), 12346);
  set_exposure_metadata(msg, 1e-9);
  EXPECT_DOUBLE_EQ(*image_from_msg(msg, true, &err)->exposure_s, 1e-6);
  for (const int64_t bad : {int64_t{0}, int64_t{-5}, kMaxExposureUs + 1, INT64_MIN}) {
    set_metadata_int(msg, "exposure_us", bad);
    err.clear();
    EXPECT_FALSE(image_from_msg(msg, true, &err)) << bad;
    EXPECT_NE(err.find("exposure_us metadata of " + std::to_string(bad)), std::string::npos) << err;
  }
}

TEST(ImageMsgTest, ColourImageDecodesToMonoOrBgr) {
  cv::Mat bgr(48, 64, CV_8UC3, cv::Scalar(10, 100, 200));
  const image_t msg = image_to_msg(bgr, 1);
  std::string err;
  const auto mono = image_from_msg(msg, true, &err);
  ASSERT_TRUE(mono) << err;
  EXPECT_EQ(mono->pixels.type(), CV_8UC1);
  cv::Mat expected;
  cv::cvtColor(bgr, expected, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(cv::norm(mono->pixels, expected, cv::NORM_INF), 0.0);
  const auto colour = image_from_msg(msg, false, &err);
  ASSERT_TRUE(colour);
  EXPECT_EQ(cv::norm(colour->pixels, bgr, cv::NORM_INF), 0.0);
}

TEST(ImageMsgTest, RgbIsSwappedToBgr) {
  image_t msg = image_to_msg(cv::Mat(2, 2, CV_8UC3, cv::Scalar(1, 2, 3)), 1);
  msg.pixelformat = image_t::PIXEL_FORMAT_RGB;
  const auto img = image_from_msg(msg, false, nullptr);
  ASSERT_TRUE(img);
  EXPECT_EQ(img->pixels.at<cv::Vec3b>(0, 0), cv::Vec3b(3, 2, 1));
}

TEST(ImageMsgTest, JpegRoundTripIsClose) {
  const cv::Mat px = gradient(320, 240);
  const image_t msg = encode_decode(jpeg_image_to_msg(px, 5, 95));
  EXPECT_EQ(msg.pixelformat, image_t::PIXEL_FORMAT_MJPEG);
  std::string err;
  const auto img = image_from_msg(msg, true, &err);
  ASSERT_TRUE(img) << err;
  EXPECT_LT(cv::norm(img->pixels, px, cv::NORM_L1) / px.total(), 3.0);
}

TEST(ImageMsgTest, TruncatedDataIsRejectedWithAReason) {
  image_t msg = image_to_msg(gradient(64, 48), 1);
  msg.data.resize(100);
  msg.size = 100;
  std::string err;
  EXPECT_FALSE(image_from_msg(msg, true, &err));
  EXPECT_NE(err.find("needed"), std::string::npos) << err;
}

TEST(ImageMsgTest, SizeFieldDisagreeingWithDataIsRejected) {
  image_t msg = image_to_msg(gradient(64, 48), 1);
  msg.size = 5;
  std::string err;
  EXPECT_FALSE(image_from_msg(msg, true, &err));
}

TEST(ImageMsgTest, NonPositiveSizeAndBadStrideAreRejected) {
  image_t msg = image_to_msg(gradient(64, 48), 1);
  msg.row_stride = 10;
  std::string err;
  EXPECT_FALSE(image_from_msg(msg, true, &err));
  EXPECT_NE(err.find("row_stride"), std::string::npos);
  msg.row_stride = 64;
  msg.width = 0;
  EXPECT_FALSE(image_from_msg(msg, true, &err));
}

TEST(ImageMsgTest, GarbageJpegIsRejected) {
  image_t msg = jpeg_image_to_msg(gradient(32, 32), 1);
  for (auto& b : msg.data) b = 0x55;
  std::string err;
  EXPECT_FALSE(image_from_msg(msg, true, &err));
  EXPECT_NE(err.find("JPEG"), std::string::npos);
}

TEST(ImageMsgTest, UnsupportedFormatIsNamed) {
  image_t msg = image_to_msg(gradient(8, 8), 1);
  msg.pixelformat = image_t::PIXEL_FORMAT_BAYER_RGGB;
  std::string err;
  EXPECT_FALSE(image_from_msg(msg, true, &err));
  EXPECT_NE(err.find(std::to_string(image_t::PIXEL_FORMAT_BAYER_RGGB)), std::string::npos);
}

TEST(ImageMsgTest, MetadataStringsAndOverwrite) {
  image_t msg = image_to_msg(gradient(8, 8), 1, 3);
  set_metadata_int(msg, "seq", 4);
  set_metadata_string(msg, "camera", "firefly");
  const image_t back = encode_decode(msg);
  EXPECT_EQ(back.nmetadata, 2);
  EXPECT_EQ(metadata_int(back, "seq"), 4);
  EXPECT_EQ(metadata_string(back, "camera"), "firefly");
  EXPECT_FALSE(metadata_int(back, "missing").has_value());
}

}  // namespace
}  // namespace alight
