// The mask's border as a pixel list (vision/ingress/mask_border.hpp): a known square's ring, and
// the nonzero pixels of OpenCV's morphological gradient in findNonZero's order on random masks of
// every shape, image edges and one-pixel-wide images included.
#include "vision/ingress/mask_border.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

namespace alight::vision {
namespace {

std::vector<cv::Point> reference_border(const cv::Mat& mask) {
  cv::Mat gradient;
  cv::morphologyEx(mask, gradient, cv::MORPH_GRADIENT, cv::Mat());
  std::vector<cv::Point> px;
  cv::findNonZero(gradient, px);
  return px;
}

TEST(MaskBorderTest, SquareGivesTheTwoPixelRingAcrossItsEdge) {
  cv::Mat mask(20, 20, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(5, 6, 8, 7)).setTo(255);  // x 5..12, y 6..12
  const auto px = mask_border_pixels(mask);
  // The ring from one pixel outside to one pixel inside: 10 x 9 minus the 6 x 5 core.
  EXPECT_EQ(px.size(), 10u * 9u - 6u * 5u);
  for (const auto& q : px) {
    EXPECT_TRUE(q.x >= 4 && q.x <= 13 && q.y >= 5 && q.y <= 13) << q;
    EXPECT_FALSE(q.x >= 6 && q.x <= 11 && q.y >= 7 && q.y <= 11) << q;
  }
  EXPECT_TRUE(mask_border_pixels(cv::Mat(8, 8, CV_8UC1, cv::Scalar(255))).empty());
  EXPECT_TRUE(mask_border_pixels(cv::Mat()).empty());
}

TEST(MaskBorderTest, SameAsTheMorphologicalGradientsNonzeroPixels) {
  cv::RNG rng(3);
  for (const cv::Size size : {cv::Size(640, 480), cv::Size(37, 21), cv::Size(1, 9), cv::Size(9, 1),
                              cv::Size(2, 2), cv::Size(17, 3)}) {
    for (int it = 0; it < 20; ++it) {
      cv::Mat mask(size, CV_8UC1, cv::Scalar(0));
      for (int k = 0; k < 3; ++k) {
        const cv::Point a(rng.uniform(-size.width / 2, size.width),
                          rng.uniform(-size.height / 2, size.height));
        mask(
            cv::Rect(a, cv::Size(rng.uniform(1, size.width + 1), rng.uniform(1, size.height + 1))) &
            cv::Rect(cv::Point(0, 0), size))
            .setTo(rng.uniform(1, 256));  // any values, not only 0 / 255
      }
      cv::Mat noise(size, CV_8UC1);
      rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
      mask.setTo(255, noise > 250);
      ASSERT_EQ(mask_border_pixels(mask), reference_border(mask)) << size << " iteration " << it;
    }
  }
}

}  // namespace
}  // namespace alight::vision
