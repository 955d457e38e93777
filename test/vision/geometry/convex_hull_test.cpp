// ConvexHullDepth against cv::pointPolygonTest (the test it replaces): the same answer to
// "inside by more than m" for m >= 0, and the same sign, on random hulls of either turn.
#include "vision/geometry/convex_hull.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

namespace alight::vision {
namespace {

TEST(ConvexHullDepth, AgreesWithPointPolygonTestInsideByAMargin) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> pos(0.f, 640.f), spread(5.f, 200.f);
  std::uniform_real_distribution<double> margin(0.0, 10.0);
  int inside = 0, tested = 0;
  for (int draw = 0; draw < 200; ++draw) {
    const float cx = pos(rng), cy = pos(rng), sx = spread(rng), sy = spread(rng);
    std::normal_distribution<float> gx(cx, sx), gy(cy, sy);
    std::vector<cv::Point2f> pts, hull;
    const int n = 3 + draw % 40;
    for (int i = 0; i < n; ++i) pts.emplace_back(gx(rng), gy(rng));
    cv::convexHull(pts, hull, /*clockwise=*/draw % 2 == 0);
    const ConvexHullDepth depth(hull);
    ASSERT_FALSE(depth.empty());
    for (int k = 0; k < 200; ++k) {
      const cv::Point2f q(gx(rng), gy(rng));
      const double m = margin(rng);
      const double ref = cv::pointPolygonTest(hull, q, true);
      const double d = depth.depth(q.x, q.y);
      if (std::abs(ref - m) < 1e-3 || std::abs(ref) < 1e-3) continue;  // float rounding
      ++tested;
      inside += ref > m;
      EXPECT_EQ(depth.inside_by(q.x, q.y, m), ref > m) << draw << " " << k;
      EXPECT_EQ(d > 0, ref > 0) << draw << " " << k;
      if (ref > 0) {
        EXPECT_NEAR(d, ref, 1e-3);
      }
    }
  }
  EXPECT_GT(inside, tested / 10);  // both answers were exercised
  EXPECT_GT(tested - inside, tested / 10);
}

TEST(ConvexHullDepth, FewerThanThreeCornersOrNoAreaHoldNothing) {
  EXPECT_TRUE(ConvexHullDepth({}).empty());
  EXPECT_TRUE(ConvexHullDepth({{0, 0}, {1, 1}}).empty());
  EXPECT_TRUE(ConvexHullDepth({{0, 0}, {1, 1}, {2, 2}}).empty());  // collinear
  EXPECT_FALSE(ConvexHullDepth({{0, 0}, {1, 1}}).inside_by(0.5, 0.5, 0.0));
  // A repeated corner is skipped, the square stays a square.
  const ConvexHullDepth square({{0, 0}, {10, 0}, {10, 0}, {10, 10}, {0, 10}});
  EXPECT_DOUBLE_EQ(square.depth(5, 5), 5.0);
  EXPECT_DOUBLE_EQ(square.depth(2, 7), 2.0);
  EXPECT_LT(square.depth(-1, 5), 0.0);
}

}  // namespace
}  // namespace alight::vision
