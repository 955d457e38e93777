// Two rendered views (alight_sim, issue 3) of a floor with a platform of the paper (landing_a:
// 43.2 x 27.9 x 10.9 cm): the whole library chain from pixels to the world waypoint. Camera at
// about 1.5 m, 20 cm baseline. Both planes are found, the decomposition agrees with the true
// motion and the platform-centre waypoint lands within 1 cm of the truth.
#include <gtest/gtest.h>

#include "sim/params.hpp"
#include "sim/renderer.hpp"
#include "sim/scene.hpp"
#include "vision/alignment.hpp"
#include "vision/homography.hpp"
#include "vision/matcher.hpp"
#include "vision/star_detector.hpp"
#include "vision/surf_descriptor.hpp"
#include "vision/waypoint.hpp"

namespace alight::vision {
namespace {

constexpr double kDeg = M_PI / 180.0;

struct View {
  cv::Mat image;
  std::vector<Keypoint> kps;
  cv::Mat desc;
};

View describe(const cv::Mat& image) {
  View v;
  v.image = image;
  const cv::Mat I = integral_image(image);
  const auto k = detect_star(image, I, StarParams{});
  EXPECT_TRUE(k) << to_string(k.reason());
  if (k) v.kps = *k;
  v.desc = describe_surf(I, v.kps, SurfParams{});
  return v;
}

class SimTwoViewsTest : public ::testing::TestWithParam<uint64_t> {};

TEST_P(SimTwoViewsTest, PlatformWaypointWithinOneCentimetreAtOnePointFiveMetres) {
  const std::string root = ALIGHT_SOURCE_DIR;
  const auto scenario = sim::load_scenario(root + "/config/scenarios/landing_a.yaml");
  const auto scene = sim::build_scene(scenario, GetParam());
  const auto rig = sim::load_camera_rig(root + "/config/vehicles/starmac.yaml", "downward");
  ASSERT_TRUE(scene.platform.has_value());
  const Vector3d p_W_top = scene.platform->top_center_W;
  const sim::Renderer renderer(rig.model);
  const CameraModel& cam = rig.model;

  PoseSample pose_1, pose_2;
  pose_1.p_W_B = Vector3d(p_W_top.x() - 0.1, p_W_top.y() + 0.05, 1.5);
  pose_1.q_WB = Quaterniond(rotation_from_rpy(1 * kDeg, -2 * kDeg, 0.2));
  pose_2.p_W_B = pose_1.p_W_B + Vector3d(0.2, -0.03, 0.01);
  pose_2.q_WB = Quaterniond(rotation_from_rpy(-1 * kDeg, 1 * kDeg, 0.23));
  auto X_WC = [&](const PoseSample& p) { return camera_in_world(p.X_WB(), rig.mount.X_BC()); };
  const View a = describe(renderer.render(scene, X_WC(pose_1)));
  const View b = describe(renderer.render(scene, X_WC(pose_2)));

  const auto sa = response_signs(a.kps), sb = response_signs(b.kps);
  const auto matches = match_descriptors(a.desc, b.desc, MatchParams{}, &sa, &sb);
  // Undistorted pixels (K times the normalised ray) for the homographies.
  const Matrix3d K = cam.K();
  std::vector<Vector2d> x1, x2;
  for (const auto& m : matches) {
    x1.push_back((K * cam.ray({a.kps[m.i1].x, a.kps[m.i1].y})).hnormalized());
    x2.push_back((K * cam.ray({b.kps[m.i2].x, b.kps[m.i2].y})).hnormalized());
  }
  const auto floor = fit_homography(x1, x2, HomographyParams{});
  ASSERT_TRUE(floor) << to_string(floor.reason());
  std::vector<Vector2d> o1, o2;
  for (size_t i = 0; i < x1.size(); ++i)
    if (!floor->inlier[i]) o1.push_back(x1[i]), o2.push_back(x2[i]);
  const auto top = fit_homography(o1, o2, HomographyParams{}, Sampling::kLocal);
  ASSERT_TRUE(top) << to_string(top.reason()) << " (" << o1.size() << " off-floor matches)";
  std::printf("sim views: %zu matches, first plane %d inliers, second plane %d inliers\n",
              matches.size(), floor->n_inliers, top->n_inliers);

  auto rays = [&](const std::vector<Vector2d>& p, const std::vector<uint8_t>& mask) {
    std::vector<Vector3d> r;
    for (size_t i = 0; i < p.size(); ++i)
      if (mask[i]) r.push_back(K.inverse() * p[i].homogeneous());
    return r;
  };
  const auto al = align_two_planes(calibrate_homography(floor->H, K), rays(x1, floor->inlier),
                                   rays(x2, floor->inlier), calibrate_homography(top->H, K),
                                   rays(o1, top->inlier), rays(o2, top->inlier));
  ASSERT_TRUE(al) << to_string(al.reason());

  // Decomposition against the truth.
  const MocapMotion truth = mocap_motion(pose_1, pose_2, rig.mount);
  EXPECT_LT(rotation_angle(al->R_21, truth.R_21), 0.1 * kDeg);
  EXPECT_LT(direction_angle(al->t_12, truth.t_12), 2 * kDeg);
  const Vector3d n_true = -(X_WC(pose_1).linear().transpose() * Vector3d::UnitZ());
  EXPECT_LT(direction_angle(al->n_a, n_true), 2 * kDeg);
  EXPECT_LT(direction_angle(al->n_b, n_true), 2 * kDeg);
  // Which plane is the platform is the landing detector's call (issue 6): here the nearer one.
  // (The paper-ream texture gives more features than the floor, so the first, "dominant",
  // homography may well be the platform's.)
  const bool a_is_top = al->plane_a().distance_1() < al->plane_b().distance_1();
  const PlaneMotion floor_plane = a_is_top ? al->plane_b() : al->plane_a();
  const PlaneMotion top_plane = a_is_top ? al->plane_a() : al->plane_b();
  const HomographyFit& floor_fit = a_is_top ? *top : *floor;
  const HomographyFit& top_fit = a_is_top ? *floor : *top;
  const double h_cam = X_WC(pose_1).translation().z();  // distance of camera 1 from the floor
  EXPECT_NEAR(floor_plane.distance_1() * truth.baseline_m, h_cam, 0.03);
  EXPECT_NEAR(top_plane.distance_1() * truth.baseline_m, h_cam - p_W_top.z(), 0.03);
  // The estimated homographies against the true ones (pixels, undistorted).
  const Matrix3d H_floor_true = K * truth.R_21 *
                                (Matrix3d::Identity() - truth.t_12 * n_true.transpose() / h_cam) *
                                K.inverse();
  const Matrix3d H_top_true =
      K * truth.R_21 *
      (Matrix3d::Identity() - truth.t_12 * n_true.transpose() / (h_cam - p_W_top.z())) *
      K.inverse();
  std::printf(
      "floor H corner error %.3f px, platform H corner error %.3f px; baseline %.4f m; "
      "distances %.4f %.4f m\n",
      corner_error(floor_fit.H, H_floor_true, 640, 480),
      corner_error(top_fit.H, H_top_true, 640, 480), truth.baseline_m,
      floor_plane.distance_1() * truth.baseline_m, top_plane.distance_1() * truth.baseline_m);
  EXPECT_LT(corner_error(floor_fit.H, H_floor_true, 640, 480), 1.0);

  // Waypoint of the platform centre, seen in the current image.
  const Vector3d p_C2 = X_WC(pose_2).inverse() * p_W_top;
  const auto w = compute_waypoint(top_plane, p_C2 / p_C2.z(), pose_1, pose_2, rig.mount);
  ASSERT_TRUE(w) << to_string(w.reason());
  std::printf("platform centre waypoint error %.4f m (xy %.4f m)\n", (w->p_W - p_W_top).norm(),
              (w->p_W - p_W_top).head<2>().norm());
  EXPECT_LT((w->p_W - p_W_top).norm(), 0.01);
}

// Seeds move the platform and change textures and lighting.
INSTANTIATE_TEST_SUITE_P(Seeds, SimTwoViewsTest, ::testing::Values(3, 4, 5));

}  // namespace
}  // namespace alight::vision
