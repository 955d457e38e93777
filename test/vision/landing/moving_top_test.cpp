// The moving top against analytic motion: a textured floor and a platform's top that moves
// (drift, turn, heave) between two exposures, projected into both views of a camera whose poses
// are known; the measurement against the truth, and the refusals.
#include "vision/landing/moving_top.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <optional>
#include <random>

#include "common/camera_model.hpp"
#include "common/camera_mount.hpp"
#include "vision/pipeline.hpp"

namespace alight::vision {
namespace {

// The top: a rectangle of features at height h above the floor, its centre c, yaw psi.
struct MovingTopTruth {
  Vector2d c = Vector2d::Zero();
  double h = 0.15, psi = 0.0;
  Vector3d point(const Vector2d& local) const {
    const Vector2d r(std::cos(psi) * local.x() - std::sin(psi) * local.y(),
                     std::sin(psi) * local.x() + std::cos(psi) * local.y());
    return Vector3d(c.x() + r.x(), c.y() + r.y(), h);
  }
};

struct MovingScene {
  CameraModel camera = CameraModel::firefly_mv_4mm();
  CameraMount mount;
  PoseSample pose_1, pose_2;
  MovingTopTruth top_1, top_2;
  Vector2d top_size{0.43, 0.28};
  int n_floor = 200, n_top = 60;
  /// Features on the top's +x end only (its outer quarter), besides n_top over all of it.
  int n_top_end = 0;
  double noise_px = 0.3;
  /// The top bare of features this close to the current image's border [px] (a print's margin).
  double bare_border_px = 0;
  bool with_top = true;
  uint64_t seed = 7;

  static PoseSample at(const Vector3d& p, double yaw) {
    PoseSample s;
    s.p_W_B = p;
    s.q_WB = Quaterniond(Eigen::AngleAxisd(yaw, Vector3d::UnitZ()));
    return s;
  }

  std::optional<Vector2d> project(const PoseSample& pose, const Vector3d& p_W) const {
    const Isometry3d X_WC = camera_in_world(pose.X_WB(), mount.X_BC());
    const auto px = camera.project(X_WC.inverse() * p_W);
    if (!px || !camera.in_image(*px, 2)) return std::nullopt;
    return px;
  }

  Correspondences correspondences() const {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> noise(0, noise_px);
    std::uniform_real_distribution<double> u(-1, 1);
    Correspondences c;
    c.camera = &camera;
    c.mount = &mount;
    c.pose_1 = pose_1;
    c.pose_2 = pose_2;
    const auto add = [&](const Vector3d& a, const Vector3d& b) {
      const auto p1 = project(pose_1, a), p2 = project(pose_2, b);
      if (!p1 || !p2) return;
      const Vector2d n1(noise(rng), noise(rng)), n2(noise(rng), noise(rng));
      c.u1.push_back(*p1 + n1);
      c.u2.push_back(*p2 + n2);
      c.x1.push_back((camera.K() * camera.ray(c.u1.back())).hnormalized());
      c.x2.push_back((camera.K() * camera.ray(c.u2.back())).hnormalized());
    };
    const Vector2d mid = 0.5 * (pose_1.p_W_B + pose_2.p_W_B).head<2>();
    for (int i = 0; i < n_floor; ++i) {
      const Vector3d f(mid.x() + 1.5 * u(rng), mid.y() + 1.2 * u(rng), 0.0);
      // The floor under the top (in either view) is hidden: only what lies outside both.
      const auto inside = [&](const MovingTopTruth& t) {
        const Vector2d d = f.head<2>() - t.c;
        const double cx = std::cos(t.psi) * d.x() + std::sin(t.psi) * d.y();
        const double cy = -std::sin(t.psi) * d.x() + std::cos(t.psi) * d.y();
        return std::abs(cx) < 0.5 * top_size.x() + 0.02 && std::abs(cy) < 0.5 * top_size.y() + 0.02;
      };
      if (with_top && (inside(top_1) || inside(top_2))) continue;
      add(f, f);
    }
    if (with_top)
      for (int i = 0; i < n_top; ++i) {
        const Vector2d local(0.5 * top_size.x() * u(rng), 0.5 * top_size.y() * u(rng));
        const auto p2 = project(pose_2, top_2.point(local));
        if (bare_border_px > 0 && p2 && !camera.in_image(*p2, bare_border_px)) continue;
        add(top_1.point(local), top_2.point(local));
      }
    if (with_top)
      for (int i = 0; i < n_top_end; ++i) {
        const Vector2d local(0.125 * top_size.x() * (3 + u(rng)), 0.5 * top_size.y() * u(rng));
        add(top_1.point(local), top_2.point(local));
      }
    return c;
  }
};

// A cart at 0.9 m/s turning at 10 deg/s under a camera flying level at 0.3 m/s, 1.5 m up, the
// top at the height the vision assumes.
MovingScene moving_cart_scene() {
  MovingScene s;
  const double dt = 0.25;
  s.pose_1 = MovingScene::at({0.0, 0.0, 1.5}, 0.3);
  s.pose_2 = MovingScene::at({0.3 * dt, 0.0, 1.5}, 0.3);
  s.pose_1.utime = 1'000'000, s.pose_2.utime = 1'250'000;
  s.top_1.c = {-0.05, 0.25};
  s.top_1.psi = 0.4;
  s.top_2 = s.top_1;
  s.top_2.c += Vector2d(0.9 * dt, 0.0);
  s.top_2.psi += 10 * M_PI / 180 * dt;
  return s;
}

// A top at 0.5 m/s along y under a camera flying with it at camera_z, level, dt apart; the top's
// centre at c.
MovingScene followed_close(double camera_z, const Vector2d& c, double dt) {
  MovingScene s;
  s.pose_1 = MovingScene::at({0.0, 0.0, camera_z}, 0.0);
  s.pose_2 = MovingScene::at({0.0, 0.5 * dt, camera_z}, 0.0);
  s.pose_1.utime = 1'000'000, s.pose_2.utime = 1'000'000 + int64_t(dt * 1e6);
  s.top_1.c = c;
  s.top_2 = s.top_1;
  s.top_2.c.y() += 0.5 * dt;
  return s;
}

TEST(MovingTopTest, MeasuresACartsPositionVelocityAndTurn) {
  const MovingScene s = moving_cart_scene();
  const MovingTopParams params;
  const MovingTop m = find_moving_top(s.correspondences(), 0.25, 0.0, params);
  ASSERT_TRUE(m.found()) << to_string(m.reason);
  EXPECT_GE(m.n_inliers, 40);
  // The features' rectangle centre is within a few features' spacing of the top's centre.
  EXPECT_NEAR(m.p_W.x(), s.top_2.c.x(), 0.03);
  EXPECT_NEAR(m.p_W.y(), s.top_2.c.y(), 0.03);
  EXPECT_NEAR(m.v_W.x(), 0.9, 0.05);
  EXPECT_NEAR(m.v_W.y(), 0.0, 0.05);
  EXPECT_NEAR(m.v_W.z(), 0.0, 0.05);
  EXPECT_NEAR(m.yaw_rate_rps, 10 * M_PI / 180, 2 * M_PI / 180);
  EXPECT_NEAR(m.yaw_rad, s.top_2.psi, 3 * M_PI / 180);
  EXPECT_NEAR(m.size_m[0], s.top_size.x(), 0.05);
  EXPECT_NEAR(m.size_m[1], s.top_size.y(), 0.05);
  // No floor match is taken for the top.
  const auto c = s.correspondences();
  ASSERT_EQ(m.inliers.size(), c.size());
}

// Two matches apart from the top that share its motion (a floor feature mismatched by the
// motion's few pixels, a speck on the top's plane) are no part of its rectangle: without them
// left out, they stretch its length by a quarter metre and turn its yaw.
TEST(MovingTopTest, MatchesApartFromTheTopThatShareItsMotionAreLeftOut) {
  const MovingScene s = moving_cart_scene();
  const MovingTopParams params;
  Correspondences c = s.correspondences();
  const size_t n_scene = c.size();
  for (const Vector2d& local : {Vector2d(-0.47, 0.0), Vector2d(-0.49, -0.03)}) {
    const auto p1 = s.project(s.pose_1, s.top_1.point(local));
    const auto p2 = s.project(s.pose_2, s.top_2.point(local));
    ASSERT_TRUE(p1 && p2);
    c.u1.push_back(*p1), c.u2.push_back(*p2);
    c.x1.push_back((s.camera.K() * s.camera.ray(*p1)).hnormalized());
    c.x2.push_back((s.camera.K() * s.camera.ray(*p2)).hnormalized());
  }
  const MovingTop m = find_moving_top(c, 0.25, 0.0, params);
  ASSERT_TRUE(m.found()) << to_string(m.reason);
  EXPECT_EQ(m.inliers[n_scene], 0);
  EXPECT_EQ(m.inliers[n_scene + 1], 0);
  EXPECT_NEAR(m.size_m[0], s.top_size.x(), 0.05);
  EXPECT_NEAR(m.yaw_rad, s.top_2.psi, 3 * M_PI / 180);
  const MovingTop alone = find_moving_top(s.correspondences(), 0.25, 0.0, params);
  EXPECT_EQ(m.n_inliers, alone.n_inliers);
  EXPECT_EQ(m.p_W, alone.p_W);
}

TEST(MovingTopTest, ATopTallerThanAssumedUnderADescendingCameraReadsAsRisingAndLarger) {
  // The top is 12 cm taller than the 15 cm assumed and moves level; the camera descends at
  // 0.4 m/s from 1.5 m. Each view's points are scaled about its camera's nadir by (z_c - 0.15) /
  // (z_c - h), so the extent is that much too large, and the scale's change over the interval reads
  // as the top rising at dh (z_c1 - z_c2) / (dt (z_c1 - h)): what a reader following the top over
  // many pairs measures its height from, given the cameras and the plane published with it.
  const double dt = 0.25, h = 0.27, vz_cam = -0.4;
  MovingScene s = followed_close(1.5, {0.0, 0.0}, dt);
  s.pose_2.p_W_B.z() += vz_cam * dt;
  s.top_1.h = s.top_2.h = h;
  s.n_top = 120;
  const MovingTopParams params;
  const MovingTop m = find_moving_top(s.correspondences(), dt, 0.0, params);
  ASSERT_TRUE(m.found()) << to_string(m.reason);
  const Isometry3d X_WC1 = camera_in_world(s.pose_1.X_WB(), s.mount.X_BC());
  const Isometry3d X_WC2 = camera_in_world(s.pose_2.X_WB(), s.mount.X_BC());
  EXPECT_LT((m.camera_W - X_WC2.translation()).norm(), 1e-9);
  EXPECT_LT((m.ref_camera_W - X_WC1.translation()).norm(), 1e-9);
  EXPECT_DOUBLE_EQ(m.plane_z_m, params.top_height_m);
  const double z1 = X_WC1.translation().z(), z2 = X_WC2.translation().z();
  const double dh = h - params.top_height_m;
  EXPECT_NEAR(m.v_W.z(), dh * (z1 - z2) / (dt * (z1 - h)), 0.01);
  EXPECT_GT(m.v_W.z(), 0.02);  // a level top, read as rising
  const double k2 = (z2 - params.top_height_m) / (z2 - h);
  EXPECT_NEAR(m.size_m[0] / k2, s.top_size.x(), 0.04);
  EXPECT_GT(m.size_m[0], s.top_size.x() + 0.03);
}

TEST(MovingTopTest, ATopGoingOnPastTheBorderIsCutThoughItsFeaturesStopShortOfIt) {
  // Followed 0.5 m above its top, a 43 cm top reaches past the image's border; its print stops
  // 30 px short of the border. The features' rectangle is then a part of the top: its motion is
  // measured, its centre is not (a cut top), as the still landing's edge_margin_px has it.
  const double dt = 0.25;
  MovingScene s = followed_close(0.71, {0.12, 0.0}, dt);
  s.n_top = 200;
  s.bare_border_px = 30;
  MovingTopParams params;
  const MovingTop m = find_moving_top(s.correspondences(), dt, 0.0, params);
  ASSERT_TRUE(m.found()) << to_string(m.reason);
  EXPECT_TRUE(m.cut);
  EXPECT_GT(m.cov_p_W(0, 0), 1.0);  // no position
  EXPECT_GT(m.size_m[1], 0.0);      // past one border only: the visible part's extent
  EXPECT_NEAR(m.v_W.y(), 0.5, 0.05);
  // Counted from the features 20 px in, the same view passed for the whole top, its centre
  // several centimetres off the top's.
  params.edge_margin_px = 20;
  const MovingTop whole = find_moving_top(s.correspondences(), dt, 0.0, params);
  ASSERT_TRUE(whole.found()) << to_string(whole.reason);
  EXPECT_FALSE(whole.cut);
  EXPECT_GT((whole.p_W.head<2>() - s.top_2.c).norm(), 0.02);
}

TEST(MovingTopTest, TheVelocityIsTheRectanglesCentresNotTheFeaturesCentroids) {
  // A cart turning at 40 deg/s whose print crowds one end of its top: the matches' centroid
  // lies towards that end, and its velocity differs from the rectangle's centre's by the turn's
  // lever arm (9 cm/s). The velocity published is p_W's, as a point of the top.
  MovingScene s = moving_cart_scene();
  const double dt = 0.25, w = 40 * M_PI / 180;
  s.top_2.psi = s.top_1.psi + w * dt;
  s.n_top = 20;
  s.n_top_end = 120;
  const MovingTop m = find_moving_top(s.correspondences(), dt, 0.0, MovingTopParams{});
  ASSERT_TRUE(m.found()) << to_string(m.reason);
  // The true mean velocity of the top's point under p_W: where it was (turned back with the
  // top) to where it is, over the interval.
  const Vector2d local = Eigen::Rotation2Dd(-s.top_2.psi) * (m.p_W.head<2>() - s.top_2.c);
  const Vector2d was = s.top_1.c + Eigen::Rotation2Dd(s.top_1.psi) * local;
  const Vector2d v_true = (m.p_W.head<2>() - was) / dt;
  EXPECT_LT((m.v_W.head<2>() - v_true).norm(), 0.02)
      << m.v_W.transpose() << " " << v_true.transpose();
}

TEST(MovingTopTest, ATopThatFillsTheViewAcrossHasNoMeasuredExtent) {
  // 0.5 m above a 0.7 x 0.6 m top: its features reach every border of the image. Their extent is
  // the view's footprint, not the top's: none is published (a footprint about the top's size
  // read as the whole top and placed the centre under the camera).
  const double dt = 0.25;
  MovingScene s = followed_close(0.65, {0.0, 0.0}, dt);
  s.top_size = {0.7, 0.6};
  s.n_top = 400;
  const MovingTop m = find_moving_top(s.correspondences(), dt, 0.0, MovingTopParams{});
  ASSERT_TRUE(m.found()) << to_string(m.reason);
  EXPECT_TRUE(m.cut);
  EXPECT_EQ(m.size_m[0], 0.0);
  EXPECT_EQ(m.size_m[1], 0.0);
  EXPECT_NEAR(m.v_W.y(), 0.5, 0.05);
}

// The yaw is the features' rectangle's, which rests on the few features nearest the edges: its
// published variance must cover its error (the platform filter weighs it by that), far beyond
// the frame-to-frame turn's. Sparse tops, 40 draws of the features.
TEST(MovingTopTest, TheRectanglesYawErrorIsWithinItsPublishedVariance) {
  MovingScene s = moving_cart_scene();
  s.n_top = 24;
  const MovingTopParams params;
  int n = 0, beyond_3_sigma = 0;
  double z2_sum = 0, var_turn_max = 0, var_yaw_min = 1e9;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    s.seed = seed;
    const MovingTop m = find_moving_top(s.correspondences(), 0.25, 0.0, params);
    if (!m.found() || m.cut) continue;
    const double e = std::remainder(m.yaw_rad - s.top_2.psi, M_PI / 2);
    z2_sum += e * e / m.var_yaw;
    if (std::abs(e) > 3 * std::sqrt(m.var_yaw)) ++beyond_3_sigma;
    var_turn_max = std::max(var_turn_max, m.var_yaw_rate * 0.25 * 0.25 / 2);
    var_yaw_min = std::min(var_yaw_min, m.var_yaw);
    ++n;
  }
  ASSERT_GE(n, 30);
  EXPECT_LT(z2_sum / n, 3.0);
  EXPECT_LE(beyond_3_sigma, n / 10);
  EXPECT_GT(var_yaw_min, var_turn_max) << "the rectangle's yaw is not the turn's";
}

TEST(MovingTopTest, AWrongHeightLeavesErrorsWithinThePublishedCovariance) {
  // The top 7 cm higher than assumed, and the camera 0.4 m aside: the position is off by the
  // height error times the view angle's tangent, the velocity by the height error over the
  // camera's height times the speed relative to the camera; both inside 3 sigma.
  MovingScene s = moving_cart_scene();
  s.top_1.h = s.top_2.h = 0.22;
  const MovingTopParams params;
  const MovingTop m = find_moving_top(s.correspondences(), 0.25, 0.0, params);
  ASSERT_TRUE(m.found()) << to_string(m.reason);
  const Vector2d ep = m.p_W.head<2>() - s.top_2.c;
  const Vector2d ev = m.v_W.head<2>() - Vector2d(0.9, 0.0);
  EXPECT_GT(ev.norm(), 0.01);  // the height error shows
  const Eigen::Matrix2d Cp =
      m.cov_p_W.topLeftCorner<2, 2>() + 0.015 * 0.015 * Eigen::Matrix2d::Identity();
  EXPECT_LT(ep.dot(Cp.inverse() * ep), 9.0) << ep.transpose();
  // The features' centroid, whose velocity is measured, is not the top's centre: the turn
  // moves them apart by omega r (10 deg/s over a few centimetres), under 1 cm/s.
  const Eigen::Matrix2d Cv =
      m.cov_v_W.topLeftCorner<2, 2>() + 0.01 * 0.01 * Eigen::Matrix2d::Identity();
  EXPECT_LT(ev.dot(Cv.inverse() * ev), 9.0) << ev.transpose();
  // Matched in speed and overhead, the same height error leaves almost nothing.
  MovingScene f = s;
  f.pose_1 = MovingScene::at({-0.05, 0.25, 1.5}, 0.3);
  f.pose_2 = MovingScene::at({-0.05 + 0.9 * 0.25, 0.25, 1.5}, 0.3);
  f.pose_1.utime = 1'000'000, f.pose_2.utime = 1'250'000;
  f.top_2.psi = f.top_1.psi;
  const MovingTop g = find_moving_top(f.correspondences(), 0.25, 0.0, params);
  ASSERT_TRUE(g.found()) << to_string(g.reason);
  EXPECT_NEAR(g.v_W.x(), 0.9, 0.01);
  EXPECT_LT((g.p_W.head<2>() - f.top_2.c).norm(), 0.02);
}

TEST(MovingTopTest, MeasuresADecksHeave) {
  // A deck rising 4 cm in 0.25 s (0.16 m/s, the top of a 5 cm, 0.5 Hz heave's speed).
  MovingScene s = moving_cart_scene();
  s.top_2.h = s.top_1.h + 0.04;
  const MovingTop m = find_moving_top(s.correspondences(), 0.25, 0.0, MovingTopParams{});
  ASSERT_TRUE(m.found()) << to_string(m.reason);
  EXPECT_NEAR(m.v_W.z(), 0.16, 0.03);
  EXPECT_NEAR(m.p_W.z(), 0.19, 0.01);
  EXPECT_GT(m.scale, 1.0);
}

TEST(MovingTopTest, AStillFloorIsNoMovingTop) {
  MovingScene s = moving_cart_scene();
  s.with_top = false;
  const MovingTop m = find_moving_top(s.correspondences(), 0.25, 0.0, MovingTopParams{});
  EXPECT_FALSE(m.found());
  EXPECT_TRUE(m.reason == MovingReason::kTooFewCandidates ||
              m.reason == MovingReason::kNoCommonMotion || m.reason == MovingReason::kOnFloor)
      << to_string(m.reason);
}

// The body turning while motion capture's stamp is a few milliseconds off: the later pose the
// vision is given is 9 mrad from the true one, so every floor match lands about 6 px from where the
// known floor carries it (past floor_tol_px) and the floor's ~200 matches share one apparent
// motion on the top's plane, three times the top's 60. That cluster is the floor's and is set
// aside; the top is the next common motion. Without a top, nothing but the floor is found.
TEST(MovingTopTest, AFloorClusterOffTheKnownFloorIsSetAsideForTheTop) {
  MovingScene s = moving_cart_scene();
  s.n_floor = 800;  // about 200 of them in both views
  auto c = s.correspondences();
  c.pose_2.q_WB = c.pose_2.q_WB * Quaterniond(Eigen::AngleAxisd(0.009, Vector3d::UnitX()));
  const MovingTopParams params;
  const MovingTop m = find_moving_top(c, 0.25, 0.0, params);
  ASSERT_TRUE(m.found()) << to_string(m.reason);
  EXPECT_GE(m.n_candidates, 150);  // the floor's matches are candidates
  // Only the top's matches (appended after the floor's) are taken.
  const size_t n_floor = c.size() - static_cast<size_t>(s.n_top);
  for (size_t i = 0; i < n_floor; ++i) EXPECT_EQ(m.inliers[i], 0) << i;
  EXPECT_GE(m.n_inliers, 40);
  // The turn's error moves the top's points by the same few millimetres as the floor's.
  EXPECT_NEAR(m.v_W.x(), 0.9, 0.1);
  EXPECT_NEAR(m.v_W.y(), 0.0, 0.1);
  s.with_top = false;
  c = s.correspondences();
  c.pose_2.q_WB = c.pose_2.q_WB * Quaterniond(Eigen::AngleAxisd(0.009, Vector3d::UnitX()));
  EXPECT_EQ(find_moving_top(c, 0.25, 0.0, params).reason, MovingReason::kOnFloor);
}

// A still top 0.8 x 0.7 m whose print repeats every 0.42 m across it (a photograph tiled over a
// large top, roof tiles, a grating), seen while hovering: 24 of its features match the next copy
// in the later view, one period on, and share that displacement (1.7 m/s over 0.25 s) as one
// rigid motion; 60 match themselves and stay put (over 5 mm of baseline the known floor carries
// them too, so they are no candidates). The still top explains the view as well: no moving top.
TEST(MovingTopTest, ATopWhosePatternRepeatsIsNotMovingByOnePeriod) {
  MovingScene s = moving_cart_scene();
  s.with_top = false;
  s.pose_2 = MovingScene::at({0.005, 0.0, 1.5}, 0.3);  // hovering
  s.pose_2.utime = 1'250'000;
  Correspondences c = s.correspondences();
  MovingTopTruth top;
  top.c = {0.1, 0.05};
  top.psi = 0.56;
  const Vector2d period(0.0, 0.42);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> ux(-0.4, 0.4), uy(-0.35, 0.35);
  const auto add = [&](const Vector2d& l1, const Vector2d& l2) {
    const auto p1 = s.project(s.pose_1, top.point(l1)), p2 = s.project(s.pose_2, top.point(l2));
    if (!p1 || !p2) return false;
    c.u1.push_back(*p1);
    c.u2.push_back(*p2);
    c.x1.push_back((s.camera.K() * s.camera.ray(*p1)).hnormalized());
    c.x2.push_back((s.camera.K() * s.camera.ray(*p2)).hnormalized());
    return true;
  };
  int twins = 0, selves = 0;
  while (twins < 24) {
    const Vector2d l(ux(rng), uy(rng) - 0.21);  // its next copy is on the top too
    twins += add(l, l + period);
  }
  while (selves < 60) {
    const Vector2d l(ux(rng), uy(rng));
    selves += add(l, l);
  }
  const MovingTop m = find_moving_top(c, 0.25, 0.0, MovingTopParams{});
  EXPECT_EQ(m.reason, MovingReason::kStillTop)
      << to_string(m.reason) << " at " << m.v_W.head<2>().norm() << " m/s";
  // The cart's measurement keeps its motion: no still matches of its own.
  EXPECT_TRUE(find_moving_top(moving_cart_scene().correspondences(), 0.25, 0.0, {}).found());
}

// A print of smooth texture: a sum of plane waves 2-8 cm long at random directions and phases;
// with `period_y`, every wave repeats along y over it (a photograph tiled along the top).
struct Print {
  std::vector<Vector3d> waves;  // (kx, ky, phase) [rad/m, rad/m, rad]
  double at(const Vector2d& p) const {
    double g = 0;
    for (const Vector3d& w : waves) g += std::cos(w.x() * p.x() + w.y() * p.y() + w.z());
    return 128 + 100 * g / std::sqrt(double(waves.size()));
  }
  static Print random(uint64_t seed, std::optional<double> period_y = std::nullopt) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0, 1);
    Print p;
    for (int i = 0; i < 24; ++i) {
      const double k = 2 * M_PI / (0.02 + 0.06 * u(rng)), a = 2 * M_PI * u(rng);
      double ky = k * std::sin(a);
      if (period_y) ky = 2 * M_PI / *period_y * std::round(ky * *period_y / (2 * M_PI));
      p.waves.emplace_back(k * std::cos(a), ky, 2 * M_PI * u(rng));
    }
    return p;
  }
};

// The camera's image at `pose`: each pixel's ray met with the top's plane inside `top`'s
// rectangle of `size` (its print in the top's own frame), else with the floor (z = 0).
cv::Mat render(const MovingScene& s, const PoseSample& pose, const MovingTopTruth& top,
               const Vector2d& size, const Print& top_print, const Print& floor_print) {
  const Isometry3d X_WC = camera_in_world(pose.X_WB(), s.mount.X_BC());
  cv::Mat g(s.camera.height, s.camera.width, CV_8UC1);
  for (int v = 0; v < g.rows; ++v)
    for (int u = 0; u < g.cols; ++u) {
      const Vector3d d = X_WC.linear() * s.camera.ray(Vector2d(u, v));
      const Vector3d o = X_WC.translation();
      const Vector3d P = o + (top.h - o.z()) / d.z() * d;
      const Vector2d e = P.head<2>() - top.c;
      const Vector2d local(std::cos(top.psi) * e.x() + std::sin(top.psi) * e.y(),
                           -std::sin(top.psi) * e.x() + std::cos(top.psi) * e.y());
      const bool on_top =
          std::abs(local.x()) < 0.5 * size.x() && std::abs(local.y()) < 0.5 * size.y();
      const double grey =
          on_top ? top_print.at(local) : floor_print.at((o + (0 - o.z()) / d.z() * d).head<2>());
      g.at<uint8_t>(v, u) = cv::saturate_cast<uint8_t>(grey);
    }
  return g;
}

// The same still top with a print that repeats every 0.42 m, as the images show it, and only
// its features matched to their next copy: the ratio test dropped every still match (each
// feature has a twin), so no match stays put and the count of still matches has nothing to
// see. The pixels do: where a still top had each feature, the earlier image shows the same
// print as where the period's motion had it.
TEST(MovingTopTest, ARepeatedPrintsPixelsRefuseItsPeriodAsMotion) {
  MovingScene s = moving_cart_scene();
  s.pose_2 = MovingScene::at({0.005, 0.0, 1.5}, 0.3);
  s.pose_2.utime = 1'250'000;
  MovingTopTruth top;
  top.c = {0.1, 0.05};
  top.psi = 0.56;
  const Vector2d size(0.8, 0.7), period(0.0, 0.42);
  s.top_1 = s.top_2 = top;  // it hides the floor under it; its own matches are added below
  s.top_size = size;
  s.n_top = 0;
  Correspondences c = s.correspondences();
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> ux(-0.38, 0.38), uy(-0.33, 0.33);
  int twins = 0;
  while (twins < 24) {
    const Vector2d l(ux(rng), uy(rng) - 0.21);
    const auto p1 = s.project(s.pose_1, top.point(l)),
               p2 = s.project(s.pose_2, top.point(l + period));
    if (!p1 || !p2 || std::abs(l.y() + period.y()) > 0.33) continue;
    c.u1.push_back(*p1);
    c.u2.push_back(*p2);
    c.x1.push_back((s.camera.K() * s.camera.ray(*p1)).hnormalized());
    c.x2.push_back((s.camera.K() * s.camera.ray(*p2)).hnormalized());
    ++twins;
  }
  const MovingTop blind = find_moving_top(c, 0.25, 0.0, MovingTopParams{});
  ASSERT_TRUE(blind.found()) << "the matches alone are a moving top: " << to_string(blind.reason);
  const Print print = Print::random(11, period.y()), floor = Print::random(12);
  const cv::Mat g1 = render(s, s.pose_1, top, size, print, floor);
  const cv::Mat g2 = render(s, s.pose_2, top, size, print, floor);
  const MovingTop m = find_moving_top(c, 0.25, 0.0, MovingTopParams{}, g1, g2);
  EXPECT_EQ(m.reason, MovingReason::kStillPixels)
      << to_string(m.reason) << ": still " << m.ncc_still << " moving " << m.ncc_moving;
  EXPECT_GT(m.ncc_still, 0.9);
}

// moving_cart_scene's cart printed all over, measured with both images.
MovingTop printed_cart(const MovingScene& s) {
  const Print print = Print::random(21), floor = Print::random(22);
  const cv::Mat g1 = render(s, s.pose_1, s.top_1, s.top_size, print, floor);
  const cv::Mat g2 = render(s, s.pose_2, s.top_2, s.top_size, print, floor);
  return find_moving_top(s.correspondences(), 0.25, 0.0, MovingTopParams{}, g1, g2);
}

// A cart whose print does not repeat keeps its motion: where each feature was, the earlier
// image shows what the cart left there.
TEST(MovingTopTest, ACartsPixelsFollowItsMotionNotAStillTop) {
  const MovingTop m = printed_cart(moving_cart_scene());
  ASSERT_TRUE(m.found()) << to_string(m.reason) << ": still " << m.ncc_still << " moving "
                         << m.ncc_moving;
  EXPECT_GT(m.ncc_moving, 0.9);
  EXPECT_LT(m.ncc_still, m.ncc_moving - kStillNccGap);
  EXPECT_NEAR(m.v_W.x(), 0.9, 0.05);
}

// A print whose subject is a blob: its print inside an ellipse of semi-axes `axes` about
// `centre`, turned `turn` in the top's frame, a plain grey around it (a photograph of a fruit on a
// plain cloth).
struct BlobPrint {
  Print subject = Print::random(31);
  Vector2d centre{0.05, -0.02}, axes{0.09, 0.05};
  double turn = 35 * M_PI / 180;
  bool inside(const Vector2d& p) const {
    const Vector2d d = p - centre;
    const double a = std::cos(turn) * d.x() + std::sin(turn) * d.y();
    const double b = -std::sin(turn) * d.x() + std::cos(turn) * d.y();
    return (a / axes.x()) * (a / axes.x()) + (b / axes.y()) * (b / axes.y()) < 1;
  }
  double at(const Vector2d& p) const { return inside(p) ? subject.at(p) : 175.0; }
};

// The cart of moving_cart_scene with its print's features on the blob alone, followed by a camera
// over it (its nadir inside the top: no side face in view): the features' rectangle is the
// blob's, turned 35 deg from the top and off its centre; the pixels that follow the cart's motion
// out to its rims give the top's own (moving_edges.hpp).
TEST(MovingTopTest, ATopWhosePrintIsABlobIsMeasuredOutToItsEdges) {
  MovingScene s = moving_cart_scene();
  s.pose_1 = MovingScene::at({s.top_1.c.x(), s.top_1.c.y(), 1.5}, 0.3);
  s.pose_2 = MovingScene::at({s.top_2.c.x(), s.top_2.c.y(), 1.5}, 0.3);
  s.pose_1.utime = 1'000'000, s.pose_2.utime = 1'250'000;
  s.n_top = 0;
  Correspondences c = s.correspondences();
  const BlobPrint blob;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> ux(-0.2, 0.2), uy(-0.12, 0.12);
  std::normal_distribution<double> noise(0, s.noise_px);
  for (int added = 0; added < 40;) {
    const Vector2d l(ux(rng), uy(rng));
    if (!blob.inside(l)) continue;
    const auto p1 = s.project(s.pose_1, s.top_1.point(l)),
               p2 = s.project(s.pose_2, s.top_2.point(l));
    if (!p1 || !p2) continue;
    c.u1.push_back(*p1 + Vector2d(noise(rng), noise(rng)));
    c.u2.push_back(*p2 + Vector2d(noise(rng), noise(rng)));
    c.x1.push_back((s.camera.K() * s.camera.ray(c.u1.back())).hnormalized());
    c.x2.push_back((s.camera.K() * s.camera.ray(c.u2.back())).hnormalized());
    ++added;
  }
  const auto yaw_error_deg = [&](const MovingTop& m) {
    return std::abs(std::remainder(m.yaw_rad - s.top_2.psi, M_PI / 2)) * 180 / M_PI;
  };
  const MovingTop features = find_moving_top(c, 0.25, 0.0, MovingTopParams{});
  ASSERT_TRUE(features.found()) << to_string(features.reason);
  EXPECT_FALSE(features.edges);
  EXPECT_GT(yaw_error_deg(features), 8.0) << "the features' rectangle is the blob's";

  const Print floor = Print::random(22);
  const auto image = [&](const PoseSample& pose, const MovingTopTruth& top) {
    cv::Mat g(s.camera.height, s.camera.width, CV_8UC1);
    const Isometry3d X_WC = camera_in_world(pose.X_WB(), s.mount.X_BC());
    for (int v = 0; v < g.rows; ++v)
      for (int u = 0; u < g.cols; ++u) {
        const Vector3d d = X_WC.linear() * s.camera.ray(Vector2d(u, v));
        const Vector3d o = X_WC.translation();
        const Vector2d e = (o + (top.h - o.z()) / d.z() * d).head<2>() - top.c;
        const Vector2d local(std::cos(top.psi) * e.x() + std::sin(top.psi) * e.y(),
                             -std::sin(top.psi) * e.x() + std::cos(top.psi) * e.y());
        const bool on_top = std::abs(local.x()) < 0.5 * s.top_size.x() &&
                            std::abs(local.y()) < 0.5 * s.top_size.y();
        g.at<uint8_t>(v, u) = cv::saturate_cast<uint8_t>(
            on_top ? blob.at(local) : floor.at((o + (0 - o.z()) / d.z() * d).head<2>()));
      }
    return g;
  };
  const cv::Mat g1 = image(s.pose_1, s.top_1), g2 = image(s.pose_2, s.top_2);
  const MovingTop m = find_moving_top(c, 0.25, 0.0, MovingTopParams{}, g1, g2);
  ASSERT_TRUE(m.found()) << to_string(m.reason);
  EXPECT_TRUE(m.edges);
  EXPECT_LT(yaw_error_deg(m), 1.5);
  // The votes stop up to half a patch inside the rims (moving_edges.cpp).
  for (int k = 0; k < 2; ++k) {
    EXPECT_LT(m.size_m[k], s.top_size[k] + 0.005);
    EXPECT_GT(m.size_m[k], s.top_size[k] - 0.025);
  }
  EXPECT_LT((m.p_W.head<2>() - s.top_2.c).norm(), 0.01);
  // Its velocity is the centre's: the cart's (the turn's lever arm from the blob included).
  EXPECT_NEAR(m.v_W.x(), 0.9, 0.05);
  // The yaw's variance covers its error; the features' did not.
  EXPECT_LT(yaw_error_deg(m), 3 * std::sqrt(m.var_yaw) * 180 / M_PI);
}

// A top printed all over, seen from beside it: its pixels follow its motion everywhere and its
// rims give the axes; the features cover the votes' rectangle, so their extent along those axes
// gives the sides (the votes can carry a side face or the platform's shadow past a rim).
TEST(MovingTopTest, ATopPrintedAllOverIsMeasuredOnItsRimsAxes) {
  const MovingScene s = moving_cart_scene();
  const MovingTop m = printed_cart(s);
  ASSERT_TRUE(m.found()) << to_string(m.reason);
  EXPECT_TRUE(m.edges);
  EXPECT_NEAR(m.size_m[0], s.top_size.x(), 0.015);
  EXPECT_NEAR(m.size_m[1], s.top_size.y(), 0.015);
  EXPECT_LT(std::abs(std::remainder(m.yaw_rad - s.top_2.psi, M_PI / 2)) * 180 / M_PI, 2.0);
  EXPECT_LT((m.p_W.head<2>() - s.top_2.c).norm(), 0.01);
}

// A top creeping 4 mm over the interval (the camera flies 25 cm over it, so the floor does not
// carry its matches): the two hypotheses read the same pixels of the earlier image, so its
// pixels give no verdict and its motion is kept.
TEST(MovingTopTest, ACreepingTopsPixelsGiveNoVerdict) {
  MovingScene s = moving_cart_scene();
  s.pose_2 = MovingScene::at({0.25, 0.0, 1.5}, 0.3);
  s.pose_2.utime = 1'250'000;
  s.top_2 = s.top_1;
  s.top_2.c += Vector2d(0.004, 0.0);
  const Print print = Print::random(21), floor = Print::random(22);
  const cv::Mat g1 = render(s, s.pose_1, s.top_1, s.top_size, print, floor);
  const cv::Mat g2 = render(s, s.pose_2, s.top_2, s.top_size, print, floor);
  const MovingTop m = find_moving_top(s.correspondences(), 0.25, 0.0, MovingTopParams{}, g1, g2);
  ASSERT_TRUE(m.found()) << to_string(m.reason);
  EXPECT_TRUE(std::isnan(m.ncc_still) && std::isnan(m.ncc_moving))
      << "still " << m.ncc_still << " moving " << m.ncc_moving;
  EXPECT_NEAR(m.v_W.x(), 0.016, 0.03);
}

// A floor of one pattern repeated every 0.6 m (a chessboard's squares, tiles): 150 of its features
// match the next copy in the later view and share that displacement, 2.4 m/s over 0.25 s, more
// matches than the cart's top holds. No platform the vehicle follows moves so: that set is set
// aside and the top, the next common motion, measured. Without a top the repeated floor is
// refused as too fast.
TEST(MovingTopTest, AFloorPatternMatchedToItsNextCopyIsSetAsideForTheTop) {
  MovingScene s = moving_cart_scene();
  const Vector2d period(0.6, 0.0);
  const auto with_repeats = [&](Correspondences c) {
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> ux(-0.9, 0.3), uy(-0.6, 0.6);
    for (int added = 0; added < 150;) {
      const Vector3d f(ux(rng), uy(rng), 0.0);
      const auto p1 = s.project(s.pose_1, f);
      const auto p2 = s.project(s.pose_2, f + Vector3d(period.x(), period.y(), 0.0));
      if (!p1 || !p2) continue;
      c.u1.push_back(*p1);
      c.u2.push_back(*p2);
      c.x1.push_back((s.camera.K() * s.camera.ray(*p1)).hnormalized());
      c.x2.push_back((s.camera.K() * s.camera.ray(*p2)).hnormalized());
      ++added;
    }
    return c;
  };
  const Correspondences c = with_repeats(s.correspondences());
  const MovingTopParams params;
  const MovingTop m = find_moving_top(c, 0.25, 0.0, params);
  ASSERT_TRUE(m.found()) << to_string(m.reason);
  // The repeated floor's matches (appended last) are not taken.
  for (size_t i = c.size() - 150; i < c.size(); ++i) EXPECT_EQ(m.inliers[i], 0) << i;
  EXPECT_GE(m.n_inliers, 40);
  EXPECT_NEAR(m.v_W.x(), 0.9, 0.1);
  EXPECT_NEAR(m.v_W.y(), 0.0, 0.1);
  s.with_top = false;
  EXPECT_EQ(find_moving_top(with_repeats(s.correspondences()), 0.25, 0.0, params).reason,
            MovingReason::kTooFast);
}

TEST(MovingTopTest, RefusesAPlatformFasterThanTheBound) {
  MovingScene s = moving_cart_scene();
  MovingTopParams params;
  params.max_speed_mps = 0.5;
  const MovingTop m = find_moving_top(s.correspondences(), 0.25, 0.0, params);
  EXPECT_EQ(m.reason, MovingReason::kTooFast) << to_string(m.reason);
}

TEST(MovingTopTest, TheSimilarityFitIsExactOnExactPoints) {
  Similarity2 S;
  S.s = 1.03, S.theta = 0.2, S.t = {0.4, -0.1};
  std::vector<Vector2d> p = {{0, 0}, {0.3, 0.1}, {-0.2, 0.25}, {0.1, -0.3}}, q;
  for (const auto& x : p) q.push_back(S.apply(x));
  const auto F = fit_similarity(p, q);
  ASSERT_TRUE(F);
  EXPECT_NEAR(F->s, S.s, 1e-12);
  EXPECT_NEAR(F->theta, S.theta, 1e-12);
  EXPECT_NEAR((F->t - S.t).norm(), 0, 1e-12);
  EXPECT_FALSE(fit_similarity({{1, 1}, {1, 1}}, {{0, 0}, {2, 2}}));
}

// A deck slowed to 6 cm/s for its turn under a camera hovering 1.4 m over its top (the vantage
// over a first sighting): over a quarter second it moves 1.5 cm, 7 px, and the known floor
// carries its matches within the floor test's tolerance, so its set is the floor's; against a
// frame 0.6 s old (kSlowTopIntervalGain's retry, slow_top_reference) it is measured at its speed.
TEST(MovingTopTest, ATopCreepingUnderAHoveringCameraIsMeasuredOverALongerInterval) {
  const auto creeping = [](double dt) {
    MovingScene s;
    s.pose_1 = MovingScene::at({1.0, 0.1, 1.55}, 0.2);
    s.pose_2 = MovingScene::at({1.0, 0.1, 1.55}, 0.2);
    s.pose_1.utime = 1'000'000, s.pose_2.utime = 1'000'000 + int64_t(dt * 1e6);
    s.top_1.c = {1.05, 0.15};
    s.top_1.psi = 0.1;
    s.top_size = {0.30, 0.24};
    s.top_2 = s.top_1;
    s.top_2.c += dt * Vector2d(-0.055, -0.025);
    return s;
  };
  const MovingTopParams params;
  const MovingTop quarter = find_moving_top(creeping(0.25).correspondences(), 0.25, 0.0, params);
  EXPECT_EQ(quarter.reason, MovingReason::kOnFloor) << to_string(quarter.reason);
  const MovingTop longer = find_moving_top(creeping(0.6).correspondences(), 0.6, 0.0, params);
  ASSERT_TRUE(longer.found()) << to_string(longer.reason);
  EXPECT_NEAR(longer.v_W.x(), -0.055, 0.015);
  EXPECT_NEAR(longer.v_W.y(), -0.025, 0.015);
  EXPECT_NEAR((longer.p_W.head<2>() - creeping(0.6).top_2.c).norm(), 0, 0.03);
  // What the first interval could not tell from the floor is kept (1.5 cm against a reach of
  // 1.9 cm at 1.4 m)...
  const double focal_px = CameraModel::firefly_mv_4mm().K()(0, 0);
  EXPECT_TRUE(creeping_top(longer, 0.25, focal_px, params));
  // ...a floor's repeated pattern read at 1.9 m/s over the longer interval (a chessboard's copy
  // one period on, too fast over the first) is not.
  MovingTop pattern = longer;
  pattern.v_W = Vector3d(0.0, 1.9, 0.0);
  EXPECT_FALSE(creeping_top(pattern, 0.25, focal_px, params));
  pattern.plane_z_m = pattern.camera_W.z();  // no depth: nothing kept
  pattern.v_W = longer.v_W;
  EXPECT_FALSE(creeping_top(pattern, 0.25, focal_px, params));
}

// The earlier frame a top set aside as the floor's is measured against again: the oldest at the
// current scale, if it is kSlowTopIntervalGain times the first's age or more.
TEST(MovingReferenceTest, ASlowTopIsMeasuredAgainstTheOldestFrameAtItsScale) {
  const std::vector<double> ages{0.6, 0.5, 0.4, 0.3, 0.2, 0.1};
  const std::vector<double> ranges(ages.size(), 1.4);
  EXPECT_EQ(slow_top_reference(ages, ranges, 1.4, 0.3), std::optional<size_t>(0));
  // The oldest not older enough than the first: nothing gained.
  EXPECT_EQ(slow_top_reference(ages, ranges, 1.4, 0.45), std::nullopt);
  // The oldest at another scale (a climb) is passed over for the oldest at this one.
  std::vector<double> climbing = ranges;
  climbing[0] = 1.0;
  EXPECT_EQ(slow_top_reference(ages, climbing, 1.4, 0.3), std::optional<size_t>(1));
  climbing[1] = 1.0;
  EXPECT_EQ(slow_top_reference(ages, climbing, 1.4, 0.3), std::nullopt);
  EXPECT_EQ(slow_top_reference({}, {}, 1.4, 0.25), std::nullopt);
}

// The earlier frame of the moving top's measurement (vision/pipeline.hpp, moving_reference):
// frames 33 ms apart, oldest first.
TEST(MovingReferenceTest, AtAConstantHeightTheNewestFrameAtLeastTheIntervalOld) {
  const std::vector<double> ages{0.5, 0.4, 0.3, 0.2, 0.1};
  const std::vector<double> ranges(ages.size(), 1.0);
  EXPECT_EQ(moving_reference(ages, ranges, 1.0, 0.25), std::optional<size_t>(2));
  // None old enough yet: the oldest, as long as it is within the scale bound.
  EXPECT_EQ(moving_reference({0.1, 0.033}, {1.0, 1.0}, 1.0, 0.25), std::optional<size_t>(0));
  EXPECT_EQ(moving_reference({}, {}, 1.0, 0.25), std::nullopt);
}

TEST(MovingReferenceTest, InTheLastDropTheOldestFrameWithinTheScaleBound) {
  // The camera 0.5 m/s down, 0.35 m over the top now: 1.7 cm a frame, 5 % of the range.
  std::vector<double> ages, ranges;
  for (int k = 8; k >= 1; --k) {
    ages.push_back(k / 30.0);
    ranges.push_back(0.35 + 0.5 * k / 30.0);
  }
  const auto k = moving_reference(ages, ranges, 0.35, 0.25);
  ASSERT_TRUE(k);
  // The frame 0.25 s back (0.47 m: a third farther) is beyond it; the one chosen is within it
  // and the one before is not.
  EXPECT_LE(std::abs(0.35 / ranges[*k] - 1.0), kMovingMaxScaleChange);
  ASSERT_GT(*k, 0u);
  EXPECT_GT(std::abs(0.35 / ranges[*k - 1] - 1.0), kMovingMaxScaleChange);
  EXPECT_LT(ages[*k], 0.25);
  // Closer still: a frame's descent alone is beyond the bound: nothing measured.
  EXPECT_EQ(moving_reference({0.033}, {0.12}, 0.1, 0.25), std::nullopt);
  // A camera at or below the assumed top, or a stamp not older than the current frame: no frame.
  EXPECT_EQ(moving_reference({0.3}, {0.0}, 0.0, 0.25), std::nullopt);
  EXPECT_EQ(moving_reference({0.0}, {1.0}, 1.0, 0.25), std::nullopt);
}

}  // namespace
}  // namespace alight::vision
