// Longuet-Higgins decomposition (paper 3.1.2): known answers from H = R (I - t n^T), agreement
// with OpenCV's decomposeHomographyMat (Malis & Vargas), properties, degenerate motion, and the
// error curves against pixel noise and baseline.
#include "vision/geometry/decomposition.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "common/build_paths.hpp"
#include "test/vision/synthetic.hpp"
#include "vision/geometry/homography.hpp"

namespace alight::vision {
namespace {

using testing::add_outliers;
using testing::add_plane;
using testing::Correspondences;
using testing::rays;
using testing::TwoViews;

constexpr double kDeg = M_PI / 180.0;

struct Truth {
  Matrix3d R_21;
  Vector3d t_12;  // unit
  Vector3d n_1;   // n / d in baseline units
};

Truth random_truth(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Truth t;
  t.R_21 = testing::random_rotation(rng, 20 * kDeg);
  t.t_12 = Vector3d(u(rng), u(rng), 0.5 * u(rng)).normalized();
  const Vector3d n = Vector3d(0.3 * u(rng), 0.3 * u(rng), 1.0).normalized();
  const double d_baselines = 3.0 + 5.0 * (u(rng) + 1.0);
  t.n_1 = n / d_baselines;
  return t;
}

/// Rays of points on the plane in front of camera 1 and their images in camera 2.
void plane_rays(const Truth& t, std::vector<Vector3d>& r1, std::vector<Vector3d>& r2) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  for (int i = 0; i < 50; ++i) {
    const Vector3d x1(u(rng), u(rng), 1.0);
    const Vector3d X1 = x1 / t.n_1.dot(x1);
    const Vector3d X2 = t.R_21 * (X1 - t.t_12);
    r1.push_back(x1);
    r2.push_back(X2 / X2.z());
  }
}

bool matches(const PlaneMotion& m, const Truth& t, double tol) {
  return rotation_angle(m.R_21, t.R_21) < tol && direction_angle(m.t_12, t.t_12) < tol &&
         (m.n_1 - t.n_1).norm() < tol * t.n_1.norm();
}

TEST(DecompositionTest, OneOfTheCandidatesIsTheTruthAndPositiveDepthLeavesAtMostTwo) {
  std::mt19937_64 rng(42);
  for (int trial = 0; trial < 200; ++trial) {
    const Truth t = random_truth(rng);
    std::vector<Vector3d> r1, r2;
    plane_rays(t, r1, r2);
    const PlaneMotion truth{t.R_21, t.t_12, t.n_1};
    const double scale = trial % 2 ? -3.7 : 0.25;  // H is known only up to scale and sign
    const auto all = decompose_homography(scale * truth.homography(), r1);
    ASSERT_EQ(all.size(), 4u);
    for (const auto& m : all) {
      EXPECT_TRUE(is_rotation(m.R_21, 1e-9));
      EXPECT_NEAR(m.t_12.norm(), 1.0, 1e-12);
      EXPECT_LT((m.homography() - truth.homography()).norm(), 1e-9);  // all explain H
    }
    const auto front = positive_depth(all, r1, r2);
    ASSERT_GE(front.size(), 1u);
    ASSERT_LE(front.size(), 2u);
    EXPECT_TRUE(std::any_of(front.begin(), front.end(),
                            [&](const PlaneMotion& m) { return matches(m, t, 1e-8); }))
        << "trial " << trial;
    DecompositionPrior prior;
    prior.R_21 = t.R_21;
    const auto chosen = decompose(scale * truth.homography(), r1, r2, prior);
    ASSERT_TRUE(chosen);
    EXPECT_TRUE(matches(*chosen, t, 1e-8));
  }
}

TEST(DecompositionTest, AgreesWithOpenCVsDecomposeHomographyMat) {
  std::mt19937_64 rng(8);
  const Matrix3d K = CameraModel::firefly_mv_4mm().K();
  cv::Mat Kcv;
  cv::eigen2cv(K, Kcv);
  for (int trial = 0; trial < 50; ++trial) {
    const Truth t = random_truth(rng);
    std::vector<Vector3d> r1, r2;
    plane_rays(t, r1, r2);
    const Matrix3d H_px = K * PlaneMotion{t.R_21, t.t_12, t.n_1}.homography() * K.inverse();
    cv::Mat Hcv;
    cv::eigen2cv(H_px, Hcv);
    std::vector<cv::Mat> Rs, ts, ns;
    const int n_cv = cv::decomposeHomographyMat(Hcv, Kcv, Rs, ts, ns);
    const auto ours = decompose_homography(calibrate_homography(H_px, K), r1);
    ASSERT_EQ(int(ours.size()), n_cv);
    // Every OpenCV solution (R, t/d, n) is one of ours: same R and normal, t = -R t12 / d.
    for (int k = 0; k < n_cv; ++k) {
      Matrix3d R;
      Vector3d tt, nn;
      cv::cv2eigen(Rs[k], R);
      cv::cv2eigen(ts[k], tt);
      cv::cv2eigen(ns[k], nn);
      const bool found = std::any_of(ours.begin(), ours.end(), [&](const PlaneMotion& m) {
        const Vector3d t_over_d = -m.R_21 * m.t_12 * m.n_1.norm();
        return rotation_angle(m.R_21, R) < 1e-7 && (m.unit_normal_1() - nn).norm() < 1e-7 &&
               (t_over_d - tt).norm() < 1e-7 * (1 + tt.norm());
      });
      EXPECT_TRUE(found) << "trial " << trial << " OpenCV solution " << k;
    }
  }
}

TEST(DecompositionTest, PureRotationIsSmallBaseline) {
  const Matrix3d R = Eigen::AngleAxisd(0.2, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  std::vector<Vector3d> r1 = {{0, 0, 1}, {0.1, 0, 1}, {0, 0.1, 1}, {0.1, 0.1, 1}};
  std::vector<Vector3d> r2;
  for (const auto& x : r1) r2.push_back((R * x) / (R * x).z());
  const auto d = decompose(R, r1, r2, {});
  EXPECT_FALSE(d);
  EXPECT_EQ(d.reason(), Reason::kSmallBaseline);
}

TEST(DecompositionTest, TwoCandidatesWithoutPriorAreAmbiguous) {
  std::mt19937_64 rng(3);
  const Truth t = random_truth(rng);
  std::vector<Vector3d> r1, r2;
  plane_rays(t, r1, r2);
  const Matrix3d H = PlaneMotion{t.R_21, t.t_12, t.n_1}.homography();
  ASSERT_EQ(positive_depth(decompose_homography(H, r1), r1, r2).size(), 2u);
  EXPECT_EQ(decompose(H, r1, r2, {}).reason(), Reason::kDecompositionAmbiguous);
  DecompositionPrior prior;
  prior.n_1 = t.n_1.normalized();
  const auto d = decompose(H, r1, r2, prior);
  ASSERT_TRUE(d);
  EXPECT_TRUE(matches(*d, t, 1e-8));
}

TEST(DecompositionTest, NonFiniteHomographyGivesNoCandidates) {
  Matrix3d H = Matrix3d::Identity();
  H(0, 1) = std::nan("");
  EXPECT_TRUE(decompose_homography(H, {}).empty());
}

/// Synthetic correspondences (downward camera at 1.5 m over a floor) through RANSAC and the
/// decomposition, errors against the truth.
struct Errors {
  double R_deg, t_deg, n_deg;
};
Errors pipeline_errors(double sigma_px, double baseline_m, uint64_t seed) {
  TwoViews v;
  std::mt19937_64 rng(seed);
  v.R_21 = testing::random_rotation(rng, 5 * kDeg);
  std::uniform_real_distribution<double> u(-1, 1);
  v.t_12_m = baseline_m * Vector3d(u(rng), u(rng), 0.3 * u(rng)).normalized();
  const Vector3d n = Vector3d(0.05 * u(rng), 0.05 * u(rng), 1).normalized();
  Correspondences c;
  add_plane(v, n, 1.5, 200, sigma_px, rng, c, 0);
  add_outliers(60, rng, c);
  const auto fit = fit_homography(c.x1, c.x2, HomographyParams{});
  if (!fit) return {180, 180, 180};
  std::vector<Vector2d> p1, p2;
  for (size_t i = 0; i < c.x1.size(); ++i)
    if (fit->inlier[i]) p1.push_back(c.x1[i]), p2.push_back(c.x2[i]);
  DecompositionPrior prior;
  prior.R_21 = v.R_21;
  const auto d = decompose(calibrate_homography(fit->H, v.K), rays(v.K, p1), rays(v.K, p2), prior);
  if (!d) return {180, 180, 180};
  return {rotation_angle(d->R_21, v.R_21) / kDeg, direction_angle(d->t_12, v.t_12_m) / kDeg,
          direction_angle(d->unit_normal_1(), n) / kDeg};
}

TEST(DecompositionTest, NoiseFreeCorrespondencesRecoverRWithinOneHundredthDegree) {
  for (uint64_t seed = 0; seed < 20; ++seed) {
    const Errors e = pipeline_errors(0.0, 0.2, seed);
    EXPECT_LT(e.R_deg, 0.01) << seed;
    EXPECT_LT(e.t_deg, 0.1) << seed;
    EXPECT_LT(e.n_deg, 0.1) << seed;
  }
}

TEST(DecompositionTest, WritesErrorCurvesAgainstNoiseAndBaseline) {
  const auto dir = std::filesystem::path(alight::build::binary_dir()) / "test-output";
  std::filesystem::create_directories(dir);
  std::ofstream out(dir / "vision_decomposition_error_curves.csv");
  out << "sigma_px,baseline_m,median_R_deg,median_t_deg,median_n_deg\n";
  double previous_noise_t = 0;
  for (const double sigma : {0.0, 0.25, 0.5, 1.0, 2.0}) {
    for (const double baseline : {0.05, 0.1, 0.2, 0.4}) {
      std::vector<double> eR, et, en;
      for (uint64_t seed = 0; seed < 15; ++seed) {
        const Errors e = pipeline_errors(sigma, baseline, 1000 + seed);
        eR.push_back(e.R_deg), et.push_back(e.t_deg), en.push_back(e.n_deg);
      }
      for (auto* v : {&eR, &et, &en}) std::nth_element(v->begin(), v->begin() + 7, v->end());
      out << sigma << "," << baseline << "," << eR[7] << "," << et[7] << "," << en[7] << "\n";
      if (baseline == 0.2) {
        EXPECT_GE(et[7] + 1e-9, previous_noise_t * 0.5);  // error grows with noise (roughly)
        previous_noise_t = et[7];
        if (sigma <= 1.0) {
          EXPECT_LT(et[7], 10.0) << sigma;
        }
      }
    }
  }
}

}  // namespace
}  // namespace alight::vision
