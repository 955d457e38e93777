// Ingress target pieces (paper 3.3) on synthetic images with known answers: the off-wall mask
// of a textured plane with a rectangular hole (plain warp and the distorted-camera remap), the
// cuts of a ragged mask border, and the ingress parameters' loading and validation.
#include "vision/ingress_target.hpp"

#include <gtest/gtest.h>

#include <cstdio>

#include <opencv2/imgproc.hpp>

#include "common/params.hpp"
#include "vision/mission_params.hpp"

namespace alight::vision {
namespace {

// Smooth random texture, as a wall or a room behind it: seeded noise, blurred to blobs.
cv::Mat texture(int rows, int cols, uint64_t seed, double sigma_px) {
  cv::Mat noise(rows, cols, CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(), sigma_px);
  cv::normalize(noise, noise, 20, 235, cv::NORM_MINMAX);
  cv::Mat out;
  noise.convertTo(out, CV_8U);
  return out;
}

// A wall seen from two positions 12 px apart (x2 = x1 + 12 for its points) with a hole
// [x0, x1) x [y0, y1) in the current view; behind the hole a far room moving only 3 px.
struct HolePair {
  cv::Mat current, reference;
  cv::Rect hole{220, 140, 200, 180};
  Matrix3d H_21 = Matrix3d::Identity();
};

HolePair hole_pair(uint64_t seed) {
  HolePair p;
  const int rows = 480, cols = 640, pad = 40;
  const cv::Mat wall = texture(rows + 2 * pad, cols + 2 * pad, seed, 3.0);
  const cv::Mat room = texture(rows + 2 * pad, cols + 2 * pad, seed + 100, 5.0);
  const cv::Rect view(pad, pad, cols, rows);
  // Current view: the wall at offset 0, the room through the hole.
  p.current = wall(view).clone();
  room(view)(p.hole).copyTo(p.current(p.hole));
  // Reference: the camera 12 px to the other side; the wall shifts 12 px, the room 3 px, the
  // hole (in the wall) with the wall.
  const cv::Rect ref_view(pad + 12, pad, cols, rows);
  p.reference = wall(ref_view).clone();
  const cv::Rect hole_ref = p.hole - cv::Point(12, 0);
  room(cv::Rect(pad + 3, pad, cols, rows))(hole_ref).copyTo(p.reference(hole_ref));
  p.H_21(0, 2) = 12.0;
  return p;
}

std::vector<Vector2d> grid_outside(const cv::Rect& hole, int step) {
  std::vector<Vector2d> px;
  for (int v = 10; v < 470; v += step)
    for (int u = 10; u < 630; u += step)
      if (!hole.contains({u, v})) px.emplace_back(u, v);
  return px;
}

// Share of the pixels of `region` the mask marks (255).
double marked(const cv::Mat& mask, const cv::Rect& region) {
  return cv::countNonZero(mask(region & cv::Rect(0, 0, mask.cols, mask.rows))) /
         static_cast<double>(region.area());
}

TEST(OffWallMaskTest, MarksTheHoleAndNothingOfTheWall) {
  for (uint64_t seed : {1, 2, 3}) {
    const HolePair p = hole_pair(seed);
    const cv::Mat mask = off_wall_mask(p.current, p.reference, p.H_21, CameraModel{},
                                       grid_outside(p.hole, 37), IngressParams{});
    ASSERT_EQ(mask.type(), CV_8UC1);
    // Inside, 3 px in from the border: all of it; the wall 3 px out from it: none.
    const cv::Rect inner(p.hole.x + 3, p.hole.y + 3, p.hole.width - 6, p.hole.height - 6);
    EXPECT_GT(marked(mask, inner), 0.99) << "seed " << seed;
    cv::Mat wall = mask.clone();
    wall(cv::Rect(p.hole.x - 3, p.hole.y - 3, p.hole.width + 6, p.hole.height + 6)) = 0;
    EXPECT_EQ(cv::countNonZero(wall), 0) << "seed " << seed;
    // The strip the reference never saw (its left 12 px) counts as wall.
    EXPECT_EQ(marked(mask, cv::Rect(0, 0, 12, 480)), 0.0);
  }
}

TEST(OffWallMaskTest, DistortedCameraRemapsThroughTheRays) {
  // A lens with barrel distortion, the camera not moving (H = I): the remap path must give the
  // identity warp, so only the changed rectangle differs.
  CameraModel cam;
  cam.D = {-0.25, 0.08, 0.0, 0.0, 0.0};
  const HolePair p = hole_pair(7);
  const cv::Mat current = p.reference.clone();
  texture(p.hole.height, p.hole.width, 99, 4.0).copyTo(current(p.hole));
  const cv::Mat mask = off_wall_mask(current, p.reference, Matrix3d::Identity(), cam,
                                     grid_outside(p.hole, 37), IngressParams{});
  const cv::Rect inner(p.hole.x + 3, p.hole.y + 3, p.hole.width - 6, p.hole.height - 6);
  EXPECT_GT(marked(mask, inner), 0.99);
  cv::Mat wall = mask.clone();
  wall(cv::Rect(p.hole.x - 3, p.hole.y - 3, p.hole.width + 6, p.hole.height + 6)) = 0;
  EXPECT_EQ(cv::countNonZero(wall), 0);
}

TEST(OffWallMaskTest, ThresholdFollowsTheNoiseOnTheWall) {
  // Strong noise on the current image: a fixed threshold would mark the wall everywhere; k x
  // the median difference at the wall's inliers keeps it clean.
  HolePair p = hole_pair(4);
  cv::Mat noise(p.current.size(), CV_16S);
  cv::RNG rng(5);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 30.0);
  cv::Mat noisy;
  p.current.convertTo(noisy, CV_16S);
  noisy += noise;
  noisy.convertTo(p.current, CV_8U);
  IngressParams q;
  q.parallax_close_px = q.parallax_open_px = 0;  // the thresholds alone
  q.parallax_noise_k = 6;
  const auto wall_px = grid_outside(p.hole, 37);
  const cv::Mat adaptive = off_wall_mask(p.current, p.reference, p.H_21, CameraModel{}, wall_px, q);
  q.parallax_noise_k = 0.0;  // fixed threshold only
  const cv::Mat fixed = off_wall_mask(p.current, p.reference, p.H_21, CameraModel{}, wall_px, q);
  const cv::Rect left_wall(20, 20, 180, 440);
  EXPECT_GT(marked(fixed, left_wall), 0.05);
  EXPECT_LT(marked(adaptive, left_wall), 0.005);
  std::printf("wall marked: fixed threshold %.3f, adaptive %.4f; hole %.3f\n",
              marked(fixed, left_wall), marked(adaptive, left_wall),
              marked(adaptive, cv::Rect(p.hole.x + 10, p.hole.y + 10, p.hole.width - 20,
                                        p.hole.height - 20)));
}

TEST(MaskCutsTest, RaggedBorderGivesItsMean) {
  // A rectangle whose left border is x = 199.5 (pixels 200.. are in) and top y = 99.5, with
  // notches 2 px deep into it along every side; plus a diagonal bar that is no cut.
  cv::Mat mask(480, 640, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(200, 100, 240, 260)).setTo(255);
  for (int k = 0; k < 240; k += 20) {
    mask(cv::Rect(200 + k, 100, 6, 2)).setTo(0);  // top
    mask(cv::Rect(200 + k, 358, 6, 2)).setTo(0);  // bottom
  }
  for (int k = 0; k < 260; k += 20) {
    mask(cv::Rect(200, 100 + k, 2, 6)).setTo(0);  // left
    mask(cv::Rect(438, 100 + k, 2, 6)).setTo(0);  // right
  }
  cv::line(mask, {20, 460}, {180, 300}, cv::Scalar(255), 9);
  std::vector<double> xc, yc;
  std::vector<cv::Vec4i> kept;
  mask_cuts(mask, IngressParams{}, &xc, &yc, &kept);
  ASSERT_EQ(xc.size(), 4u);
  ASSERT_EQ(yc.size(), 4u);
  EXPECT_EQ(xc.front(), 0.0);
  EXPECT_EQ(xc.back(), 640.0);
  EXPECT_EQ(yc.front(), 0.0);
  EXPECT_EQ(yc.back(), 480.0);
  // Notches cover 6 of every 20 border pixels 2 px deep: the mean moves about 0.6 px inwards
  // (their sides add a little more); the cut stays within a pixel of the border.
  EXPECT_NEAR(xc[1], 199.5 + 0.6, 0.7);
  EXPECT_NEAR(xc[2], 439.5 - 0.6, 0.7);
  EXPECT_NEAR(yc[1], 99.5 + 0.6, 0.7);
  EXPECT_NEAR(yc[2], 359.5 - 0.6, 0.7);
  std::printf("cuts x %.2f %.2f  y %.2f %.2f\n", xc[1], xc[2], yc[1], yc[2]);
  EXPECT_GE(kept.size(), 4u);
}

TEST(MaskCutsTest, EmptyMaskGivesOnlyTheImageBorders) {
  const cv::Mat mask(480, 640, CV_8UC1, cv::Scalar(0));
  std::vector<double> xc, yc;
  mask_cuts(mask, IngressParams{}, &xc, &yc, nullptr);
  EXPECT_EQ(xc, (std::vector<double>{0.0, 640.0}));
  EXPECT_EQ(yc, (std::vector<double>{0.0, 480.0}));
}

TEST(IngressParamsTest, LoadedFromTheVehicleFileAndValidated) {
  const auto p = load_node_params(ParamNode::from_string(
      "vision:\n  ingress:\n    parallax_mask: false\n    parallax_min_diff: 15\n"
      "    cut_margin_px: 3\n",
      "vehicle.yaml"));
  EXPECT_FALSE(p.pipeline.ingress.parallax_mask);
  EXPECT_EQ(p.pipeline.ingress.parallax_min_diff, 15);
  EXPECT_EQ(p.pipeline.ingress.cut_margin_px, 3);
  try {
    load_node_params(ParamNode::from_string(
        "vision:\n  ingress:\n    parallax_close_px: -4\n", "vehicle.yaml"));
    FAIL() << "accepted a negative closing";
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("parallax_close_px"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("-4"), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_node_params(ParamNode::from_string(
                   "vision:\n  ingress:\n    parallax_mask_typo: true\n", "vehicle.yaml")),
               ParamError);
}

}  // namespace
}  // namespace alight::vision
