// The smooth gain between two views of a plane (vision/geometry/plane_gain.hpp) on synthetic
// views with a known falloff: a radial vignette moved across the image by the plane's motion is
// recovered to a percent and removed (the plane's difference falls to the noise), points off the
// plane do not pull it, a global gain is fitted from a few points, noise alone fits no falloff,
// the model is not extrapolated beyond the points it was fitted to, and too few or too dark
// points give no gain.
#include "vision/geometry/plane_gain.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

namespace alight::vision {
namespace {

// A smooth random texture (blurred noise) of mean ~120, contrast ~+-40 grey levels, as a float
// image larger than the view so that a shifted view stays inside it.
cv::Mat texture(int rows, int cols, uint64_t seed) {
  cv::Mat noise(rows, cols, CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(), 3.0);
  cv::Scalar mean, sd;
  cv::meanStdDev(noise, mean, sd);
  return 120.0 + (noise - mean[0]) * (40.0 / sd[0]);
}

// cos^4-like falloff to `corner` of the centre's brightness in the image corners.
double vignette(const CameraModel& m, double u, double v, double corner) {
  const double dx = m.cx + 0.5, dy = m.cy + 0.5;
  const double rho2 = ((u - m.cx) * (u - m.cx) + (v - m.cy) * (v - m.cy)) / (dx * dx + dy * dy);
  const double f = 1.0 + (1.0 / std::sqrt(corner) - 1.0) * rho2;
  return 1.0 / (f * f);
}

// The view of texture t whose pixel (u, v) sees t at (u + shift.x, v + shift.y), times `gain`
// and the vignette.
cv::Mat view(const cv::Mat& t, const CameraModel& m, cv::Point shift, double corner,
             double gain = 1.0) {
  cv::Mat out(m.height, m.width, CV_8UC1);
  for (int v = 0; v < m.height; ++v)
    for (int u = 0; u < m.width; ++u)
      out.at<uint8_t>(v, u) = cv::saturate_cast<uint8_t>(gain * vignette(m, u, v, corner) *
                                                         t.at<float>(v + shift.y, u + shift.x));
  return out;
}

// A texture seen by the reference and, moved by d px (x2 = x1 + d), by the current view, both
// through the same falloff; the current view's exposure `gain` times the reference's.
struct Views {
  cv::Mat reference, current;
};
Views moved_views(const CameraModel& m, uint64_t seed, cv::Point d, double corner,
                  double gain = 1.0) {
  const cv::Mat t = texture(m.height + 80, m.width + 80, seed);
  return {view(t, m, cv::Point(40, 40), corner), view(t, m, cv::Point(40, 40) - d, corner, gain)};
}

// The current view sees the plane moved by (dx, dy) px against the reference: x2 = x1 + d.
Matrix3d translation(double dx, double dy) {
  Matrix3d H = Matrix3d::Identity();
  H(0, 2) = dx, H(1, 2) = dy;
  return H;
}

std::vector<Vector2d> grid_points(const CameraModel& m, int step, int margin) {
  std::vector<Vector2d> px;
  for (int v = margin; v < m.height - margin; v += step)
    for (int u = margin; u < m.width - margin; u += step) px.emplace_back(u, v);
  return px;
}

double fitted_gain(const PlaneGain& g, const CameraModel& m, double u, double v) {
  return std::exp(g.log_gain((u - m.cx) / m.fx, (v - m.cy) / m.fy));
}

// The median absolute difference between the current view and the reference moved by d, over
// the pixels both see (20 px margin).
double median_plane_difference(const cv::Mat& current, const cv::Mat& reference, cv::Point d) {
  std::vector<int> diffs;
  for (int v = 20; v < current.rows - 20; v += 2)
    for (int u = 20; u < current.cols - 20; u += 2)
      diffs.push_back(
          std::abs(current.at<uint8_t>(v, u) - reference.at<uint8_t>(v - d.y, u - d.x)));
  std::nth_element(diffs.begin(), diffs.begin() + diffs.size() / 2, diffs.end());
  return diffs[diffs.size() / 2];
}

TEST(PlaneGainTest, AMovedVignetteIsRecoveredAndRemoved) {
  const CameraModel m;
  const cv::Point d(30, -20);  // the plane moved 30 px right and 20 px up in the current view
  const double corner = 0.5;
  const auto [reference, current] = moved_views(m, 1, d, corner);
  const auto g =
      fit_plane_gain(current, reference, 1.0, translation(d.x, d.y), m, grid_points(m, 25, 30));
  ASSERT_TRUE(g);
  EXPECT_GE(g->n_used, kMinPointsQuadratic);
  for (const auto& [u, v] :
       {std::pair{100.0, 100.0}, {320.0, 240.0}, {560.0, 400.0}, {80.0, 420.0}, {600.0, 60.0}}) {
    const double truth = vignette(m, u, v, corner) / vignette(m, u - d.x, v - d.y, corner);
    EXPECT_NEAR(fitted_gain(*g, m, u, v), truth, 0.01) << u << ", " << v;
  }
  // The plane's own difference: the vignette's change before, the rounding's after.
  const cv::Mat removed = remove_gain(current, 1.0, m, *g);
  EXPECT_GE(median_plane_difference(current, reference, d), 3);
  EXPECT_LE(median_plane_difference(removed, reference, d), 1);
}

TEST(PlaneGainTest, ASmallerImageIsFittedInTheCameraFramesCoordinates) {
  // The images at half size (the mask's decimated grid), the points in full-size pixels.
  const CameraModel m;
  const cv::Mat t = texture(m.height + 80, m.width + 80, 2);
  const cv::Point d(24, 10);
  const double corner = 0.5;
  cv::Mat reference, current;
  cv::resize(view(t, m, cv::Point(40, 40), corner), reference, {m.width / 2, m.height / 2}, 0, 0,
             cv::INTER_AREA);
  cv::resize(view(t, m, cv::Point(40, 40) - d, corner), current, {m.width / 2, m.height / 2}, 0, 0,
             cv::INTER_AREA);
  const auto g =
      fit_plane_gain(current, reference, 2.0, translation(d.x, d.y), m, grid_points(m, 25, 30));
  ASSERT_TRUE(g);
  for (const auto& [u, v] : {std::pair{100.0, 100.0}, {560.0, 400.0}}) {
    const double truth = vignette(m, u, v, corner) / vignette(m, u - d.x, v - d.y, corner);
    EXPECT_NEAR(fitted_gain(*g, m, u, v), truth, 0.015) << u << ", " << v;
  }
}

TEST(PlaneGainTest, PointsOffThePlaneDoNotPullTheGain) {
  // A third of the points see something else in the current view (an opening onto a brighter
  // room): their ratios are far from the plane's and the robust fit drops them.
  const CameraModel m;
  const cv::Mat t = texture(m.height + 80, m.width + 80, 3);
  const cv::Mat room = texture(m.height + 80, m.width + 80, 4) * 1.6;
  const cv::Point d(20, 0);
  const double corner = 0.6;
  const cv::Mat reference = view(t, m, cv::Point(40, 40), corner);
  cv::Mat current = view(t, m, cv::Point(40, 40) - d, corner);
  const cv::Rect opening(190, 120, 260, 240);
  view(room, m, cv::Point(40, 40), corner)(opening).copyTo(current(opening));
  const auto px = grid_points(m, 20, 30);
  int inside = 0;
  for (const auto& p : px) inside += opening.contains(cv::Point(p.x(), p.y()));
  ASSERT_GT(inside, static_cast<int>(px.size()) / 5);
  const auto g = fit_plane_gain(current, reference, 1.0, translation(d.x, d.y), m, px);
  ASSERT_TRUE(g);
  EXPECT_LE(g->n_used, static_cast<int>(px.size()) - inside / 2);
  for (const auto& [u, v] : {std::pair{100.0, 100.0}, {560.0, 400.0}, {320.0, 240.0}}) {
    const double truth = vignette(m, u, v, corner) / vignette(m, u - d.x, v - d.y, corner);
    EXPECT_NEAR(fitted_gain(*g, m, u, v), truth, 0.015) << u << ", " << v;
  }
}

TEST(PlaneGainTest, AFewPointsGiveAGlobalGain) {
  // An exposure change of 0.8 and no vignette, measured at 10 points: a constant.
  const CameraModel m;
  const auto [reference, current] = moved_views(m, 5, cv::Point(0, 0), 1.0, 0.8);
  std::vector<Vector2d> px;
  for (int i = 0; i < 10; ++i) px.emplace_back(100 + 45 * i, 120 + 20 * i);
  const auto g = fit_plane_gain(current, reference, 1.0, Matrix3d::Identity(), m, px);
  ASSERT_TRUE(g);
  EXPECT_NEAR(fitted_gain(*g, m, 50, 50), 0.8, 0.01);
  EXPECT_NEAR(fitted_gain(*g, m, 600, 450), 0.8, 0.01);
  EXPECT_EQ(g->c.tail<5>().norm(), 0.0);  // the constant term alone
}

TEST(PlaneGainTest, TheModelIsNotExtrapolatedBeyondItsPoints) {
  // Points on the left half only: at the right edge the gain stays within what it is on them.
  const CameraModel m;
  const cv::Point d(30, 0);
  const auto [reference, current] = moved_views(m, 6, d, 0.4);
  std::vector<Vector2d> px;
  for (const auto& p : grid_points(m, 20, 30))
    if (p.x() < 300) px.push_back(p);
  const auto g = fit_plane_gain(current, reference, 1.0, translation(d.x, d.y), m, px);
  ASSERT_TRUE(g);
  for (int v = 0; v < m.height; v += 40) {
    const double log_g = std::log(fitted_gain(*g, m, m.width - 1, v));
    EXPECT_GE(log_g, g->log_min - 1e-9);
    EXPECT_LE(log_g, g->log_max + 1e-9);
  }
}

TEST(PlaneGainTest, NoiseAloneKeepsAConstant) {
  // No falloff, sensor noise, a few dozen points: the ratios scatter by a few percent, and a
  // quadratic fitted to them would swing across the view; the constant explains them as well.
  const CameraModel m;
  const cv::Point d(25, 8);
  auto [reference, current] = moved_views(m, 9, d, 1.0, 1.02);
  cv::RNG rng(10);
  for (cv::Mat* image : {&reference, &current}) {
    cv::Mat noise(image->size(), CV_16S);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 8.0);
    cv::Mat noisy;
    image->convertTo(noisy, CV_16S);
    cv::Mat(noisy + noise).convertTo(*image, CV_8U);
  }
  std::vector<Vector2d> px;
  std::mt19937_64 draw(11);
  std::uniform_real_distribution<double> u(30, m.width - 30), v(30, m.height - 30);
  for (int i = 0; i < 30; ++i) px.emplace_back(u(draw), v(draw));
  const auto g = fit_plane_gain(current, reference, 1.0, translation(d.x, d.y), m, px);
  ASSERT_TRUE(g);
  EXPECT_EQ(g->c.tail<5>().norm(), 0.0);
  EXPECT_NEAR(std::exp(g->c(0)), 1.02, 0.01);
}

TEST(PlaneGainTest, TooFewOrTooDarkPointsGiveNoGain) {
  const CameraModel m;
  const cv::Mat t = texture(m.height + 80, m.width + 80, 7);
  const cv::Mat reference = view(t, m, cv::Point(40, 40), 1.0);
  std::vector<Vector2d> few{{100, 100}, {200, 200}, {300, 300}};
  EXPECT_FALSE(fit_plane_gain(reference, reference, 1.0, Matrix3d::Identity(), m, few));
  const cv::Mat dark(m.height, m.width, CV_8UC1, cv::Scalar(5));
  EXPECT_FALSE(fit_plane_gain(dark, dark, 1.0, Matrix3d::Identity(), m, grid_points(m, 40, 30)));
  // Points at the border or not finite are skipped, never read outside the image.
  std::vector<Vector2d> outside{{0, 0}, {639, 479}, {-5, 10}, {1e9, 3}, {NAN, 2}};
  EXPECT_FALSE(fit_plane_gain(reference, reference, 1.0, Matrix3d::Identity(), m, outside));
}

TEST(PlaneGainTest, NoFalloffLeavesTheImageAsItIs) {
  const CameraModel m;
  const cv::Point d(15, 5);
  const auto [reference, current] = moved_views(m, 8, d, 1.0);
  const auto g =
      fit_plane_gain(current, reference, 1.0, translation(d.x, d.y), m, grid_points(m, 25, 30));
  ASSERT_TRUE(g);
  cv::Mat diff;
  cv::absdiff(remove_gain(current, 1.0, m, *g), current, diff);
  double max_diff = 0;
  cv::minMaxLoc(diff, nullptr, &max_diff);
  EXPECT_LE(max_diff, 1.0);
}

}  // namespace
}  // namespace alight::vision
