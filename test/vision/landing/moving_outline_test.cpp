// The moving top from its outline against analytic motion: a rectangle's corners at a height,
// moved (drift, turn) between two exposures of a camera whose poses are known, projected into
// both views as the outlines; the measurement against the truth, and the refusals.
#include "vision/landing/moving_outline.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "common/camera_model.hpp"
#include "common/camera_mount.hpp"

namespace alight::vision {
namespace {

struct OutlineRect {
  Vector2d c = Vector2d::Zero();
  double psi = 0.0, h = 0.15;
  Vector2d size{0.40, 0.28};
  Vector3d corner(int i) const {
    const double sx = (i == 1 || i == 2) ? 0.5 : -0.5, sy = i >= 2 ? 0.5 : -0.5;
    const Vector2d l(sx * size.x(), sy * size.y());
    const Vector2d r(std::cos(psi) * l.x() - std::sin(psi) * l.y(),
                     std::sin(psi) * l.x() + std::cos(psi) * l.y());
    return Vector3d(c.x() + r.x(), c.y() + r.y(), h);
  }
};

PoseSample outline_camera_at(const Vector3d& p, double yaw) {
  PoseSample s;
  s.p_W_B = p;
  s.q_WB = Quaterniond(Eigen::AngleAxisd(yaw, Vector3d::UnitZ()));
  return s;
}

constexpr double kOutlineDt = 0.25;  // the earliest frame's age; the middle one's is half of it

// Three exposures, kOutlineDt and kOutlineDt / 2 before the current one, of a camera at 1.5 m
// flying 0.3 m/s along y, and the rectangle (a deck) at each: r[0] the earliest, r[2] the current.
struct OutlineScene {
  CameraModel camera = CameraModel::firefly_mv_4mm();
  CameraMount mount;
  PoseSample pose[3];
  OutlineRect r[3];
  std::vector<Outline> outlines[2];  // the earlier frames'
  OutlineScene() {
    for (int i = 0; i < 3; ++i)
      pose[i] = outline_camera_at({0.0, 0.3 * kOutlineDt * i / 2, 1.5}, 0.3);
  }
  // A deck at 0.4 m/s along x turning 8 deg/s.
  static OutlineScene deck() {
    OutlineScene s;
    for (int i = 0; i < 3; ++i) {
      s.r[i].c = Vector2d(-0.1 + 0.4 * kOutlineDt * i / 2, 0.2);
      s.r[i].psi = 0.5 + 8 * M_PI / 180 * kOutlineDt * i / 2;
    }
    return s;
  }
  // The rectangle's outline in frame i, its corners from `start` on, each moved by `jitter`
  // pixels along a fixed pattern (an outline's corners are a few pixels from frame to frame).
  Outline outline(const OutlineRect& rect, int i, int start = 0, double jitter = 0) const {
    const Isometry3d X_CW = camera_in_world(pose[i].X_WB(), mount.X_BC()).inverse();
    Outline o;
    for (int k = 0; k < 4; ++k) {
      const auto px = camera.project(X_CW * rect.corner((k + start) % 4));
      EXPECT_TRUE(px && camera.in_image(*px, 2));
      const double a = 2.1 * k + 0.7 * i;
      o.corners.push_back(*px + jitter * Vector2d(std::cos(a), std::sin(a)));
    }
    return o;
  }
  // The measurement with the earlier frames' outlines set (frame 0, frame 1) and the current
  // ones `now`.
  MovingTop measure(std::vector<Outline> earliest, std::vector<Outline> middle,
                    const std::vector<Outline>& now, size_t* used = nullptr) {
    outlines[0] = std::move(earliest);
    outlines[1] = std::move(middle);
    std::vector<EarlierOutlines> earlier;
    for (int i = 0; i < 2; ++i)
      earlier.push_back({&outlines[i], pose[i], nullptr, kOutlineDt * (2 - i) / 2});
    Correspondences c;
    c.camera = &camera;
    c.mount = &mount;
    c.pose_2 = pose[2];
    return find_moving_outline(earlier, now, c, 0.0, MovingTopParams{}, used);
  }
};

TEST(MovingOutlineTest, MeasuresADecksPositionVelocityTurnAndSidesFromItsCorners) {
  OutlineScene s = OutlineScene::deck();
  // The earlier outlines start at other corners: the order is found, the least turn kept.
  size_t used = 9;
  const MovingTop m = s.measure({s.outline(s.r[0], 0, 2, 2.0)}, {s.outline(s.r[1], 1, 1, 2.0)},
                                {s.outline(s.r[2], 2, 0, 2.0)}, &used);
  ASSERT_TRUE(m.found()) << to_string(m.reason);
  EXPECT_EQ(used, 0u);  // the longer interval
  EXPECT_EQ(m.dt_s, kOutlineDt);
  EXPECT_TRUE(m.outline);
  EXPECT_EQ(m.n_inliers, 4);
  EXPECT_NEAR(m.p_W.x(), s.r[2].c.x(), 0.01);
  EXPECT_NEAR(m.p_W.y(), s.r[2].c.y(), 0.01);
  EXPECT_NEAR(m.v_W.x(), 0.4, 0.06);
  EXPECT_NEAR(m.v_W.y(), 0.0, 0.06);
  // Two pixels on each corner turn a 40 cm side by half a degree over a quarter second.
  EXPECT_NEAR(m.yaw_rate_rps, 8 * M_PI / 180, 4 * M_PI / 180);
  EXPECT_LT(std::abs(m.yaw_rate_rps - 8 * M_PI / 180), 3 * std::sqrt(m.var_yaw_rate));
  EXPECT_NEAR(std::remainder(m.yaw_rad - s.r[2].psi, M_PI), 0.0, 1.5 * M_PI / 180);
  EXPECT_NEAR(m.size_m[0], 0.40, 0.01);
  EXPECT_NEAR(m.size_m[1], 0.28, 0.01);
  EXPECT_NEAR(m.scale, 1.0, 0.01);
  EXPECT_EQ(m.plane_z_m, 0.15);
  // The errors within three published sigmas.
  const Vector2d e = m.p_W.head<2>() - s.r[2].c;
  EXPECT_LT(e.dot(m.cov_p_W.topLeftCorner<2, 2>().inverse() * e), 9.0 * 2);
  EXPECT_LT(std::abs(m.v_W.x() - 0.4), 3 * std::sqrt(m.cov_v_W(0, 0)));
}

TEST(MovingOutlineTest, OneEarlierFrameAloneConfirmsNoMotion) {
  OutlineScene s = OutlineScene::deck();
  const MovingTop m = s.measure({s.outline(s.r[0], 0)}, {}, {s.outline(s.r[2], 2)});
  EXPECT_EQ(m.reason, MovingReason::kOutlineUnpaired) << to_string(m.reason);
}

TEST(MovingOutlineTest, ARectangleThatStaysPutIsTheFloorsOrAStillTop) {
  OutlineScene s;
  for (OutlineRect& r : s.r) r.h = 0.0;
  MovingTop m =
      s.measure({s.outline(s.r[0], 0, 1)}, {s.outline(s.r[1], 1)}, {s.outline(s.r[2], 2)});
  EXPECT_EQ(m.reason, MovingReason::kOnFloor) << to_string(m.reason);
  for (OutlineRect& r : s.r) r.h = 0.25;
  m = s.measure({s.outline(s.r[0], 0)}, {s.outline(s.r[1], 1)}, {s.outline(s.r[2], 2)});
  EXPECT_EQ(m.reason, MovingReason::kStillTop) << to_string(m.reason);
}

// A chessboard's square and its neighbour one period (30 cm) along: paired with the neighbour
// it would move at 1.2-2.4 m/s, a platform's speed. Where the square itself is in an earlier
// frame interval_s old, it stayed put: the floor's. Where it is in none, the neighbour, paired in
// both earlier frames, stayed put between them: off the track of any one motion.
TEST(MovingOutlineTest, AFloorSquareIsNotPairedWithItsNeighbourOnePeriodOn) {
  OutlineScene s;
  OutlineRect square;
  square.h = 0.0;
  square.size = {0.20, 0.20};
  square.c = {0.1, 0.1};
  OutlineRect neighbour = square;
  neighbour.c.x() -= 0.20;
  MovingTop m = s.measure({s.outline(neighbour, 0), s.outline(square, 0)},
                          {s.outline(neighbour, 1)}, {s.outline(square, 2)});
  EXPECT_EQ(m.reason, MovingReason::kOnFloor) << to_string(m.reason);
  m = s.measure({s.outline(neighbour, 0)}, {s.outline(neighbour, 1)}, {s.outline(square, 2)});
  EXPECT_EQ(m.reason, MovingReason::kOutlineUnpaired) << to_string(m.reason);
}

TEST(MovingOutlineTest, RefusesAMotionNoPlatformMakesAndASizeOutOfRange) {
  OutlineScene fast;
  for (int i = 0; i < 3; ++i) {
    fast.r[i].size = {0.20, 0.14};
    fast.r[i].c = Vector2d(-0.25 + 2.2 * kOutlineDt * i / 2, 0.1);  // 2.2 m/s
  }
  MovingTop m = fast.measure({fast.outline(fast.r[0], 0)}, {fast.outline(fast.r[1], 1)},
                             {fast.outline(fast.r[2], 2)});
  EXPECT_EQ(m.reason, MovingReason::kTooFast) << to_string(m.reason);
  OutlineScene small = OutlineScene::deck();
  for (OutlineRect& r : small.r) r.size = {0.10, 0.05};
  m = small.measure({small.outline(small.r[0], 0)}, {small.outline(small.r[1], 1)},
                    {small.outline(small.r[2], 2)});
  EXPECT_EQ(m.reason, MovingReason::kSizeOutOfRange) << to_string(m.reason);
}

TEST(MovingOutlineTest, AnOutlineNoEarlierOneFollowsIsUnpaired) {
  OutlineScene s = OutlineScene::deck();
  Outline o0 = s.outline(s.r[0], 0), o1 = s.outline(s.r[1], 1);
  o0.dark = o1.dark = false;  // the earlier regions are the other shading: other regions
  MovingTop m = s.measure({o0}, {o1}, {s.outline(s.r[2], 2)});
  EXPECT_EQ(m.reason, MovingReason::kOutlineUnpaired) << to_string(m.reason);
  // A different shape (a square where the current outline is a long rectangle).
  OutlineRect sq0 = s.r[0], sq1 = s.r[1];
  sq0.size = sq1.size = {0.28, 0.28};
  m = s.measure({s.outline(sq0, 0)}, {s.outline(sq1, 1)}, {s.outline(s.r[2], 2)});
  EXPECT_EQ(m.reason, MovingReason::kOutlineUnpaired) << to_string(m.reason);
  m = s.measure({}, {}, {s.outline(s.r[2], 2)});
  EXPECT_EQ(m.reason, MovingReason::kOutlineUnpaired) << to_string(m.reason);
}

}  // namespace
}  // namespace alight::vision
