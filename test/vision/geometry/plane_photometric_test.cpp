// The dense plane check between a floor and a top (vision/geometry/plane_photometric.hpp, issue
// 15).

#include "vision/geometry/plane_photometric.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "test/vision/test_images.hpp"

namespace alight::vision {
namespace {

struct Pair {
  CameraModel camera = CameraModel::firefly_mv_4mm();
  Matrix3d H_floor, H_top;  // reference -> current, undistorted pixels
};

// A level floor 1.5 m below camera 1 and a top 0.15 m above it; camera 2 0.25 m to the side.
Pair planes() {
  Pair p;
  const Matrix3d K = p.camera.K();
  const Vector3d t(-0.25, 0.05, 0.0);  // camera 1 in camera 2 coordinates
  const Vector3d n(0, 0, 1);           // plane normal in camera 1 (looking down its z)
  p.H_floor = K * (Matrix3d::Identity() + t * n.transpose() / 1.5) * K.inverse();
  p.H_top = K * (Matrix3d::Identity() + t * n.transpose() / 1.35) * K.inverse();
  return p;
}

// The current image whose every pixel sits at `gamma` between the two planes (the mapping the
// check inverts): the reference sampled where that plane maps each current pixel.
cv::Mat current_at(const cv::Mat& ref, const Pair& p, double gamma) {
  cv::Mat map_x(ref.size(), CV_32F), map_y(ref.size(), CV_32F);
  const Matrix3d Hf = p.H_floor.inverse(), Ht = p.H_top.inverse();
  for (int v = 0; v < ref.rows; ++v)
    for (int u = 0; u < ref.cols; ++u) {
      const Vector2d a = (Hf * Vector3d(u, v, 1)).hnormalized();
      const Vector2d b = (Ht * Vector3d(u, v, 1)).hnormalized();
      const Vector2d x = a + gamma * (b - a);
      map_x.at<float>(v, u) = static_cast<float>(x.x());
      map_y.at<float>(v, u) = static_cast<float>(x.y());
    }
  cv::Mat out;
  cv::remap(ref, out, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return out;
}

std::vector<cv::Point> block(int u0, int v0, int w, int h, int stride) {
  std::vector<cv::Point> px;
  for (int v = v0; v < v0 + h; v += stride)
    for (int u = u0; u < u0 + w; u += stride) px.emplace_back(u, v);
  return px;
}

// Known answer: pixels on the floor, on the top and halfway between are placed where they are,
// to a few hundredths of the top's height, with an uncertainty that says so.
TEST(PlanePhotometry, FindsTheHeightOfEveryPixelSetBetweenTheTwoPlanes) {
  const Pair p = planes();
  const cv::Mat ref = testing::procedural_photo(640, 480, 7);
  for (const double gamma : {0.0, 0.5, 1.0, 1.4}) {
    const cv::Mat cur = current_at(ref, p, gamma);
    const auto r =
        plane_photometry(ref, cur, p.camera, p.H_floor, p.H_top, block(200, 150, 200, 150, 3), 100);
    ASSERT_TRUE(r);
    EXPECT_NEAR(r->gamma, gamma, 0.03) << "gamma " << gamma;
    EXPECT_LT(r->sigma_gamma, 0.03);
    EXPECT_GT(r->n, 3000);
  }
}

// The comparison is a normalised cross-correlation: the camera's gain and offset changing
// between the frames (gain flicker) move nothing.
TEST(PlanePhotometry, GainAndOffsetBetweenTheFramesChangeNothing) {
  const Pair p = planes();
  const cv::Mat ref = testing::procedural_photo(640, 480, 11);
  cv::Mat cur = current_at(ref, p, 1.0), brighter;
  cur.convertTo(brighter, CV_8U, 0.8, 20);
  const auto a =
      plane_photometry(ref, cur, p.camera, p.H_floor, p.H_top, block(100, 100, 120, 120, 2), 100);
  const auto b = plane_photometry(ref, brighter, p.camera, p.H_floor, p.H_top,
                                  block(100, 100, 120, 120, 2), 100);
  ASSERT_TRUE(a && b);
  EXPECT_NEAR(a->gamma, b->gamma, 0.02);
}

// A blank surface says nothing about its height: the images share no texture (the landing
// target's check takes no verdict below PhotometricLimits::min_ncc, 0.5).
TEST(PlanePhotometry, BlankSurfaceGivesNoConfidentHeight) {
  const Pair p = planes();
  cv::Mat ref(480, 640, CV_8U, cv::Scalar(200)), noise(480, 640, CV_8U);
  cv::RNG rng(3);
  rng.fill(noise, cv::RNG::NORMAL, 0, 2);
  cv::Mat cur = current_at(ref, p, 1.0);
  ref += noise;
  rng.fill(noise, cv::RNG::NORMAL, 0, 2);
  cur += noise;
  const auto r =
      plane_photometry(ref, cur, p.camera, p.H_floor, p.H_top, block(200, 150, 200, 150, 3), 100);
  ASSERT_TRUE(r);
  EXPECT_LT(r->ncc_best, 0.2);
}

// Pixels mapped out of the reference at some height are not compared; too few left: no answer.
TEST(PlanePhotometry, PixelsOutOfTheReferenceAreLeftOut) {
  const Pair p = planes();
  const cv::Mat ref = testing::procedural_photo(640, 480, 5);
  const cv::Mat cur = current_at(ref, p, 1.0);
  // Camera 2 is 0.25 m to the side: its right edge's pixels map out of the reference (x1 = x2
  // + 111 px on the floor).
  EXPECT_FALSE(
      plane_photometry(ref, cur, p.camera, p.H_floor, p.H_top, block(600, 100, 40, 200, 2), 100));
  EXPECT_TRUE(
      plane_photometry(ref, cur, p.camera, p.H_floor, p.H_top, block(0, 100, 40, 200, 2), 100));
  EXPECT_FALSE(plane_photometry(ref, cur, p.camera, p.H_floor, p.H_top, {}, 1));
}

}  // namespace
}  // namespace alight::vision
