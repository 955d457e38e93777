// The landing target's size from its features' extent (side_from_extent) and its refusal of a
// "top" that does not hide the floor (vision/landing_target.hpp).

#include "vision/landing_target.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "common/camera_model.hpp"
#include "common/geometry.hpp"

namespace alight::vision {
namespace {

// Regression (issue 15, platform refusals): 20-21 cm platforms with few features on the top were
// measured 1.4-3 cm short and refused (gear 15 cm + 2 x 2 cm margin). The range of n features
// spread over a side falls short of it by 2 / (n + 1) of it on average; the widened range is
// right on average at every feature count the landing target accepts (>= 12 inliers).
TEST(LandingSizeTest, FewFeaturesOnANarrowTopAreNotMeasuredShort) {
  std::mt19937_64 rng(5);
  const double side_m = 0.205;
  std::uniform_real_distribution<double> U(0.0, side_m);
  for (const size_t n : {12u, 20u, 40u, 300u}) {
    double sum_range = 0, sum_side = 0;
    const int trials = 4000;
    for (int k = 0; k < trials; ++k) {
      double lo = 1e9, hi = -1e9;
      for (size_t i = 0; i < n; ++i) {
        const double x = U(rng);
        lo = std::min(lo, x);
        hi = std::max(hi, x);
      }
      sum_range += hi - lo;
      sum_side += side_from_extent(hi - lo, n);
    }
    const double range = sum_range / trials, side = sum_side / trials;
    EXPECT_NEAR(range, side_m * (n - 1.0) / (n + 1.0), 5e-4) << n;  // the shortfall
    EXPECT_NEAR(side, side_m, 5e-4) << n;
  }
  // Never narrower than the features' own extent; fewer than two features: the extent.
  EXPECT_DOUBLE_EQ(side_from_extent(0.18, 1), 0.18);
  EXPECT_GT(side_from_extent(0.18, 12), 0.18);
}

// Matches of floor points and of points on a level plane height_m up, within the given box
// around the spot under the camera, seen from two poses 15 cm apart (exact, no noise).
struct Views {
  Correspondences c;
  CameraModel camera = CameraModel::firefly_mv_4mm();
  CameraMount mount;
};

// n points on z = z_m within half_m of the spot under camera 1; none that a box top of
// top_half_m, top_z_m up under that spot hides from either camera.
void add_points(Views& v, std::mt19937_64& rng, double z_m, const Vector2d& half_m, int n,
                const Vector2d& top_half_m = Vector2d::Zero(), double top_z_m = 0.0) {
  std::uniform_real_distribution<double> U(-1, 1);
  const Matrix3d K = v.camera.K();
  const auto project = [&](const PoseSample& p, const Vector3d& X_W) -> std::optional<Vector2d> {
    const Vector3d X_C = camera_in_world(p.X_WB(), v.mount.X_BC()).inverse() * X_W;
    if (X_C.z() <= 0) return std::nullopt;
    const Vector2d u = (K * X_C).hnormalized();
    if (u.x() < 0 || u.y() < 0 || u.x() > 639 || u.y() > 479) return std::nullopt;
    return u;
  };
  for (int k = 0; k < n;) {
    const Vector3d X_W(v.c.pose_1.p_W_B.x() + half_m.x() * U(rng),
                       v.c.pose_1.p_W_B.y() + half_m.y() * U(rng), z_m);
    const auto u1 = project(v.c.pose_1, X_W), u2 = project(v.c.pose_2, X_W);
    if (!u1 || !u2) continue;
    bool hidden = false;
    for (const PoseSample* p : {&v.c.pose_1, &v.c.pose_2}) {
      const Vector3d o = camera_in_world(p->X_WB(), v.mount.X_BC()).translation();
      const double s = (top_z_m - X_W.z()) / (o.z() - X_W.z());
      const Vector3d q = X_W + s * (o - X_W) - v.c.pose_1.p_W_B;
      hidden |= s > 0 && std::abs(q.x()) < top_half_m.x() && std::abs(q.y()) < top_half_m.y();
    }
    if (hidden) continue;
    v.c.x1.push_back(*u1);
    v.c.x2.push_back(*u2);
    v.c.u1.push_back(*u1);
    v.c.u2.push_back(*u2);
    ++k;
  }
}

Views two_views() {
  Views v;
  v.mount.t_B_C = Vector3d(0.05, 0.0, -0.06);
  v.c.pose_1.p_W_B = Vector3d(0.0, 0.0, 1.45);
  v.c.pose_2.p_W_B = Vector3d(0.12, 0.09, 1.45);
  v.c.camera = &v.camera;
  v.c.mount = &v.mount;
  return v;
}

// Regression (issue 15, landing_photo seeds 8008, 8017, 8019: targets 0.9 x 0.7 m and 1.4-1.6 m
// off in refinement): over a photographed floor with few matches the known floor's fit found a
// "top" of 12-35 matches at one height spread over the whole image, the floor's inliers among
// them. A real top hides the floor beneath it.
TEST(LandingTargetTest, TopWithTheFloorShowingThroughIsNoPlatform) {
  PipelineParams params;
  params.landing.floor_prior = "always";
  std::mt19937_64 rng(3);
  {  // a 30 x 24 cm top 20 cm up, the floor around it (where the top does not hide it): found
    Views v = two_views();
    add_points(v, rng, 0.0, Vector2d(0.55, 0.4), 40, Vector2d(0.15, 0.12), 0.2);
    add_points(v, rng, 0.2, Vector2d(0.15, 0.12), 30);
    v.c.camera = &v.camera;
    v.c.mount = &v.mount;
    const auto out = find_landing_target(v.c, params);
    EXPECT_TRUE(out.reason == Reason::kOk || out.reason == Reason::kPartialView)
        << to_string(out.reason);
  }
  {  // the same matches at 20 cm spread over the view, the floor's among them: refused
    Views v = two_views();
    add_points(v, rng, 0.0, Vector2d(0.55, 0.4), 30);
    add_points(v, rng, 0.2, Vector2d(0.45, 0.33), 20);
    v.c.camera = &v.camera;
    v.c.mount = &v.mount;
    const auto out = find_landing_target(v.c, params);
    EXPECT_EQ(out.reason, Reason::kNoTargetPlane) << to_string(out.reason);
    // Without the check the same matches were a platform (the bug).
    PipelineParams before = params;
    before.landing.max_floor_under_top_frac = 1e9;
    const Reason was = find_landing_target(v.c, before).reason;
    EXPECT_TRUE(was == Reason::kOk || was == Reason::kPartialView) << to_string(was);
  }
}

}  // namespace
}  // namespace alight::vision
