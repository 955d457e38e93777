// The known floor's homography from motion-capture poses and the level top fitted with the
// known motion (vision/geometry/known_floor.hpp).

#include "vision/geometry/known_floor.hpp"

#include <gtest/gtest.h>

#include <random>

#include "common/camera_model.hpp"
#include "vision/geometry/decomposition.hpp"
#include "vision/geometry/waypoint.hpp"

namespace alight::vision {
namespace {

constexpr double kDeg = M_PI / 180.0;

PoseSample pose(const Vector3d& p_W_B, double roll, double pitch, double yaw) {
  PoseSample s;
  s.p_W_B = p_W_B;
  s.q_WB = Eigen::AngleAxisd(yaw, Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Vector3d::UnitY()) *
           Eigen::AngleAxisd(roll, Vector3d::UnitX());
  return s;
}

CameraMount downward() {
  CameraMount m;
  m.t_B_C = Vector3d(0.05, 0.0, -0.06);
  return m;
}

// Pixel of a world point in the camera at pose, or nothing when behind it.
std::optional<Vector2d> project(const Matrix3d& K, const PoseSample& p, const CameraMount& mount,
                                const Vector3d& X_W) {
  const Vector3d X_C = camera_in_world(p.X_WB(), mount.X_BC()).inverse() * X_W;
  if (X_C.z() <= 0) return std::nullopt;
  return (K * X_C).hnormalized();
}

TEST(KnownFloorTest, HomographyFromPosesMapsFloorPointsExactly) {
  const Matrix3d K = CameraModel::firefly_mv_4mm().K();
  const CameraMount mount = downward();
  const double floor_z = 0.07;
  const PoseSample p1 = pose({0.3, -0.2, 1.4}, 2 * kDeg, -3 * kDeg, 20 * kDeg);
  const PoseSample p2 = pose({0.42, -0.11, 1.31}, -1 * kDeg, 2 * kDeg, 27 * kDeg);
  const auto floor = known_floor(p1, mount, floor_z);
  ASSERT_TRUE(floor);
  // Camera 1 centre above the floor, its axis nearly down.
  const Isometry3d X_WC1 = camera_in_world(p1.X_WB(), mount.X_BC());
  EXPECT_NEAR(floor->d_1_m, X_WC1.translation().z() - floor_z, 1e-12);
  EXPECT_LT(direction_angle(floor->n_1, Vector3d::UnitZ()), 5 * kDeg);
  const MocapMotion m = mocap_motion(p1, p2, mount);
  const Matrix3d H =
      K * plane_homography({m.R_21, m.t_12}, floor->n_1, 1.0 / floor->d_1_m) * K.inverse();
  int n = 0;
  for (double x = -0.6; x <= 1.2; x += 0.15)
    for (double y = -0.8; y <= 0.4; y += 0.15) {
      const Vector3d X_W(x, y, floor_z);
      const auto u1 = project(K, p1, mount, X_W), u2 = project(K, p2, mount, X_W);
      if (!u1 || !u2) continue;
      EXPECT_LT(((H * u1->homogeneous()).hnormalized() - *u2).norm(), 1e-6);
      ++n;
    }
  EXPECT_GT(n, 50);
  // A point 20 cm above the floor does not map: the homography is the floor's only.
  const Vector3d X_W(0.4, -0.2, floor_z + 0.2);
  const auto u1 = project(K, p1, mount, X_W), u2 = project(K, p2, mount, X_W);
  ASSERT_TRUE(u1 && u2);
  EXPECT_GT(((H * u1->homogeneous()).hnormalized() - *u2).norm(), 3.0);
}

TEST(KnownFloorTest, NoFloorBelowACameraUnderIt) {
  EXPECT_FALSE(known_floor(pose({0, 0, 0.02}, 0, 0, 0), downward(), 0.5));
}

// A downward camera over a floor with a level platform top; rays of matches with pixel noise,
// a share of mismatches, and motion capture's R21 off by a small rotation.
struct Scene {
  std::vector<Vector3d> r1, r2;
  std::vector<int> label;  // 0 floor, 1 top, -1 mismatch
  KnownMotion mocap;
  KnownPlane floor;
};

struct SceneShape {
  double camera_z_m = 1.35;  ///< camera 1 height, +-0.1 [m]
  double baseline_min_m = 0.12, baseline_max_m = 0.28;
  Vector2d top_half_m = Vector2d(0.15, 0.12);
  double descent_m = 0.0;  ///< camera 2 this much lower than camera 1 (the approach) [m]
};

Scene make_scene(uint64_t seed, double height_m, int n_floor, int n_top, int n_out,
                 double rot_err_rad, const SceneShape& shape = {}) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1, 1);
  std::normal_distribution<double> G(0, 1);
  const Matrix3d K = CameraModel::firefly_mv_4mm().K();
  const double f = K(0, 0);
  const CameraMount mount = downward();
  const PoseSample p1 = pose({0.1 * U(rng), 0.1 * U(rng), shape.camera_z_m + 0.1 * U(rng)},
                             0.02 * U(rng), 0.02 * U(rng), U(rng));
  // The pipeline's references are up to 0.3 m back (max_reference_baseline_m): 12-28 cm here.
  const double dir = M_PI * U(rng),
               len = shape.baseline_min_m +
                     0.5 * (shape.baseline_max_m - shape.baseline_min_m) * (1 + U(rng));
  const Vector3d step(len * std::cos(dir), len * std::sin(dir), 0.03 * U(rng) - shape.descent_m);
  const PoseSample p2 = pose(p1.p_W_B + step, 0.02 * U(rng), 0.02 * U(rng), U(rng) * 0.05);
  Scene s;
  s.floor = *known_floor(p1, mount, 0.0);
  const MocapMotion m = mocap_motion(p1, p2, mount);
  const Vector3d w(G(rng), G(rng), G(rng));
  s.mocap = {Eigen::AngleAxisd(rot_err_rad, w.normalized()).toRotationMatrix() * m.R_21, m.t_12};
  const Vector3d below = p1.p_W_B;
  const auto add = [&](const Vector3d& X_W, int label) {
    const auto u1 = project(K, p1, mount, X_W), u2 = project(K, p2, mount, X_W);
    if (!u1 || !u2) return false;
    const Vector2d n1(0.4 * G(rng), 0.4 * G(rng)), n2(0.4 * G(rng), 0.4 * G(rng));
    s.r1.push_back(K.inverse() * (*u1 + n1).homogeneous());
    s.r2.push_back(K.inverse() * (*u2 + n2).homogeneous());
    s.label.push_back(label);
    return true;
  };
  for (int k = 0; k < n_floor;)
    k += add(Vector3d(below.x() + 0.7 * U(rng), below.y() + 0.55 * U(rng), 0.0), 0);
  for (int k = 0; k < n_top;)  // a 30 x 25 cm top under the camera
    k += add(Vector3d(below.x() + shape.top_half_m.x() * U(rng),
                      below.y() + shape.top_half_m.y() * U(rng), height_m),
             1);
  for (int k = 0; k < n_out; ++k) {  // mismatches: random pixel pairs
    s.r1.push_back(K.inverse() * Vector2d(320 + 300 * U(rng), 240 + 220 * U(rng)).homogeneous());
    s.r2.push_back(K.inverse() * Vector2d(320 + 300 * U(rng), 240 + 220 * U(rng)).homogeneous());
    s.label.push_back(-1);
  }
  (void)f;
  return s;
}

TEST(KnownFloorTest, RecoversThePlatformHeightFromNoisyMatchesWithOutliers) {
  const double f = CameraModel::firefly_mv_4mm().K()(0, 0);
  LandingParams params;
  int n_ok = 0;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    const double h = 0.08 + 0.14 * static_cast<double>(seed % 7) / 6.0;  // the families' tops
    // Few floor matches (the tile floor), more on the top, a fifth mismatches; R21 0.15 deg off.
    const Scene s = make_scene(seed, h, 8, 40, 12, 0.15 * kDeg);
    const auto fit = fit_known_floor_planes(s.r1, s.r2, s.mocap, s.floor, f, params, 2.0);
    ASSERT_TRUE(fit) << "seed " << seed << ": " << to_string(fit.reason());
    EXPECT_NEAR(fit->height_m(), h, 0.015) << "seed " << seed;
    EXPECT_LT(fit->rotation_correction_rad, 0.3 * kDeg);
    int top_right = 0, top_wrong = 0;
    for (size_t i = 0; i < s.label.size(); ++i) {
      top_right += fit->top[i] && s.label[i] == 1;
      top_wrong += fit->top[i] && s.label[i] != 1;
    }
    EXPECT_GE(top_right, params.min_platform_inliers) << "seed " << seed;
    EXPECT_LE(top_wrong, 1) << "seed " << seed;
    n_ok += std::abs(fit->height_m() - h) < 0.01;
  }
  EXPECT_GE(n_ok, 36);  // most within 1 cm
}

// Regression (issue 15, landing_tiles seed 8001: target lost in approach): over flat tiles the
// platform top holds 20 times the floor's matches, and from 1.5 m over a 12-18 cm baseline a
// 9 cm top moves 3-5 px against the floor, about twice the threshold. The hypothesis that took
// the top for the floor (its rotation correction absorbing the parallax) outscored the truth,
// and the refinement, fitted to the top's matches off the floor's band only, drifted into it.
TEST(KnownFloorTest, LowTopWithMostMatchesIsNotTakenForTheFloor) {
  const double f = CameraModel::firefly_mv_4mm().K()(0, 0);
  LandingParams params;
  SceneShape shape;
  shape.camera_z_m = 1.5;
  shape.baseline_min_m = 0.12;
  shape.baseline_max_m = 0.18;
  shape.top_half_m = Vector2d(0.13, 0.11);
  int n_ok = 0;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    const Scene s = make_scene(seed, 0.09, 15, 300, 20, 0.1 * kDeg, shape);
    const auto fit = fit_known_floor_planes(s.r1, s.r2, s.mocap, s.floor, f, params, 2.0);
    if (!fit) continue;  // the top inside the floor's band: honestly no platform
    int top_wrong = 0;
    for (size_t i = 0; i < s.label.size(); ++i) top_wrong += fit->top[i] && s.label[i] != 1;
    EXPECT_LE(top_wrong, 1) << "seed " << seed;
    n_ok += std::abs(fit->height_m() - 0.09) < 0.01 && fit->n_top >= params.min_platform_inliers;
  }
  EXPECT_GE(n_ok, 36);  // was 22
}

TEST(KnownFloorTest, BareFloorWithMismatchesHasNoTop) {
  const double f = CameraModel::firefly_mv_4mm().K()(0, 0);
  LandingParams params;
  for (uint64_t seed = 1; seed <= 30; ++seed) {
    const Scene s = make_scene(100 + seed, 0.2, 80, 0, 30, 0.15 * kDeg);
    const auto fit = fit_known_floor_planes(s.r1, s.r2, s.mocap, s.floor, f, params, 2.0);
    ASSERT_FALSE(fit) << "seed " << seed << ": a top of " << fit->n_top;
    EXPECT_TRUE(
        fit.reason() == Reason::kTopMatchesFew || fit.reason() == Reason::kNoTopHeight ||
        (fit.reason() >= Reason::kTopNotParallel && fit.reason() <= Reason::kTopAloneLowParallax))
        << to_string(fit.reason());
  }
}

// The known floor names why it has no top: a bare floor whose matches all carry with it has
// nothing at a top's height; a top 9 cm up holding 6 matches (a small top seen from far, under
// min_platform_inliers 12) has a height its matches share, too few of them. Neither is the
// paper's second homography (NO_TARGET_PLANE), and both leave the frame to the outline search.
TEST(KnownFloorTest, ABareFloorHasNoTopHeightAndAFewMatchesTopTooFewMatches) {
  const double f = CameraModel::firefly_mv_4mm().K()(0, 0);
  LandingParams params;
  int bare_no_height = 0, small_few = 0;
  for (uint64_t seed = 1; seed <= 10; ++seed) {
    const Scene bare = make_scene(300 + seed, 0.09, 80, 0, 0, 0.15 * kDeg);
    const auto none =
        fit_known_floor_planes(bare.r1, bare.r2, bare.mocap, bare.floor, f, params, 2.0);
    ASSERT_FALSE(none) << "seed " << seed;
    bare_no_height += none.reason() == Reason::kNoTopHeight;
    const Scene small = make_scene(400 + seed, 0.09, 80, 6, 0, 0.15 * kDeg);
    const auto few =
        fit_known_floor_planes(small.r1, small.r2, small.mocap, small.floor, f, params, 2.0);
    ASSERT_FALSE(few) << "seed " << seed;
    small_few += few.reason() == Reason::kTopMatchesFew;
    EXPECT_TRUE(no_top_plane(none.reason()) && no_top_plane(few.reason()))
        << to_string(none.reason()) << ", " << to_string(few.reason());
  }
  EXPECT_GE(bare_no_height, 9);
  EXPECT_GE(small_few, 9);
}

// The approach's last metre over a top on a bland floor (landing_lowtex seed 9917, lost in the
// approach with the camera 0.65 m over a paper top: every match on the top, none on the floor):
// the pair has no floor, the top alone is found at its height.
SceneShape close_over_the_top() {
  SceneShape shape;
  shape.camera_z_m = 0.85;      // 0.53-0.87 m over the tops
  shape.baseline_min_m = 0.03;  // mostly the descent: 0.25 m/s over the reference's age
  shape.baseline_max_m = 0.10;
  shape.descent_m = 0.25;
  shape.top_half_m = Vector2d(0.25, 0.2);  // filling most of the view
  return shape;
}

TEST(KnownFloorTest, TopFillingTheViewOverABlandFloorIsFoundAlone) {
  const double f = CameraModel::firefly_mv_4mm().K()(0, 0);
  LandingParams params;
  int n_ok = 0;
  for (uint64_t seed = 1; seed <= 30; ++seed) {
    const double h = 0.08 + 0.14 * static_cast<double>(seed % 7) / 6.0;
    const Scene s = make_scene(200 + seed, h, 2, 120, 10, 0.1 * kDeg, close_over_the_top());
    EXPECT_FALSE(fit_known_floor_planes(s.r1, s.r2, s.mocap, s.floor, f, params, 2.0))
        << "seed " << seed << ": the pair needs a floor";
    const auto fit = fit_known_top_alone(s.r1, s.r2, s.mocap, s.floor, f, params, 2.0);
    ASSERT_TRUE(fit) << "seed " << seed << ": " << to_string(fit.reason());
    EXPECT_NEAR(fit->height_m(), h, 0.02) << "seed " << seed;
    int top_right = 0, top_wrong = 0;
    for (size_t i = 0; i < s.label.size(); ++i) {
      top_right += fit->top[i] && s.label[i] == 1;
      top_wrong += fit->top[i] && s.label[i] != 1;
    }
    // Of 120: those near the descent's epipole fit both planes and count for neither.
    EXPECT_GE(top_right, 50) << "seed " << seed;
    EXPECT_LE(top_wrong, 1) << "seed " << seed;
    EXPECT_LT(direction_angle(fit->n_top_free_1, s.floor.n_1), 5 * kDeg) << "seed " << seed;
    n_ok += std::abs(fit->height_m() - h) < 0.01;
  }
  EXPECT_GE(n_ok, 27);  // most within 1 cm
}

// Where the floor is seen around the top, the pair decides; a floor alone, textured or bland
// with mismatches, is never a top alone; 0 turns it off.
TEST(KnownFloorTest, TopAloneOnlyWhereTheFloorIsOutOfSight) {
  const double f = CameraModel::firefly_mv_4mm().K()(0, 0);
  LandingParams params;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    const Scene with_floor = make_scene(300 + seed, 0.15, 30, 100, 10, 0.1 * kDeg);
    EXPECT_FALSE(fit_known_top_alone(with_floor.r1, with_floor.r2, with_floor.mocap,
                                     with_floor.floor, f, params, 2.0))
        << "seed " << seed;
    const Scene bare = make_scene(400 + seed, 0.15, 80, 0, 20, 0.15 * kDeg);
    EXPECT_FALSE(fit_known_top_alone(bare.r1, bare.r2, bare.mocap, bare.floor, f, params, 2.0))
        << "seed " << seed;
    const Scene bland = make_scene(500 + seed, 0.15, 3, 0, 25, 0.15 * kDeg, close_over_the_top());
    EXPECT_FALSE(fit_known_top_alone(bland.r1, bland.r2, bland.mocap, bland.floor, f, params, 2.0))
        << "seed " << seed;
  }
  // Deterministic; non-finite rays are outliers, no input a crash.
  {
    const Scene s = make_scene(202, 0.15, 2, 120, 10, 0.1 * kDeg, close_over_the_top());
    const auto a = fit_known_top_alone(s.r1, s.r2, s.mocap, s.floor, f, params, 2.0);
    const auto b = fit_known_top_alone(s.r1, s.r2, s.mocap, s.floor, f, params, 2.0);
    ASSERT_TRUE(a && b);
    EXPECT_EQ(a->rho_top, b->rho_top);
    EXPECT_EQ(a->top, b->top);
    Scene bad = s;
    for (size_t i = 0; i < bad.r1.size(); i += 5) bad.r2[i] = Vector3d::Constant(NAN);
    const auto c = fit_known_top_alone(bad.r1, bad.r2, bad.mocap, bad.floor, f, params, 2.0);
    ASSERT_TRUE(c) << to_string(c.reason());
    EXPECT_NEAR(c->height_m(), 0.15, 0.02);
    EXPECT_FALSE(fit_known_top_alone({}, {}, s.mocap, s.floor, f, params, 2.0));
    EXPECT_FALSE(fit_known_top_alone(s.r1, {}, s.mocap, s.floor, f, params, 2.0));
  }
  // A floor alone whose every parallax is 4 % long (motion capture's baseline 4 % short: a pose a
  // few milliseconds off its image) looks like one plane 4 % nearer: no top.
  int refused_for_rise = 0;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    Scene biased = make_scene(600 + seed, 0.15, 80, 0, 5, 0.05 * kDeg, close_over_the_top());
    biased.mocap.t_12_m *= 1.0 / 1.04;
    const auto fit =
        fit_known_top_alone(biased.r1, biased.r2, biased.mocap, biased.floor, f, params, 2.0);
    EXPECT_FALSE(fit) << "seed " << seed;
    refused_for_rise += !fit && fit.reason() == Reason::kTopAloneLowRise;
  }
  EXPECT_GE(refused_for_rise, 10);  // the rule, not another, refuses them
  // A bland floor over a 3 cm baseline with motion capture's rotation 0.4 deg off (landing_lowtex
  // 9917, sim seed 1: a "top" 36 cm up in detection, refinement sent after it): no top alone.
  SceneShape short_base = close_over_the_top();
  short_base.camera_z_m = 1.5;
  short_base.baseline_min_m = short_base.baseline_max_m = 0.03;
  short_base.descent_m = 0;
  LandingParams no_angle = params;
  no_angle.max_rotation_correction_deg = 1e-6;
  int taken_without_angle = 0;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    const Scene s = make_scene(700 + seed, 0.15, 60, 0, 5, 0.4 * kDeg, short_base);
    EXPECT_FALSE(fit_known_top_alone(s.r1, s.r2, s.mocap, s.floor, f, params, 2.0))
        << "seed " << seed;
    taken_without_angle +=
        static_cast<bool>(fit_known_top_alone(s.r1, s.r2, s.mocap, s.floor, f, no_angle, 2.0));
  }
  EXPECT_GE(taken_without_angle, 2);  // the rule, not another, refuses these
  // A photographed floor seen climbing (the baseline along the optical axis) with the rotation
  // 0.4 deg off (landing_none_photo 9776, after take-off: a "top" 25 cm up on 36 matches). A
  // plane's parallax grows from nothing at the epipole, the view's centre: the angle rule
  // measures it where the top's matches are, not as baseline times the inverse distances'
  // difference, which passes every one of the tops below.
  SceneShape climb = short_base;
  climb.camera_z_m = 1.45;
  climb.baseline_min_m = 0.0;
  climb.baseline_max_m = 0.02;
  climb.descent_m = -0.17;
  int taken_in_climb = 0, across_axis_passes = 0;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    const Scene s = make_scene(800 + seed, 0.15, 120, 0, 5, 0.4 * kDeg, climb);
    EXPECT_FALSE(fit_known_top_alone(s.r1, s.r2, s.mocap, s.floor, f, params, 2.0))
        << "seed " << seed;
    const auto taken = fit_known_top_alone(s.r1, s.r2, s.mocap, s.floor, f, no_angle, 2.0);
    if (!taken) continue;
    ++taken_in_climb;
    across_axis_passes += s.mocap.t_12_m.norm() * (taken->rho_top - taken->rho_floor) >=
                          params.max_rotation_correction_deg * kDeg;
  }
  EXPECT_GE(taken_in_climb, 2);
  EXPECT_EQ(across_axis_passes, taken_in_climb);
  const Scene s = make_scene(201, 0.15, 2, 120, 10, 0.1 * kDeg, close_over_the_top());
  EXPECT_TRUE(fit_known_top_alone(s.r1, s.r2, s.mocap, s.floor, f, params, 2.0));
}

TEST(KnownFloorTest, DeterministicAndRefusesAbsurdInput) {
  const double f = CameraModel::firefly_mv_4mm().K()(0, 0);
  LandingParams params;
  const Scene s = make_scene(7, 0.25, 10, 30, 10, 0.1 * kDeg);
  const auto a = fit_known_floor_planes(s.r1, s.r2, s.mocap, s.floor, f, params, 2.0);
  const auto b = fit_known_floor_planes(s.r1, s.r2, s.mocap, s.floor, f, params, 2.0);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->rho_top, b->rho_top);
  EXPECT_EQ(a->top, b->top);
  // No translation: no parallax to tell planes by.
  KnownMotion still = s.mocap;
  still.t_12_m.setZero();
  EXPECT_EQ(fit_known_floor_planes(s.r1, s.r2, still, s.floor, f, params, 2.0).reason(),
            Reason::kSmallBaseline);
  // Non-finite rays are outliers, never a crash.
  Scene bad = s;
  for (size_t i = 0; i < bad.r1.size(); i += 5) bad.r2[i] = Vector3d::Constant(NAN);
  const auto c = fit_known_floor_planes(bad.r1, bad.r2, bad.mocap, bad.floor, f, params, 2.0);
  ASSERT_TRUE(c) << to_string(c.reason());
  EXPECT_NEAR(c->height_m(), 0.25, 0.02);
}

}  // namespace
}  // namespace alight::vision
