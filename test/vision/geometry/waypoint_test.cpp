// Waypoint geometry (paper 3.1.3, eqs. 3-6) against a scene with known world geometry: camera
// mounted off the body origin, vehicle rotating and translating between the two images.
#include "vision/geometry/waypoint.hpp"

#include <gtest/gtest.h>

#include "test/vision/synthetic.hpp"
#include "vision/geometry/homography.hpp"

namespace alight::vision {
namespace {

constexpr double kWaypointDeg = M_PI / 180.0;

struct Scene {
  CameraMount mount;
  PoseSample pose_1, pose_2;
  double plane_z_m = 0.2;  // platform top, world z [m]
  Scene() {
    mount.R_BC = R_BC_downward() *
                 rotation_from_rpy(1 * kWaypointDeg, -2 * kWaypointDeg, 0.5 * kWaypointDeg);
    mount.t_B_C = Vector3d(0.05, 0.02, -0.06);
    pose_1.p_W_B = Vector3d(0.1, -0.2, 1.5);
    pose_1.q_WB = Quaterniond(rotation_from_rpy(2 * kWaypointDeg, -1 * kWaypointDeg, 0.3));
    pose_2.p_W_B = Vector3d(0.25, -0.1, 1.45);
    pose_2.q_WB = Quaterniond(rotation_from_rpy(-1 * kWaypointDeg, 3 * kWaypointDeg, 0.4));
  }
  Isometry3d X_WC(const PoseSample& p) const { return camera_in_world(p.X_WB(), mount.X_BC()); }
  /// The true decomposition of the plane z = plane_z_m (eq. 1), in baseline units.
  PlaneMotion truth() const {
    const Isometry3d C1 = X_WC(pose_1), C2 = X_WC(pose_2);
    const double s = (C2.translation() - C1.translation()).norm();
    PlaneMotion m;
    m.R_21 = C2.linear().transpose() * C1.linear();
    m.t_12 = C1.linear().transpose() * (C2.translation() - C1.translation()) / s;
    const Vector3d n1 = -(C1.linear().transpose() * Vector3d::UnitZ());  // camera towards plane
    const double d1 = C1.translation().z() - plane_z_m;
    m.n_1 = n1 / (d1 / s);
    return m;
  }
  Vector3d ray_2(const Vector3d& p_W) const {
    const Vector3d p_C = X_WC(pose_2).inverse() * p_W;
    return p_C / p_C.z();
  }
};

TEST(WaypointTest, MocapMotionMatchesTheCameraPoses) {
  const Scene s;
  const MocapMotion m = mocap_motion(s.pose_1, s.pose_2, s.mount);
  const PlaneMotion t = s.truth();
  EXPECT_LT(rotation_angle(m.R_21, t.R_21), 1e-12);
  EXPECT_LT(direction_angle(m.t_12, t.t_12), 1e-12);
  // eq. 3: the camera baseline differs from the body translation by R_V2 t_c - R_V1 t_c.
  const Vector3d t_V = s.pose_2.p_W_B - s.pose_1.p_W_B;
  const Vector3d expected = t_V - s.pose_1.q_WB * s.mount.t_B_C + s.pose_2.q_WB * s.mount.t_B_C;
  EXPECT_NEAR(m.baseline_m, expected.norm(), 1e-12);
  EXPECT_GT(std::abs(m.baseline_m - t_V.norm()), 1e-4);  // the offset matters here
}

TEST(WaypointTest, ExactDecompositionGivesTheExactWorldPoint) {
  const Scene s;
  const Vector3d p_W_target(0.3, 0.1, s.plane_z_m);
  const auto w = compute_waypoint(s.truth(), s.ray_2(p_W_target), s.pose_1, s.pose_2, s.mount);
  ASSERT_TRUE(w) << to_string(w.reason());
  EXPECT_LT((w->p_W - p_W_target).norm(), 1e-9);
  EXPECT_LT((w->n_W - Vector3d::UnitZ()).norm(), 1e-9);  // towards the camera: up
  EXPECT_NEAR(w->distance_m, s.X_WC(s.pose_2).translation().z() - s.plane_z_m, 0.05);
}

TEST(WaypointTest, DecomposedHomographyGivesTheWorldPoint) {
  const Scene s;
  const PlaneMotion t = s.truth();
  std::vector<Vector3d> r1, r2;
  for (double x = -0.2; x <= 0.2; x += 0.1)
    for (double y = -0.3; y <= 0.3; y += 0.1) {
      const Vector3d p_W(x, y, s.plane_z_m);
      const Vector3d p1 = s.X_WC(s.pose_1).inverse() * p_W;
      r1.push_back(p1 / p1.z());
      r2.push_back(s.ray_2(p_W));
    }
  DecompositionPrior prior;
  prior.R_21 = mocap_motion(s.pose_1, s.pose_2, s.mount).R_21;
  const auto d = decompose(-2.0 * t.homography(), r1, r2, prior);
  ASSERT_TRUE(d);
  const Vector3d p_W_target(-0.1, 0.2, s.plane_z_m);
  const auto w = compute_waypoint(*d, s.ray_2(p_W_target), s.pose_1, s.pose_2, s.mount);
  ASSERT_TRUE(w);
  EXPECT_LT((w->p_W - p_W_target).norm(), 1e-9);
}

TEST(WaypointTest, NoisyCorrespondencesGiveCentimetreAccuracyAtOnePointFiveMetres) {
  // 20 cm baseline at about 1.3 m above the platform top, 0.3 px noise, 200 matches.
  const Scene s;
  const auto K = CameraModel::firefly_mv_4mm().K();
  std::mt19937_64 rng(4);
  std::normal_distribution<double> noise(0, 0.3);
  std::uniform_real_distribution<double> ux(-0.4, 0.6), uy(-0.6, 0.4);
  std::vector<Vector2d> x1, x2;
  for (int i = 0; i < 200; ++i) {
    const Vector3d p_W(ux(rng), uy(rng), s.plane_z_m);
    const Vector3d p1 = s.X_WC(s.pose_1).inverse() * p_W;
    const Vector2d q1 = (K * p1).hnormalized(), q2 = (K * s.ray_2(p_W)).hnormalized();
    x1.push_back(q1 + Vector2d(noise(rng), noise(rng)));
    x2.push_back(q2 + Vector2d(noise(rng), noise(rng)));
  }
  const auto fit = fit_homography(x1, x2, HomographyParams{});
  ASSERT_TRUE(fit);
  DecompositionPrior prior;
  prior.R_21 = mocap_motion(s.pose_1, s.pose_2, s.mount).R_21;
  const auto d =
      decompose(calibrate_homography(fit->H, K), testing::rays(K, x1), testing::rays(K, x2), prior);
  ASSERT_TRUE(d);
  const Vector3d p_W_target(0.1, -0.1, s.plane_z_m);
  const auto w = compute_waypoint(*d, s.ray_2(p_W_target), s.pose_1, s.pose_2, s.mount);
  ASSERT_TRUE(w);
  EXPECT_LT((w->p_W - p_W_target).head<2>().norm(), 0.01);
  EXPECT_LT(std::abs(w->p_W.z() - p_W_target.z()), 0.03);
}

TEST(WaypointTest, TooSmallBaselineIsRefused) {
  Scene s;
  s.pose_2 = s.pose_1;
  s.pose_2.p_W_B.x() += 0.01;
  const auto w = compute_waypoint(s.truth(), Vector3d(0, 0, 1), s.pose_1, s.pose_2, s.mount);
  EXPECT_FALSE(w);
  EXPECT_EQ(w.reason(), Reason::kSmallBaseline);
}

TEST(WaypointTest, MotionContradictingMotionCaptureIsRefused) {
  const Scene s;
  PlaneMotion wrong = s.truth();
  wrong.t_12 = -wrong.t_12;
  const auto w = compute_waypoint(wrong, Vector3d(0, 0, 1), s.pose_1, s.pose_2, s.mount);
  EXPECT_FALSE(w);
  EXPECT_EQ(w.reason(), Reason::kMotionDisagrees);
}

TEST(WaypointTest, RayParallelToThePlaneIsRefused) {
  const Scene s;
  PlaneMotion m = s.truth();
  const Vector3d n2 = m.n_2();
  const Vector3d ray = n2.cross(Vector3d::UnitX());  // n2^T ray = 0
  const auto w = compute_waypoint(m, ray / ray.z(), s.pose_1, s.pose_2, s.mount);
  EXPECT_FALSE(w);
  EXPECT_EQ(w.reason(), Reason::kAimBehindCamera);
}

TEST(WaypointTest, RayMeetingThePlaneBehindTheCameraIsRefused) {
  const Scene s;
  const PlaneMotion m = s.truth();
  // A ray past the plane's horizon (n2^T ray < 0, in front of the camera: z > 0) meets the plane
  // only behind the camera.
  const Vector3d n2 = m.n_2();
  Vector3d along = n2.cross(Vector3d::UnitX());
  if (along.z() < 0) along = -along;
  ASSERT_GT(along.z(), 1e-6);
  const Vector3d ray = along - 0.5 * along.z() / n2.z() * n2;
  ASSERT_GT(ray.z(), 0);
  ASSERT_LT(n2.dot(ray), 0);
  const auto w = compute_waypoint(m, ray / ray.z(), s.pose_1, s.pose_2, s.mount);
  EXPECT_FALSE(w);
  EXPECT_EQ(w.reason(), Reason::kAimBehindCamera);
}

TEST(WaypointTest, PatternAngleFollowsTheCameraYaw) {
  // A downward camera yawed by psi sees the world x axis rotated by -psi... in image terms the
  // angle changes by exactly the yaw difference.
  const Matrix3d R_a = rotation_from_rpy(0, 0, 0.1) * R_BC_downward();
  const Matrix3d R_b = rotation_from_rpy(0, 0, 0.6) * R_BC_downward();
  const double d =
      wrap_angle(pattern_angle(R_b, Vector3d::UnitX()) - pattern_angle(R_a, Vector3d::UnitX()));
  EXPECT_NEAR(std::abs(d), 0.5, 1e-12);
}

}  // namespace
}  // namespace alight::vision
