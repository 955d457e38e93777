// The plane-induced parallax image (vision/geometry/warp_diff.hpp) on synthetic images with known
// answers: identity and whole-pixel shifts give plain differences, a half-pixel shift the mean
// of two neighbours, what the reference did not see (outside it, behind the camera) differs by
// 0, the AVX2 and scalar variants agree bit for bit, and a perspective warp agrees with
// cv::warpPerspective away from the reference's border; the map given on a grid of nodes (a lens)
// gives cv::remap's own difference, with what it did not see at 0.
#include "vision/geometry/warp_diff.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <tuple>
#include <vector>

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

// The grid's map written out pixel by pixel, sampled by cv::remap, unseen where cv::remap's
// nearest neighbour finds nothing: what grid_remap_abs_diff must give bit for bit.
cv::Mat remap_difference_by_hand(const cv::Mat& a, const cv::Mat& b, const std::vector<float>& nx,
                                 const std::vector<float>& ny, int gw, int step) {
  const int gh = static_cast<int>(nx.size()) / gw;
  cv::Mat map_x(a.size(), CV_32FC1), map_y(a.size(), CV_32FC1);
  for (int v = 0; v < a.rows; ++v)
    for (int u = 0; u < a.cols; ++u) {
      const int i = std::min(u / step, gw - 2), j = std::min(v / step, gh - 2);
      const float x0 = i * step, x1 = std::min((i + 1) * step, a.cols - 1);
      const float y0 = j * step, y1 = std::min((j + 1) * step, a.rows - 1);
      const float fx = (u - x0) / (x1 - x0), fy = (v - y0) / (y1 - y0);
      const auto lerp = [&](const std::vector<float>& n) {
        return (1 - fy) * ((1 - fx) * n[j * gw + i] + fx * n[j * gw + i + 1]) +
               fy * ((1 - fx) * n[(j + 1) * gw + i] + fx * n[(j + 1) * gw + i + 1]);
      };
      map_x.at<float>(v, u) = lerp(nx);
      map_y.at<float>(v, u) = lerp(ny);
    }
  cv::Mat warped, seen, diff;
  cv::remap(b, warped, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  cv::remap(cv::Mat(b.size(), CV_8UC1, cv::Scalar(255)), seen, map_x, map_y, cv::INTER_NEAREST,
            cv::BORDER_CONSTANT);
  cv::absdiff(a, warped, diff);
  diff.setTo(0, seen == 0);
  return diff;
}

TEST(GridRemapAbsDiffTest, IsCvRemapsDifferenceOfTheBilinearMapBitForBit) {
  for (const auto& [rows, cols, step] : {std::tuple{480, 640, 8}, std::tuple{61, 83, 4},
                                         std::tuple{37, 41, 2}, std::tuple{20, 30, 7}}) {
    const cv::Mat a = noise(rows, cols, 21), b = noise(rows, cols, 22);
    const int gw = (cols - 1 + step - 1) / step + 1, gh = (rows - 1 + step - 1) / step + 1;
    std::vector<float> nx(gw * gh), ny(gw * gh);
    cv::RNG rng(23);
    for (int j = 0; j < gh; ++j)
      for (int i = 0; i < gw; ++i) {
        // A barrel-like bend, shifted so part of the view leaves the reference, exact ties at
        // the border's half pixels, and a node that sees nothing.
        const double x = std::min(i * step, cols - 1), y = std::min(j * step, rows - 1);
        const double r2 =
            std::pow((x - cols / 2.0) / cols, 2) + std::pow((y - rows / 2.0) / rows, 2);
        nx[j * gw + i] =
            static_cast<float>(x * (1 - 0.2 * r2) + 0.1 * cols + rng.uniform(-0.3, 0.3));
        ny[j * gw + i] = static_cast<float>(y * (1 - 0.2 * r2) - 0.05 * rows);
      }
    nx[gw + 1] = -0.5f, ny[gw + 1] = rows - 0.5f;
    nx[gw * (gh - 1)] = -1e6f, ny[gw * (gh - 1)] = -1e6f;
    const cv::Mat d = grid_remap_abs_diff(a, b, nx, ny, gw, step);
    const cv::Mat expected = remap_difference_by_hand(a, b, nx, ny, gw, step);
    EXPECT_EQ(cv::countNonZero(d != expected), 0) << rows << " x " << cols << " every " << step;
    EXPECT_GT(cv::countNonZero(expected == 0), cv::countNonZero(a == b) + cols / 20)
        << "part of the view is unseen";
  }
}

}  // namespace
}  // namespace alight::vision
