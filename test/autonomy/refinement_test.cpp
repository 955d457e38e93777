// Refinement estimator (eqs. 7-9, outlier gate) and vantage sampler (N(mu, Sigma) with cutoff).

#include "autonomy/refinement.hpp"

#include <gtest/gtest.h>

#include <random>

#include "autonomy/search_path.hpp"

namespace alight::autonomy {
namespace {

TEST(RefinementTest, MeanAndCovarianceAreTheSampleStatistics) {
  RefinementParams p;
  p.gate_min_n = 100;  // gate off
  RefinementEstimator e(p);
  const std::vector<Vector3d> xs = {{1, 2, 3}, {2, 2, 1}, {3, 5, 2}, {2, 3, 2}};
  for (const auto& x : xs) e.add(x);
  EXPECT_TRUE(e.mean().isApprox(Vector3d(2, 3, 2)));
  Matrix3d C = Matrix3d::Zero();
  for (const auto& x : xs) C += (x - Vector3d(2, 3, 2)) * (x - Vector3d(2, 3, 2)).transpose();
  EXPECT_TRUE(e.covariance().isApprox(C / 3));
}

TEST(RefinementTest, StopsOnlyWhenEquations7To9Hold) {
  RefinementParams p;
  p.n_min = 5;
  p.eps_horz_m = 0.01;
  p.eps_vert_m = 0.02;
  p.gate_min_n = 100;  // eqs. 7-9 alone
  RefinementEstimator e(p);
  for (int i = 0; i < 4; ++i) {
    e.add(Vector3d(1, 1, 0.2));
    EXPECT_FALSE(e.converged()) << "eq. 7: n = " << e.n();
  }
  e.add(Vector3d(1, 1, 0.2));
  EXPECT_TRUE(e.converged());
  // A new waypoint moving the mean 1.2 cm horizontally (6 cm / 5... here 6 cm / 6): eq. 8 fails.
  e.add(Vector3d(1.072, 1, 0.2));
  EXPECT_NEAR(e.last_change().x(), 0.012, 1e-12);
  EXPECT_FALSE(e.converged());
  e.reset();
  for (int i = 0; i < 5; ++i) e.add(Vector3d(1, 1, 0.2));
  e.add(Vector3d(1, 1, 0.2 + 6 * 0.025));  // mean moves 2.5 cm vertically: eq. 9 fails
  EXPECT_FALSE(e.converged());
}

TEST(RefinementTest, HorizontalChangeIsTheNormNotTheSumOfXAndY) {
  // [1 1 0] read literally would sum +x and -y changes to zero.
  RefinementParams p;
  p.n_min = 2;
  p.gate_min_n = 100;
  RefinementEstimator e(p);
  e.add(Vector3d(0, 0, 0));
  e.add(Vector3d(0.05, -0.05, 0));
  EXPECT_FALSE(e.converged());
}

TEST(RefinementTest, GateRejectsAFarOutlierAndKeepsTheMean) {
  RefinementParams p;
  RefinementEstimator e(p);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0, 0.01);
  for (int i = 0; i < 8; ++i) e.add(Vector3d(1 + n(rng), 2 + n(rng), 0.2 + n(rng)));
  const Vector3d mean = e.mean();
  EXPECT_EQ(e.add(Vector3d(1.4, 2, 0.2)), RefinementEstimator::Verdict::kRejected);
  EXPECT_EQ(e.n(), 8);
  EXPECT_EQ(e.n_rejected(), 1);
  EXPECT_EQ(e.mean(), mean);
  EXPECT_GT(e.mahalanobis2(Vector3d(1.4, 2, 0.2)), p.gate_chi2);
  EXPECT_EQ(e.add(Vector3d(1.005, 2.0, 0.2)), RefinementEstimator::Verdict::kAccepted);
}

TEST(RefinementTest, AnOutlierAmongTheFirstWaypointsIsRemovedLater) {
  RefinementParams p;
  RefinementEstimator e(p);
  e.add(Vector3d(1.5, 2.3, 0.6));  // X_V,1 is an outlier: before the gate starts
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n(0, 0.01);
  for (int i = 0; i < 10; ++i) e.add(Vector3d(1 + n(rng), 2 + n(rng), 0.2 + n(rng)));
  EXPECT_GE(e.n_rejected(), 1);
  EXPECT_LT((e.mean() - Vector3d(1, 2, 0.2)).norm(), 0.01);
}

TEST(RefinementTest, RestartsWhenTheEstimateWasSeededByOutliers) {
  RefinementParams p;
  p.max_consecutive_rejections = 3;
  RefinementEstimator e(p);
  for (int i = 0; i < 5; ++i) e.add(Vector3d(0.5 + 0.001 * i, 0, 0));  // consistent but wrong
  EXPECT_EQ(e.add(Vector3d(1, 1, 0)), RefinementEstimator::Verdict::kRejected);
  EXPECT_EQ(e.add(Vector3d(1, 1, 0)), RefinementEstimator::Verdict::kRejected);
  EXPECT_EQ(e.add(Vector3d(1, 1, 0)), RefinementEstimator::Verdict::kRestarted);
  EXPECT_EQ(e.n(), 1);
  EXPECT_EQ(e.mean(), Vector3d(1, 1, 0));
}

TEST(VantageSamplerTest, DrawsRespectTheCutoffAndFollowTheDistribution) {
  RefinementParams p;
  p.cutoff_m = 0.3;
  p.vantage_sigma_floor_m = 0.0;
  VantageSampler s(p, 42);
  Eigen::Matrix2d Sigma;
  Sigma << 0.01, 0.004, 0.004, 0.0025;  // sigma 10 cm x 5 cm, correlated
  const Vector2d mu(1, 2);
  Vector2d sum = Vector2d::Zero();
  Eigen::Matrix2d S = Eigen::Matrix2d::Zero();
  const int N = 20000;
  std::vector<Vector2d> xs;
  for (int i = 0; i < N; ++i) {
    const Vector2d x = s.draw(mu, Sigma, 10);
    ASSERT_LE((x - mu).norm(), p.cutoff_m + 1e-12);
    xs.push_back(x);
    sum += x;
  }
  const Vector2d m = sum / N;
  for (const auto& x : xs) S += (x - m) * (x - m).transpose();
  S /= N - 1;
  EXPECT_LT((m - mu).norm(), 0.003);
  // The 0.3 m cutoff is 3 sigma of the wide axis: truncation shrinks Sigma by a few percent.
  EXPECT_NEAR(S(0, 0), 0.01, 0.001);
  EXPECT_NEAR(S(1, 1), 0.0025, 0.0003);
  EXPECT_NEAR(S(0, 1), 0.004, 0.0005);
}

TEST(VantageSamplerTest, SeededAndUsesThePriorBeforeTwoWaypoints) {
  RefinementParams p;
  VantageSampler a(p, 9), b(p, 9), c(p, 10);
  const Vector2d x = a.draw(Vector2d::Zero(), Eigen::Matrix2d::Zero(), 1);
  EXPECT_EQ(x, b.draw(Vector2d::Zero(), Eigen::Matrix2d::Zero(), 1));
  EXPECT_NE(x, c.draw(Vector2d::Zero(), Eigen::Matrix2d::Zero(), 1));
  EXPECT_GT(x.norm(), 0.0) << "prior + floor: vantages differ from the mean";
}

TEST(SearchPathTest, LawnmowerCoversTheRectangleLaneByLane) {
  const auto pts = lawnmower(Vector2d(0, 0), Vector2d(2, 1), 0.5, 1.2);
  ASSERT_EQ(pts.size(), 6u);  // 3 lanes
  EXPECT_EQ(pts[0], Vector3d(0, 0, 1.2));
  EXPECT_EQ(pts[1], Vector3d(2, 0, 1.2));
  EXPECT_EQ(pts[2], Vector3d(2, 0.5, 1.2));
  EXPECT_EQ(pts[3], Vector3d(0, 0.5, 1.2));
  EXPECT_EQ(pts[5], Vector3d(2, 1, 1.2));
}

TEST(SearchPathTest, CarrotMovesAtTheSpeedAndWaitsForTheVehicle) {
  PathFollower f;
  f.start(Vector3d::Zero(), {Vector3d(1, 0, 0), Vector3d(1, 1, 0)});
  f.step(Vector3d::Zero(), 0.5, 0.4, 0.3);
  EXPECT_TRUE(f.carrot().isApprox(Vector3d(0.2, 0, 0)));
  EXPECT_TRUE(f.carrot_velocity().isApprox(Vector3d(0.4, 0, 0)));
  f.step(Vector3d(-1, 0, 0), 0.5, 0.4, 0.3);  // vehicle far behind: carrot waits
  EXPECT_TRUE(f.carrot().isApprox(Vector3d(0.2, 0, 0)));
  f.step(Vector3d(0.2, 0, 0), 2.5, 0.4, 0.3);  // 1 m: round the corner
  EXPECT_TRUE(f.carrot().isApprox(Vector3d(1, 0.2, 0)));
  EXPECT_FALSE(f.finished(f.carrot(), 0.05));
  for (int i = 0; i < 10; ++i) f.step(f.carrot(), 0.5, 0.4, 0.3);
  EXPECT_TRUE(f.finished(Vector3d(1, 1, 0), 0.05));
}

}  // namespace
}  // namespace alight::autonomy
