// Ingress target on rendered views of the paper's wall with a 60 x 60 cm opening (ingress) and
// of the solid wall (ingress_solid): opening found, its width / height and centre against the
// scene's truth, and no opening in the solid wall.
#include <cstdio>
#include <cstdlib>
#include <opencv2/imgcodecs.hpp>

#include "common/build_paths.hpp"
#include "sim/camera_effects.hpp"
#include "test/vision/mission_sim.hpp"
#include "vision/node/diag_image.hpp"

namespace alight::vision {
namespace {

using testing::render_sequence;
using testing::run;

class IngressMissionTest : public ::testing::TestWithParam<uint64_t> {};

// The paper's wall (ingress.yaml) drawn with `seed`: the opening's true centre, and seven views
// from 1.5 m in front of the wall, 5 cm left of the opening's centre, moving 24 cm sideways.
struct OpeningViews {
  Vector3d centre_W;
  testing::Sequence seq;
};
OpeningViews opening_views(uint64_t seed) {
  const std::string root = alight::build::source_dir();
  const auto scene =
      sim::build_scene(sim::load_scenario(root + "/config/scenarios/ingress.yaml"), seed);
  EXPECT_TRUE(scene.opening);
  const Vector3d c = scene.opening ? scene.opening->center_W : Vector3d::Zero();
  return {c, render_sequence("ingress.yaml", seed, "forward",
                             Vector3d(c.x() - 1.5 - 0.12, c.y() - 0.12, c.z() + 0.03),
                             Vector3d(0.0, 0.04, -0.005), Vector3d(0.01, 0.0, 0.02), 7)};
}

// Issue 6's bars: width 60 +- 1 cm, centre within 2 cm; the height within 2 cm (the sill's and
// lintel's inner faces next to the wall's edge agree with the wall homography for a few pixels,
// so top and bottom sit up to ~1 cm inside). Regression: before the off-wall mask (Canny on the
// grey image) seed 1 missed the opening's top and left edges and seed 2 cut the height at the
// far edges of the inner faces (56 cm).
TEST_P(IngressMissionTest, OpeningWidthAndCentre) {
  const auto [c, seq] = opening_views(GetParam());
  const auto results = run(seq, Mission::kIngress);
  const FrameResult& r = results.back();
  if (const char* dir = std::getenv("ALIGHT_DIAG_DIR"))  // for a look at Fig. 7's equivalent
    cv::imwrite(std::string(dir) + "/ingress_" + std::to_string(GetParam()) + ".png",
                draw_diag_image(seq.frames.back().image, r));
  ASSERT_TRUE(r.found()) << to_string(r.reason) << " matches " << r.n_matches << " in block "
                         << r.target.n_inliers_target;
  std::printf(
      "ingress seed %llu: centre error %.4f m (in wall %.4f), width %.4f height %.4f (true "
      "%.2f x %.2f), wall inliers %d, off-wall in opening %d, %zu lines\n",
      static_cast<unsigned long long>(GetParam()), (r.target.p_W - c).norm(),
      (r.target.p_W - c).tail<2>().norm(), r.target.size_m[0], r.target.size_m[1],
      seq.scene.opening->size_m.x(), seq.scene.opening->size_m.y(), r.target.n_inliers_dominant,
      r.target.n_inliers_target, r.lines.size());
  EXPECT_LT((r.target.p_W - c).norm(), 0.02);
  EXPECT_NEAR(r.target.size_m[0], 0.60, 0.01);
  EXPECT_NEAR(r.target.size_m[1], 0.60, 0.02);
  EXPECT_LT(r.target.n_W.x(), -0.99);  // towards the approach side
  const cv::Mat diag = draw_diag_image(seq.frames.back().image, r);
  EXPECT_EQ(diag.type(), CV_8UC3);
  EXPECT_EQ(diag.size(), seq.frames.back().image.size());
}

INSTANTIATE_TEST_SUITE_P(Seeds, IngressMissionTest, ::testing::Values(1, 2, 3, 4, 5, 6));

// The same views through a lens whose corners get 45 % of the centre's light: the wall's points
// change brightness as they move across the image, which the off-wall mask must not read as
// parallax (plane_gain.hpp). The same bars as without it.
class VignettedIngressMissionTest : public ::testing::TestWithParam<uint64_t> {};

TEST_P(VignettedIngressMissionTest, OpeningWidthAndCentre) {
  auto [c, seq] = opening_views(GetParam());
  const cv::Mat falloff = sim::vignetting_map(seq.rig.model, 0.45);
  for (auto& f : seq.frames) {
    cv::Mat light;
    f.image.convertTo(light, CV_32F);
    cv::multiply(light, falloff, light);
    light.convertTo(f.image, CV_8U);
  }
  const FrameResult r = run(seq, Mission::kIngress).back();
  ASSERT_TRUE(r.found()) << to_string(r.reason);
  std::printf("vignetted ingress seed %llu: centre error %.4f m, width %.4f height %.4f\n",
              static_cast<unsigned long long>(GetParam()), (r.target.p_W - c).norm(),
              r.target.size_m[0], r.target.size_m[1]);
  EXPECT_LT((r.target.p_W - c).norm(), 0.02);
  EXPECT_NEAR(r.target.size_m[0], 0.60, 0.01);
  EXPECT_NEAR(r.target.size_m[1], 0.60, 0.02);
}

INSTANTIATE_TEST_SUITE_P(Seeds, VignettedIngressMissionTest, ::testing::Values(1, 2, 3, 4, 5, 6));

TEST(IngressMissionTest, NoOpeningInTheSolidWall) {
  const auto seq = render_sequence("ingress_solid.yaml", 3, "forward", Vector3d(1.5, -0.12, 1.2),
                                   Vector3d(0.0, 0.04, 0.0), Vector3d(0.0, 0.0, 0.0), 7);
  const auto results = run(seq, Mission::kIngress);
  int with_reference = 0;
  for (const auto& r : results) {
    EXPECT_FALSE(r.found()) << "frame " << r.seq;
    if (r.ref_utime > 0) {
      ++with_reference;
      // No block seen through the wall, or one that the opening's checks refuse (each with its
      // own reason).
      EXPECT_TRUE(r.reason == Reason::kNoOpening ||
                  (r.reason >= Reason::kOpeningTooSmall && r.reason <= Reason::kPartialNotBehind))
          << to_string(r.reason);
    }
  }
  EXPECT_GE(with_reference, 4);
}

}  // namespace
}  // namespace alight::vision
