// Two-plane alignment (paper 3.2): the agreeing pair of decompositions is the true one, the
// joint refinement makes both homographies share R21 and t12 and is at least as accurate as
// either plane alone; inconsistent planes are refused.
#include "vision/geometry/alignment.hpp"

#include <gtest/gtest.h>

#include <cstdio>

#include "test/vision/synthetic.hpp"
#include "vision/geometry/homography.hpp"

namespace alight::vision {
namespace {

using testing::add_plane;
using testing::Correspondences;
using testing::rays;
using testing::TwoViews;

constexpr double kDeg = M_PI / 180.0;

struct TwoPlanes {
  TwoViews v;
  Vector3d n = Vector3d::UnitZ();
  double d_floor = 1.5, d_top = 1.2;
  Correspondences floor, top;
};

TwoPlanes make(uint64_t seed, double sigma_px, int n_floor = 200, int n_top = 60) {
  TwoPlanes s;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  s.v.R_21 = testing::random_rotation(rng, 3 * kDeg);
  s.v.t_12_m = 0.2 * Vector3d(u(rng), u(rng), 0.2 * u(rng)).normalized();
  add_plane(s.v, s.n, s.d_floor, n_floor, sigma_px, rng, s.floor, 0);
  add_plane(s.v, s.n, s.d_top, n_top, sigma_px, rng, s.top, 1, {240, 160, 400, 320});
  return s;
}

struct Fitted {
  Matrix3d Ha, Hb;
  std::vector<Vector3d> r1a, r2a, r1b, r2b;
};

Fitted fit(const TwoPlanes& s) {
  Fitted f;
  const auto fa = fit_homography(s.floor.x1, s.floor.x2, HomographyParams{});
  const auto fb = fit_homography(s.top.x1, s.top.x2, HomographyParams{});
  EXPECT_TRUE(fa && fb);
  f.Ha = calibrate_homography(fa->H, s.v.K);
  f.Hb = calibrate_homography(fb->H, s.v.K);
  f.r1a = rays(s.v.K, s.floor.x1), f.r2a = rays(s.v.K, s.floor.x2);
  f.r1b = rays(s.v.K, s.top.x1), f.r2b = rays(s.v.K, s.top.x2);
  return f;
}

TEST(AlignmentTest, NoiseFreePlanesGiveTheTrueMotionWithoutAnyPrior) {
  for (uint64_t seed = 0; seed < 10; ++seed) {
    const TwoPlanes s = make(seed, 0.0);
    const Fitted f = fit(s);
    const auto a = align_two_planes(f.Ha, f.r1a, f.r2a, f.Hb, f.r1b, f.r2b);
    ASSERT_TRUE(a) << to_string(a.reason());
    EXPECT_LT(rotation_angle(a->R_21, s.v.R_21), 0.01 * kDeg);
    EXPECT_LT(direction_angle(a->t_12, s.v.t_12_m), 0.1 * kDeg);
    EXPECT_LT(direction_angle(a->n_a, s.n), 0.1 * kDeg);
    EXPECT_LT(direction_angle(a->n_b, s.n), 0.1 * kDeg);
    // Distances in baselines: d / |t|.
    EXPECT_NEAR(a->plane_a().distance_1(), s.d_floor / s.v.t_12_m.norm(), 1e-4);
    EXPECT_NEAR(a->plane_b().distance_1(), s.d_top / s.v.t_12_m.norm(), 1e-4);
    EXPECT_TRUE(is_rotation(a->R_21, 1e-9));
  }
}

TEST(AlignmentTest, JointRefinementIsAtLeastAsAccurateAsThePlatformAlone) {
  double err_joint = 0, err_top_alone = 0;
  for (uint64_t seed = 100; seed < 120; ++seed) {
    const TwoPlanes s = make(seed, 0.5);
    const Fitted f = fit(s);
    const auto a = align_two_planes(f.Ha, f.r1a, f.r2a, f.Hb, f.r1b, f.r2b);
    ASSERT_TRUE(a) << seed << " " << to_string(a.reason());
    EXPECT_LE(a->rms_after, a->rms_before + 1e-12);
    DecompositionPrior prior;
    prior.R_21 = s.v.R_21;
    const auto top = decompose(f.Hb, f.r1b, f.r2b, prior);
    ASSERT_TRUE(top);
    err_joint += direction_angle(a->n_b, s.n);
    err_top_alone += direction_angle(top->n_1, s.n);
  }
  std::printf("platform normal error: joint %.3f deg, platform alone %.3f deg\n",
              err_joint / 20 / kDeg, err_top_alone / 20 / kDeg);
  EXPECT_LT(err_joint, err_top_alone) << "platform normal error, joint " << err_joint / 20 / kDeg
                                      << " deg, alone " << err_top_alone / 20 / kDeg << " deg";
}

TEST(AlignmentTest, RegressionParallelPlanesFalsePairAgreeingInTranslationIsNotChosen) {
  // Seed 109 at 0.5 px: the false decompositions of floor and platform both put t12 along the
  // normal and agreed better than the true pair; choosing by agreement alone took them and the
  // refined platform ended behind the camera. The pair is now chosen by the joint fit.
  const TwoPlanes s = make(109, 0.5);
  const Fitted f = fit(s);
  const auto a = align_two_planes(f.Ha, f.r1a, f.r2a, f.Hb, f.r1b, f.r2b);
  ASSERT_TRUE(a) << to_string(a.reason());
  EXPECT_LT(direction_angle(a->t_12, s.v.t_12_m), 5 * kDeg);
  EXPECT_LT(direction_angle(a->n_b, s.n), 5 * kDeg);
}

TEST(AlignmentTest, HomographiesOfDifferentMotionsAreRefused) {
  // The "second plane" comes from another camera motion: no pair of candidates agrees.
  const TwoPlanes s = make(7, 0.0);
  TwoPlanes other = make(8, 0.0);
  other.v.R_21 = Eigen::AngleAxisd(20 * kDeg, Vector3d(0, 1, 0)).toRotationMatrix();
  other.top = {};
  std::mt19937_64 rng(1);
  add_plane(other.v, other.n, other.d_top, 60, 0.0, rng, other.top, 1, {240, 160, 400, 320});
  const Fitted f = fit(s), g = fit(other);
  const auto a = align_two_planes(f.Ha, f.r1a, f.r2a, g.Hb, g.r1b, g.r2b);
  EXPECT_FALSE(a);
  EXPECT_EQ(a.reason(), Reason::kPlanesDisagree);
}

TEST(AlignmentTest, RotationPriorIsOffByDefaultAndWeighsFeatureNoiseAgainstItsSigma) {
  const Matrix3d R = Eigen::AngleAxisd(0.1, Vector3d(0, 0, 1)).toRotationMatrix();
  EXPECT_FALSE(rotation_prior(R, AlignParams{}, 500.0));
  AlignParams p;
  p.rotation_prior_sigma_deg = 0.1;
  p.feature_sigma_px = 0.5;
  const auto prior = rotation_prior(R, p, 500.0);
  ASSERT_TRUE(prior);
  EXPECT_TRUE(prior->R_21.isApprox(R));
  // One sigma of rotation costs as much as one feature one sigma off.
  EXPECT_NEAR(prior->weight * 0.1 * kDeg, 0.5 / 500.0, 1e-12);
}

TEST(AlignmentTest, AccurateRotationPriorRemovesTheDistanceErrorOfTheBasReliefAmbiguity) {
  // A narrow field of view at 0.5 px noise: a rotation error across the baseline is absorbed by
  // |t|/d, so vision alone gets the planes' distances (in baselines) a few percent wrong. With
  // motion capture's R21 as a prior the rotation, and with it the distances, are pinned.
  double r_alone = 0, r_prior = 0, d_alone = 0, d_prior = 0;
  AlignParams with;
  with.rotation_prior_sigma_deg = 0.01;
  for (uint64_t seed = 100; seed < 120; ++seed) {
    const TwoPlanes s = make(seed, 0.5);
    const Fitted f = fit(s);
    const auto alone = align_two_planes(f.Ha, f.r1a, f.r2a, f.Hb, f.r1b, f.r2b);
    const auto prior = rotation_prior(s.v.R_21, with, s.v.K(0, 0));
    const auto aided = align_two_planes(f.Ha, f.r1a, f.r2a, f.Hb, f.r1b, f.r2b, with,
                                        DecompositionParams{}, prior);
    ASSERT_TRUE(alone) << seed << " " << to_string(alone.reason());
    ASSERT_TRUE(aided) << seed << " " << to_string(aided.reason());
    EXPECT_FALSE(alone->used_rotation_prior);
    EXPECT_TRUE(aided->used_rotation_prior);
    EXPECT_TRUE(is_rotation(aided->R_21, 1e-9));
    const double d_true = s.d_floor / s.v.t_12_m.norm();
    r_alone += rotation_angle(alone->R_21, s.v.R_21) / kDeg / 20;
    r_prior += rotation_angle(aided->R_21, s.v.R_21) / kDeg / 20;
    d_alone += std::abs(alone->plane_a().distance_1() / d_true - 1) / 20;
    d_prior += std::abs(aided->plane_a().distance_1() / d_true - 1) / 20;
    EXPECT_LT(rotation_angle(aided->R_21, s.v.R_21), 0.03 * kDeg) << seed;
  }
  std::printf(
      "mean R21 error: alone %.4f deg, prior %.4f deg; floor distance error: alone %.3f%%, "
      "prior %.3f%%\n",
      r_alone, r_prior, 100 * d_alone, 100 * d_prior);
  EXPECT_LT(d_prior, 0.5 * d_alone);
  EXPECT_LT(r_prior, 0.5 * r_alone);
}

TEST(AlignmentTest, RegressionNearMissesInsideTheThresholdDoNotPullTheJointRotation) {
  // Rendered seed 6 (sim_two_views_test): features on the platform's edges, where the view
  // straddles two depths, sit just inside the RANSAC threshold, and a plain least-squares joint
  // refinement let them pull R21 to 0.19 deg off (each plane alone: 0.05 deg), which the
  // bas-relief ambiguity turned into a 2.8 cm depth error. Here, as there, few floor and many
  // platform features (40 and 400), 0.3 px noise, and the platform's
  // points along one edge (the right eighth of it) pushed 1.4-1.9 px outwards, inside the 2 px
  // threshold.
  double r_plain = 0, r_robust = 0;
  AlignParams plain;
  plain.robust = false;
  for (uint64_t seed = 200; seed < 220; ++seed) {
    TwoPlanes s = make(seed, 0.3, 40, 400);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> push(1.4, 1.9);
    for (size_t i = 0; i < s.top.x2.size(); ++i)
      if (s.top.x1[i].x() > 380) s.top.x2[i] += Vector2d(push(rng), 0.0);
    const Fitted f = fit(s);
    const auto a = align_two_planes(f.Ha, f.r1a, f.r2a, f.Hb, f.r1b, f.r2b, plain);
    const auto b = align_two_planes(f.Ha, f.r1a, f.r2a, f.Hb, f.r1b, f.r2b);
    ASSERT_TRUE(a && b) << seed;
    r_plain += rotation_angle(a->R_21, s.v.R_21) / kDeg / 20;
    r_robust += rotation_angle(b->R_21, s.v.R_21) / kDeg / 20;
  }
  std::printf("mean R21 error with near misses: plain %.4f deg, Cauchy-weighted %.4f deg\n",
              r_plain, r_robust);
  EXPECT_LT(r_robust, 0.8 * r_plain);
}

TEST(AlignmentTest, PureRotationIsSmallBaseline) {
  const Matrix3d R = Eigen::AngleAxisd(0.1, Vector3d(0, 0, 1)).toRotationMatrix();
  std::vector<Vector3d> r1 = {{0, 0, 1}, {0.1, 0, 1}, {0, 0.1, 1}, {0.1, 0.1, 1}}, r2;
  for (const auto& x : r1) r2.push_back(R * x / (R * x).z());
  EXPECT_EQ(align_two_planes(R, r1, r2, R, r1, r2).reason(), Reason::kSmallBaseline);
}

}  // namespace
}  // namespace alight::vision
