// Landing target on rendered views of the paper's platforms (landing_a/b/c) and of the floor
// alone (landing_none): the platform centre's waypoint, its height and extent against the
// scene's truth, and no platform where there is none.
#include <cstdio>

#include "test/vision/mission_sim.hpp"

namespace alight::vision {
namespace {

using testing::render_sequence;
using testing::run;

struct Case {
  const char* scenario;
  uint64_t seed;
};

class LandingMissionTest : public ::testing::TestWithParam<Case> {};

TEST_P(LandingMissionTest, PlatformCentreAndHeightWithinTwoCentimetres) {
  const Case k = GetParam();
  const std::string root = ALIGHT_SOURCE_DIR;
  const auto scene =
      sim::build_scene(sim::load_scenario(root + "/config/scenarios/" + k.scenario), k.seed);
  ASSERT_TRUE(scene.platform);
  const Vector3d top = scene.platform->top_center_W;
  // 1.7 m above the floor, starting 12 cm off the platform centre, 24 cm baseline: the platform's
  // corners stay clear of the partial-view band (edge_margin_px) in both images.
  const auto seq =
      render_sequence(k.scenario, k.seed, "downward", Vector3d(top.x() - 0.12, top.y() + 0.04, 1.7),
                      Vector3d(0.04, -0.01, 0.0), Vector3d(0.01, -0.02, 0.2), 7);
  const auto results = run(seq, Mission::kLanding);
  const FrameResult& r = results.back();
  ASSERT_TRUE(r.found()) << to_string(r.reason) << " matches " << r.n_matches;
  const double err = (r.target.p_W - top).norm();
  std::printf(
      "%s seed %llu: waypoint error %.4f m (xy %.4f), height %.4f (true %.4f), size %.3f x "
      "%.3f (true %.3f x %.3f), inliers floor %d platform %d, baseline %.3f m\n",
      k.scenario, static_cast<unsigned long long>(k.seed), err,
      (r.target.p_W - top).head<2>().norm(), r.target.height_m, scene.platform->size_m.z(),
      r.target.size_m[0], r.target.size_m[1], scene.platform->size_m.x(),
      scene.platform->size_m.y(), r.target.n_inliers_dominant, r.target.n_inliers_target,
      r.baseline_m);
  EXPECT_LT(err, 0.02);
  EXPECT_NEAR(r.target.height_m, scene.platform->size_m.z(), 0.015);
  // The platform's edges modulo 90 deg (autonomy turns the square gear to them).
  const double edge_error =
      std::abs(wrap_angle(4 * (r.target.yaw_rad - scene.platform->yaw_rad)) / 4);
  std::printf("  yaw %.1f deg, true %.1f deg: edge error %.1f deg\n", r.target.yaw_rad * 180 / M_PI,
              scene.platform->yaw_rad * 180 / M_PI, edge_error * 180 / M_PI);
  EXPECT_LT(edge_error, 5 * M_PI / 180);
  // The visible extent of the features cannot exceed the platform's top (plus feature radius).
  EXPECT_LT(r.target.size_m[0],
            std::max(scene.platform->size_m.x(), scene.platform->size_m.y()) + 0.05);
  EXPECT_GT(r.target.size_m[1],
            0.5 * std::min(scene.platform->size_m.x(), scene.platform->size_m.y()));
  EXPECT_GT(r.target.n_W.z(), 0.99);
  EXPECT_EQ(r.mission, Mission::kLanding);
  EXPECT_GT(r.ref_utime, 0);
  EXPECT_LT(r.ref_utime, r.utime);
  // The first frame has no reference yet.
  EXPECT_EQ(results.front().reason, Reason::kNoReference);
}

INSTANTIATE_TEST_SUITE_P(Platforms, LandingMissionTest,
                         ::testing::Values(Case{"landing_a.yaml", 3}, Case{"landing_b.yaml", 4},
                                           Case{"landing_c.yaml", 5}));

TEST(LandingMissionTest, NoPlatformAboveTheBareFloor) {
  const auto seq = render_sequence("landing_none.yaml", 7, "downward", Vector3d(0.1, -0.2, 1.5),
                                   Vector3d(0.04, 0.01, 0.0), Vector3d(0.0, 0.01, 0.3), 7);
  const auto results = run(seq, Mission::kLanding);
  int with_reference = 0;
  for (const auto& r : results) {
    EXPECT_FALSE(r.found()) << "frame " << r.seq;
    if (r.ref_utime > 0) {
      ++with_reference;
      EXPECT_EQ(r.reason, Reason::kNoTargetPlane) << to_string(r.reason);
      EXPECT_GT(r.target.n_inliers_dominant, 40);
    }
  }
  EXPECT_GE(with_reference, 4);
}

TEST(LandingMissionTest, DegenerateFramesGiveAReason) {
  const auto seq = render_sequence("landing_a.yaml", 3, "downward", Vector3d(0, 0, 1.5),
                                   Vector3d(0.0, 0.0, 0.0), Vector3d(0, 0, 0), 3);
  Pipeline p(Mission::kLanding, PipelineParams{}, seq.rig.model, seq.rig.mount);
  const auto& f = seq.frames;
  EXPECT_EQ(p.process(f[0].image, f[0].utime, std::nullopt).reason, Reason::kNoPose);
  EXPECT_EQ(p.process(cv::Mat(), f[0].utime, f[0].pose).reason, Reason::kBadImage);
  EXPECT_EQ(p.process(cv::Mat(100, 100, CV_8UC1, cv::Scalar(0)), f[0].utime, f[0].pose).reason,
            Reason::kBadImage);
  EXPECT_EQ(p.process(cv::Mat(480, 640, CV_8UC1, cv::Scalar(90)), f[0].utime, f[0].pose).reason,
            Reason::kTooFewFeatures);
  EXPECT_EQ(p.process(f[0].image, f[0].utime, f[0].pose).reason, Reason::kNoReference);
  // The camera hovers: no baseline.
  EXPECT_EQ(p.process(f[1].image, f[1].utime, f[1].pose).reason, Reason::kSmallBaseline);
  EXPECT_EQ(p.process(f[2].image, f[2].utime, f[2].pose).seq, 7);
}

TEST(LandingMissionTest, ReplayGivesIdenticalResults) {
  const std::string root = ALIGHT_SOURCE_DIR;
  const Vector3d top =
      sim::build_scene(sim::load_scenario(root + "/config/scenarios/landing_b.yaml"), 4)
          .platform->top_center_W;
  const auto seq =
      render_sequence("landing_b.yaml", 4, "downward", Vector3d(top.x() - 0.1, top.y(), 1.7),
                      Vector3d(0.04, -0.01, 0.0), Vector3d(0.01, -0.02, 0.2), 6);
  const auto a = run(seq, Mission::kLanding), b = run(seq, Mission::kLanding);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].reason, b[i].reason);
    EXPECT_EQ(a[i].ref_utime, b[i].ref_utime);
    EXPECT_EQ(a[i].n_matches, b[i].n_matches);
    EXPECT_EQ(a[i].target.n_inliers_target, b[i].target.n_inliers_target);
    EXPECT_EQ(a[i].target.p_W, b[i].target.p_W);  // bit-identical
    EXPECT_EQ(a[i].target.height_m, b[i].target.height_m);
  }
  EXPECT_TRUE(a.back().found()) << to_string(a.back().reason);
}

}  // namespace
}  // namespace alight::vision
