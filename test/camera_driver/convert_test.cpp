// Conversion on known images: YUYV built by hand from the BT.601 definition, MJPEG from
// OpenCV's own encoder, GREY with padded rows; short buffers are errors, not crashes.

#include "camera_driver/convert.hpp"

#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace alight::camera {
namespace {

cv::Mat gradient_gray(int w, int h) {
  cv::Mat g(h, w, CV_8UC1);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) g.at<uint8_t>(r, c) = static_cast<uint8_t>((3 * c + 5 * r) % 256);
  return g;
}

// A colour test card: smooth gradients plus a few flat colour blocks.
cv::Mat colour_card(int w, int h) {
  cv::Mat bgr(h, w, CV_8UC3);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c)
      bgr.at<cv::Vec3b>(r, c) =
          cv::Vec3b(static_cast<uint8_t>(c * 255 / w), static_cast<uint8_t>(r * 255 / h),
                    static_cast<uint8_t>(255 - c * 255 / w));
  cv::rectangle(bgr, cv::Rect(10, 10, 40, 40), cv::Scalar(0, 0, 255), cv::FILLED);
  cv::rectangle(bgr, cv::Rect(60, 10, 40, 40), cv::Scalar(0, 255, 0), cv::FILLED);
  return bgr;
}

uint8_t clamp8(double v) { return static_cast<uint8_t>(std::clamp(std::lround(v), 0L, 255L)); }

// YUYV (Y0 U Y1 V) by the BT.601 studio-range definition, U and V averaged over the pixel pair.
std::vector<uint8_t> yuyv_from_bgr(const cv::Mat& bgr, int stride) {
  std::vector<uint8_t> out(static_cast<size_t>(stride) * bgr.rows, 0xEE);
  for (int r = 0; r < bgr.rows; ++r) {
    for (int c = 0; c < bgr.cols; c += 2) {
      double y[2], u = 0, v = 0;
      for (int k = 0; k < 2; ++k) {
        const cv::Vec3b p = bgr.at<cv::Vec3b>(r, c + k);
        const double R = p[2], G = p[1], B = p[0];
        y[k] = 16 + (65.481 * R + 128.553 * G + 24.966 * B) / 255.0;
        u += (128 + (-37.797 * R - 74.203 * G + 112.0 * B) / 255.0) / 2;
        v += (128 + (112.0 * R - 93.786 * G - 18.214 * B) / 255.0) / 2;
      }
      uint8_t* q = out.data() + static_cast<size_t>(r) * stride + 2 * c;
      q[0] = clamp8(y[0]), q[1] = clamp8(u), q[2] = clamp8(y[1]), q[3] = clamp8(v);
    }
  }
  return out;
}

TEST(ConvertTest, GreyWithPaddedRowsIsCopiedExactly) {
  const cv::Mat g = gradient_gray(64, 48);
  const int stride = 80;  // drivers may pad rows
  std::vector<uint8_t> buf(static_cast<size_t>(stride) * 48, 0xAB);
  for (int r = 0; r < 48; ++r) std::memcpy(buf.data() + r * stride, g.ptr(r), 64);
  cv::Mat out;
  std::string err;
  ASSERT_TRUE(convert_frame({buf.data(), buf.size(), 64, 48, stride, PixelFormat::kGrey},
                            OutputEncoding::kMono8, out, &err))
      << err;
  EXPECT_EQ(cv::norm(out, g, cv::NORM_INF), 0.0);
  EXPECT_TRUE(out.isContinuous());
}

TEST(ConvertTest, YuyvOfAGrayImageGivesBackItsLumaExactly) {
  // A gray pixel has U = V = 128 and Y = the gray value: build the YUYV bytes directly.
  const cv::Mat g = gradient_gray(64, 48);
  std::vector<uint8_t> buf(64 * 2 * 48);
  for (int r = 0; r < 48; ++r)
    for (int c = 0; c < 64; ++c) {
      buf[r * 128 + 2 * c] = g.at<uint8_t>(r, c);
      buf[r * 128 + 2 * c + 1] = 128;
    }
  cv::Mat out;
  std::string err;
  ASSERT_TRUE(convert_frame({buf.data(), buf.size(), 64, 48, 128, PixelFormat::kYuyv},
                            OutputEncoding::kMono8, out, &err));
  EXPECT_EQ(cv::norm(out, g, cv::NORM_INF), 0.0);
}

TEST(ConvertTest, YuyvOfAColourImageGivesBackItsColours) {
  const cv::Mat bgr = colour_card(128, 96);
  const int stride = 128 * 2 + 16;
  const auto buf = yuyv_from_bgr(bgr, stride);
  cv::Mat rgb, bgr_out, mono;
  std::string err;
  const RawFrameView view{buf.data(), buf.size(), 128, 96, stride, PixelFormat::kYuyv};
  ASSERT_TRUE(convert_frame(view, OutputEncoding::kRgb8, rgb, &err)) << err;
  ASSERT_TRUE(convert_frame(view, OutputEncoding::kBgr8, bgr_out, &err)) << err;
  ASSERT_TRUE(convert_frame(view, OutputEncoding::kMono8, mono, &err)) << err;
  cv::Mat rgb_ref;
  cv::cvtColor(bgr, rgb_ref, cv::COLOR_BGR2RGB);
  // Chroma is shared by pixel pairs and quantised: colours come back within a few levels where
  // neighbours agree (the flat blocks), and within ~5 levels on average over the gradients.
  const cv::Rect red(12, 12, 36, 36);
  EXPECT_LE(cv::norm(rgb(red), rgb_ref(red), cv::NORM_INF), 3.0);
  EXPECT_LE(cv::norm(bgr_out(red), bgr(red), cv::NORM_INF), 3.0);
  EXPECT_LE(cv::norm(rgb, rgb_ref, cv::NORM_L1) / rgb.total() / 3, 5.0);
  // The red block is red: R high, G and B low, in RGB order.
  const cv::Vec3b p = rgb.at<cv::Vec3b>(30, 30);
  EXPECT_GT(p[0], 240);
  EXPECT_LT(p[1], 15);
  EXPECT_LT(p[2], 15);
  // Mono is the luma channel, which maps studio-range Y back to the pixel's gray level.
  cv::Mat gray_ref;
  cv::cvtColor(bgr, gray_ref, cv::COLOR_BGR2GRAY);
  const cv::Rect flat(62, 12, 36, 36);
  EXPECT_LE(cv::norm(mono(flat), gray_ref(flat), cv::NORM_L1) / flat.area(), 20.0);
}

TEST(ConvertTest, YuyvMonoIsTheYBytes) {
  // Whatever the chroma, mono8 from YUYV is the Y samples as sent.
  std::vector<uint8_t> buf(16 * 2 * 4);
  for (size_t i = 0; i < buf.size(); ++i) buf[i] = static_cast<uint8_t>(i * 37 + 11);
  cv::Mat out;
  ASSERT_TRUE(convert_frame({buf.data(), buf.size(), 16, 4, 32, PixelFormat::kYuyv},
                            OutputEncoding::kMono8, out, nullptr));
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 16; ++c) ASSERT_EQ(out.at<uint8_t>(r, c), buf[r * 32 + 2 * c]);
}

TEST(ConvertTest, MjpegFromOpenCvsEncoderDecodesToTheImage) {
  const cv::Mat bgr = colour_card(160, 120);
  std::vector<uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, 95}));
  cv::Mat mono, rgb;
  std::string err;
  const RawFrameView view{jpeg.data(), jpeg.size(), 160, 120, 0, PixelFormat::kMjpeg};
  ASSERT_TRUE(convert_frame(view, OutputEncoding::kMono8, mono, &err)) << err;
  ASSERT_TRUE(convert_frame(view, OutputEncoding::kRgb8, rgb, &err)) << err;
  ASSERT_EQ(mono.type(), CV_8UC1);
  ASSERT_EQ(rgb.type(), CV_8UC3);
  cv::Mat gray_ref, rgb_ref;
  cv::cvtColor(bgr, gray_ref, cv::COLOR_BGR2GRAY);
  cv::cvtColor(bgr, rgb_ref, cv::COLOR_BGR2RGB);
  EXPECT_LE(cv::norm(mono, gray_ref, cv::NORM_L1) / mono.total(), 2.0);
  EXPECT_LE(cv::norm(rgb, rgb_ref, cv::NORM_L1) / rgb.total() / 3, 3.0);
}

TEST(ConvertTest, ShortOrCorruptBuffersAreErrorsNotCrashes) {
  std::vector<uint8_t> buf(640 * 479);
  cv::Mat out;
  std::string err;
  EXPECT_FALSE(convert_frame({buf.data(), buf.size(), 640, 480, 640, PixelFormat::kGrey},
                             OutputEncoding::kMono8, out, &err));
  EXPECT_NE(err.find("needed"), std::string::npos) << err;
  EXPECT_FALSE(convert_frame({buf.data(), buf.size(), 640, 480, 1280, PixelFormat::kYuyv},
                             OutputEncoding::kMono8, out, &err));
  EXPECT_FALSE(convert_frame({buf.data(), 1000, 640, 480, 0, PixelFormat::kMjpeg},
                             OutputEncoding::kMono8, out, &err));
  EXPECT_NE(err.find("decoded"), std::string::npos) << err;
  // A valid JPEG of another size than negotiated.
  std::vector<uint8_t> jpeg;
  cv::imencode(".jpg", gradient_gray(64, 48), jpeg);
  EXPECT_FALSE(convert_frame({jpeg.data(), jpeg.size(), 640, 480, 0, PixelFormat::kMjpeg},
                             OutputEncoding::kMono8, out, &err));
  EXPECT_NE(err.find("64x48"), std::string::npos) << err;
}

TEST(ConvertTest, FourccNamesRoundTrip) {
  for (auto f : {PixelFormat::kGrey, PixelFormat::kYuyv, PixelFormat::kMjpeg}) {
    EXPECT_EQ(pixel_format_from_fourcc(fourcc(f)), f);
    EXPECT_EQ(parse_pixel_format(to_string(f)), f);
  }
  EXPECT_EQ(fourcc_text(V4L2_PIX_FMT_YUYV), "YUYV");
  EXPECT_FALSE(parse_pixel_format("NV12"));
}

}  // namespace
}  // namespace alight::camera
