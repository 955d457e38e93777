// The plane-induced parallax image (vision/geometry/warp_diff.hpp) on synthetic images with known
// answers: identity and whole-pixel shifts give plain differences, a half-pixel shift the mean
// of two neighbours, what the reference did not see (outside it, behind the camera) differs by
// 0, the AVX2 and scalar variants agree bit for bit, and a perspective warp agrees with
// cv::warpPerspective away from the reference's border.
#include "vision/geometry/warp_diff.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

namespace alight::vision {
namespace {

cv::Mat noise(int rows, int cols, uint64_t seed) {
  cv::Mat m(rows, cols, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(m, cv::RNG::UNIFORM, 0, 256);
  return m;
}

int abs_diff(int a, int b) { return a > b ? a - b : b - a; }

TEST(WarpAbsDiffTest, IdentityIsThePlainDifference) {
  const cv::Mat a = noise(48, 70, 1), b = noise(48, 70, 2);
  const cv::Mat d = warp_abs_diff(a, b, Matrix3d::Identity());
  cv::Mat expected;
  cv::absdiff(a, b, expected);
  EXPECT_EQ(cv::countNonZero(d != expected), 0);
}

TEST(WarpAbsDiffTest, WholePixelShiftAndUnseenPixels) {
  // The current pixel (u, v) sees the reference at (u + 3, v - 2).
  const cv::Mat a = noise(40, 64, 3), b = noise(40, 64, 4);
  Matrix3d H_12 = Matrix3d::Identity();
  H_12(0, 2) = 3, H_12(1, 2) = -2;
  const cv::Mat d = warp_abs_diff(a, b, H_12);
  for (int v = 0; v < a.rows; ++v)
    for (int u = 0; u < a.cols; ++u) {
      const int x = u + 3, y = v - 2;
      const bool seen = x < b.cols && y >= 0;
      const int expected = seen ? abs_diff(a.at<uint8_t>(v, u), b.at<uint8_t>(y, x)) : 0;
      ASSERT_EQ(d.at<uint8_t>(v, u), expected) << "at " << u << ", " << v;
    }
}

TEST(WarpAbsDiffTest, HalfPixelShiftIsTheRoundedMeanOfTheNeighbours) {
  const cv::Mat a = noise(20, 40, 5), b = noise(20, 40, 6);
  Matrix3d H_12 = Matrix3d::Identity();
  H_12(0, 2) = 0.5;
  const cv::Mat d = warp_abs_diff(a, b, H_12);
  for (int v = 0; v < a.rows; ++v)
    for (int u = 0; u + 1 < a.cols; ++u) {
      const int mean = (b.at<uint8_t>(v, u) + b.at<uint8_t>(v, u + 1) + 1) / 2;
      ASSERT_EQ(d.at<uint8_t>(v, u), abs_diff(a.at<uint8_t>(v, u), mean)) << u << ", " << v;
    }
  // The last column looks half a pixel past the reference's last pixel centre: not seen.
  for (int v = 0; v < a.rows; ++v) EXPECT_EQ(d.at<uint8_t>(v, a.cols - 1), 0);
}

TEST(WarpAbsDiffTest, BehindTheCameraIsUnseen) {
  // w = 1 - u / 100: the columns from 100 on map behind the camera.
  const cv::Mat a(30, 160, CV_8UC1, cv::Scalar(200)), b(30, 160, CV_8UC1, cv::Scalar(10));
  Matrix3d H_12 = Matrix3d::Identity();
  H_12(2, 0) = -0.01;
  const cv::Mat d = warp_abs_diff(a, b, H_12);
  for (int v = 0; v < a.rows; ++v)
    for (int u = 100; u < a.cols; ++u) ASSERT_EQ(d.at<uint8_t>(v, u), 0) << u << ", " << v;
  EXPECT_EQ(d.at<uint8_t>(0, 0), 190);
}

// A perspective homography with every kind of pixel in view: seen, off each side, far away.
Matrix3d perspective(double scale) {
  Matrix3d H_21;
  H_21 << 1.01 * scale, 0.02, 3.5, -0.01, 0.99 * scale, -2.25, 1.2e-4, -4e-5, 1.0;
  return H_21.inverse();
}

TEST(WarpAbsDiffTest, Avx2AndScalarAgreeBitForBit) {
  for (const uint64_t seed : {7, 8}) {
    const cv::Mat a = noise(480, 640, seed), b = noise(480, 640, seed + 10);
    for (const double scale : {0.8, 1.0, 1.3}) {
      const cv::Mat fast = warp_abs_diff(a, b, perspective(scale));
      const cv::Mat scalar = warp_abs_diff_scalar(a, b, perspective(scale));
      EXPECT_EQ(cv::countNonZero(fast != scalar), 0) << "seed " << seed << " scale " << scale;
    }
  }
  // Odd sizes: rows that end between knots, a reference read up to its last byte.
  const cv::Mat a = noise(37, 53, 9), b = noise(37, 53, 10);
  Matrix3d shift = Matrix3d::Identity();
  shift(0, 2) = 0.7, shift(1, 2) = 0.3;
  EXPECT_EQ(cv::countNonZero(warp_abs_diff(a, b, shift) != warp_abs_diff_scalar(a, b, shift)), 0);
}

TEST(WarpAbsDiffTest, AgreesWithWarpPerspectiveAwayFromTheBorder) {
  cv::Mat a = noise(480, 640, 11), b = noise(480, 640, 12);
  cv::GaussianBlur(a, a, cv::Size(), 1.5);  // smooth, as the off-wall mask's images
  cv::GaussianBlur(b, b, cv::Size(), 1.5);
  for (const double scale : {0.9, 1.0, 1.1}) {
    const Matrix3d H_12 = perspective(scale), H_21 = H_12.inverse();
    cv::Mat H(3, 3, CV_64F), warped, seen, expected;
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) H.at<double>(r, k) = H_21(r, k);
    cv::warpPerspective(b, warped, H, b.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    cv::warpPerspective(cv::Mat(b.size(), CV_8UC1, cv::Scalar(255)), seen, H, b.size(),
                        cv::INTER_NEAREST, cv::BORDER_CONSTANT);
    cv::absdiff(a, warped, expected);
    // Two pixels inside the seen region and the image: warpPerspective blends what lies past
    // the reference's outermost pixel centres with black, warp_abs_diff repeats them.
    cv::erode(seen, seen, cv::Mat(), cv::Point(-1, -1), 2, cv::BORDER_CONSTANT, cv::Scalar(0));
    const cv::Mat d = warp_abs_diff(a, b, H_12);
    cv::Mat gap;
    cv::absdiff(d, expected, gap);
    gap.setTo(0, seen == 0);
    double worst = 0;
    cv::minMaxLoc(gap, nullptr, &worst);
    EXPECT_LE(worst, 1.0) << "scale " << scale;  // rounding of the sub-pixel position only
    EXPECT_GT(cv::countNonZero(seen), 200000);
  }
}

}  // namespace
}  // namespace alight::vision
