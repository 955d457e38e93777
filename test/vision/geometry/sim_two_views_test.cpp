// Two rendered views (alight_sim, issue 3) of a floor with a platform of the paper (landing_a:
// 43.2 x 27.9 x 10.9 cm): the whole library chain from pixels to the world waypoint. Camera at
// about 1.5 m, 20 cm baseline. Both planes are found, the decomposition agrees with the true
// motion and the platform-centre waypoint lands within 1 cm of the truth, vision alone (the
// paper: motion capture gives the scale only).
//
// Regression (seeds 6, 8, 12): with a plain least-squares joint refinement the aligned R21 came
// out worse than either plane's own decomposition (seed 6: 0.19 deg against 0.05 deg each), and
// with a 20 cm baseline at 1.5 m a rotation error delta about the axis across the baseline moves
// image points like a translation of delta * depth, so |t| / d absorbed it (bas-relief
// ambiguity): both distances 2.2% short, the waypoint 2.8 cm off along the line of sight. The
// Cauchy-weighted joint refinement (AlignParams::robust) keeps platform-edge features and near
// misses from pulling the shared motion: seeds 1-20, R21 within 0.07 deg, waypoint within 8.4 mm.
//
// Motion capture's relative rotation as a prior (AlignParams::rotation_prior_sigma_deg, off by
// default): exact, every waypoint is within 0.3 mm; with the simulator's motion-capture noise
// (0.3 mm, 0.086 deg per axis and sample) the relative rotation is worse than the vision's
// (waypoints within 1.9 cm), which is why the prior stays off.
#include <gtest/gtest.h>

#include <random>
#include <tuple>

#include "common/build_paths.hpp"
#include "sim/params.hpp"
#include "sim/renderer.hpp"
#include "sim/scene.hpp"
#include "vision/frontend/matcher.hpp"
#include "vision/frontend/star_detector.hpp"
#include "vision/frontend/surf_descriptor.hpp"
#include "vision/geometry/alignment.hpp"
#include "vision/geometry/homography.hpp"
#include "vision/geometry/waypoint.hpp"

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

/// A motion-capture sample of a true pose: the simulator's noise (config/scenarios: 0.3 mm,
/// 0.0015 rad per axis), seeded.
PoseSample mocap_sample(const PoseSample& truth, std::mt19937_64& rng) {
  std::normal_distribution<double> pos(0.0, 0.0003), rot(0.0, 0.0015);
  PoseSample p = truth;
  p.p_W_B += Vector3d(pos(rng), pos(rng), pos(rng));
  const Vector3d w(rot(rng), rot(rng), rot(rng));
  p.q_WB = (truth.q_WB * Quaterniond(Eigen::AngleAxisd(w.norm(), w.normalized()))).normalized();
  return p;
}

enum class Mocap {
  kVisionAlone,  ///< exact poses for the scale only (the paper)
  kExactPrior,   ///< exact poses, their R21 a prior with 0.02 deg
  kNoisyPrior,   ///< the simulator's motion-capture noise, prior with 0.15 deg
};

void PrintTo(Mocap m, std::ostream* os) {
  *os << (m == Mocap::kVisionAlone  ? "vision alone"
          : m == Mocap::kExactPrior ? "exact prior"
                                    : "noisy prior");
}

class SimTwoViewsTest : public ::testing::TestWithParam<std::tuple<uint64_t, Mocap>> {};

TEST_P(SimTwoViewsTest, PlatformWaypointWithinOneCentimetreAtOnePointFiveMetres) {
  const auto [seed, mode] = GetParam();
  const bool with_prior = mode != Mocap::kVisionAlone;
  const std::string root = alight::build::source_dir();
  const auto scenario = sim::load_scenario(root + "/config/scenarios/landing_a.yaml");
  const auto scene = sim::build_scene(scenario, seed);
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
  // What the vision node has: motion-capture samples of both poses.
  std::mt19937_64 rng(seed);
  const bool noisy = mode == Mocap::kNoisyPrior;
  const PoseSample mocap_1 = noisy ? mocap_sample(pose_1, rng) : pose_1;
  const PoseSample mocap_2 = noisy ? mocap_sample(pose_2, rng) : pose_2;
  AlignParams align;
  align.rotation_prior_sigma_deg = mode == Mocap::kExactPrior ? 0.02 : noisy ? 0.15 : 0.0;
  const auto prior = rotation_prior(mocap_motion(mocap_1, mocap_2, rig.mount).R_21, align, K(0, 0));
  const auto al = align_two_planes(calibrate_homography(floor->H, K), rays(x1, floor->inlier),
                                   rays(x2, floor->inlier), calibrate_homography(top->H, K),
                                   rays(o1, top->inlier), rays(o2, top->inlier), align,
                                   DecompositionParams{}, prior);
  ASSERT_TRUE(al) << to_string(al.reason());
  EXPECT_EQ(al->used_rotation_prior, with_prior);

  // Decomposition against the truth.
  const MocapMotion truth = mocap_motion(pose_1, pose_2, rig.mount);
  EXPECT_LT(rotation_angle(al->R_21, truth.R_21), (mode == Mocap::kExactPrior ? 0.02
                                                   : noisy                    ? 0.25
                                                                              : 0.1) *
                                                      kDeg);
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
  // Vision alone the floor's distance is within 1.05 cm (seed 8), the waypoint within 8.4 mm.
  const double distance_tol_m = mode == Mocap::kExactPrior ? 0.01 : noisy ? 0.035 : 0.015;
  EXPECT_NEAR(floor_plane.distance_1() * truth.baseline_m, h_cam, distance_tol_m);
  EXPECT_NEAR(top_plane.distance_1() * truth.baseline_m, h_cam - p_W_top.z(), distance_tol_m);
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
  const auto w = compute_waypoint(top_plane, p_C2 / p_C2.z(), mocap_1, mocap_2, rig.mount);
  ASSERT_TRUE(w) << to_string(w.reason());
  std::printf(
      "seed %d mocap mode %d: R21 error %.3f deg, platform centre waypoint error %.4f m (xy %.4f "
      "m)\n",
      int(seed), int(mode), rotation_angle(al->R_21, truth.R_21) / kDeg, (w->p_W - p_W_top).norm(),
      (w->p_W - p_W_top).head<2>().norm());
  EXPECT_LT((w->p_W - p_W_top).head<2>().norm(), 0.01);
  EXPECT_LT((w->p_W - p_W_top).norm(), noisy ? 0.035 : 0.01);
}

// Seeds move the platform and change textures and lighting.
INSTANTIATE_TEST_SUITE_P(Seeds, SimTwoViewsTest,
                         ::testing::Combine(::testing::Range<uint64_t>(1, 21),
                                            ::testing::Values(Mocap::kVisionAlone,
                                                              Mocap::kExactPrior,
                                                              Mocap::kNoisyPrior)));

}  // namespace
}  // namespace alight::vision
