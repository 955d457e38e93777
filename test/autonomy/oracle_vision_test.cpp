// The oracle-vision fixture itself: field of view, rate, noise and outlier statistics, seeding.

#include "oracle_vision.hpp"

#include <gtest/gtest.h>

namespace alight::autonomy::test {
namespace {

OracleTruth landing_truth(const Vector3d& vehicle) {
  OracleTruth t;
  t.vehicle.p_W_B = vehicle;
  t.has_platform = true;
  t.platform_center_W = Vector3d(1, 0.5, 0.2);
  t.platform_size_m = Vector3d(0.432, 0.279, 0.2);
  return t;
}

TEST(OracleVisionTest, SeesThePlatformOnlyInsideTheFieldOfView) {
  OracleVisionParams p;
  OracleVision v(p);
  EXPECT_TRUE(v.in_view(landing_truth({1, 0.5, 1.2})));
  EXPECT_TRUE(v.in_view(landing_truth({1.2, 0.5, 1.2})));
  EXPECT_TRUE(v.in_view(landing_truth({1.0, 0.85, 1.2}))) << "wider field of view across";
  EXPECT_FALSE(v.in_view(landing_truth({2.2, 0.5, 1.2})));
  EXPECT_FALSE(v.in_view(landing_truth({1, 0.5, 0.45}))) << "closer than min_range";
}

TEST(OracleVisionTest, RateNoiseAndOutliersAreAsConfigured) {
  OracleVisionParams p;
  p.rate_hz = 5;
  p.outlier_prob = 0.1;
  OracleVision v(p);
  const auto truth = landing_truth({1, 0.5, 1.2});
  int n = 0;
  double sxx = 0, szz = 0;
  int inliers = 0;
  for (int64_t t = 0; t < 2000'000'000; t += 10'000) {
    const auto m = v.update(truth, t);
    if (!m) continue;
    ++n;
    ASSERT_TRUE(m->found);
    const Vector3d e = m->p_W_target - truth.platform_center_W;
    if (e.norm() < 0.1) {
      ++inliers;
      sxx += e.x() * e.x();
      szz += e.z() * e.z();
    }
  }
  EXPECT_NEAR(n, 2000 * 5, 2);
  EXPECT_NEAR(v.n_outliers() / double(n), 0.1, 0.015);
  EXPECT_NEAR(std::sqrt(sxx / inliers), p.sigma_xy_m, 0.001);
  EXPECT_NEAR(std::sqrt(szz / inliers), p.sigma_z_m, 0.002);
}

TEST(OracleVisionTest, SeededSilentAndBlind) {
  OracleVisionParams p;
  OracleVision a(p), b(p);
  const auto truth = landing_truth({1, 0.5, 1.2});
  for (int64_t t = 0; t < 5'000'000; t += 10'000) {
    const auto ma = a.update(truth, t), mb = b.update(truth, t);
    ASSERT_EQ(ma.has_value(), mb.has_value());
    if (ma) {
      EXPECT_EQ(ma->p_W_target, mb->p_W_target);
    }
  }
  a.blind = true;
  for (int64_t t = 5'000'000; t < 6'000'000; t += 10'000) {
    if (auto m = a.update(truth, t)) {
      EXPECT_FALSE(m->found);
    }
  }
  b.silent = true;
  for (int64_t t = 5'000'000; t < 6'000'000; t += 10'000) EXPECT_FALSE(b.update(truth, t));
}

}  // namespace
}  // namespace alight::autonomy::test
