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

TEST(RefinementTest, AViewOfPartOfTheTargetIsSetAsideWhileWholeViewsAreTheMany) {
  // An opening 1.0 x 0.8 m centred at the origin; views that took its lower 0.3 m for the
  // whole (a smooth room above showed no parallax) put the centre 0.25 m low.
  RefinementParams p;
  p.n_min = 3;
  p.gate_min_n = 100;  // the sizes alone
  RefinementEstimator e(p);
  const Vector2d whole(1.0, 0.8), part(1.0, 0.3), larger(1.02, 0.81);
  const Vector3d centre(3, 0, 1.2), low = centre - Vector3d(0, 0, 0.25);
  for (int i = 0; i < 3; ++i) e.add(centre, Matrix3d::Zero(), whole);
  EXPECT_EQ(e.add(low, Matrix3d::Zero(), part), RefinementEstimator::Verdict::kSetAside);
  EXPECT_EQ(e.n(), 3);
  EXPECT_EQ(e.n_set_aside(), 1);
  EXPECT_TRUE(e.mean().isApprox(centre));
  EXPECT_FALSE(e.converged()) << "a view set aside judges no change";
  // A view measuring it a little larger is whole (vision's views fall short, rarely long).
  EXPECT_EQ(e.add(centre, Matrix3d::Zero(), larger), RefinementEstimator::Verdict::kAccepted);
  EXPECT_TRUE(e.converged());
  // Once the part's views are the many, its size reads as the target's: they count again (the
  // larger views stay whole), and the whole ones come back once they are the many again.
  for (int i = 0; i < 4; ++i) e.add(low, Matrix3d::Zero(), part);
  EXPECT_EQ(e.n_set_aside(), 0);
  EXPECT_EQ(e.n(), 9);
  for (int i = 0; i < 3; ++i) e.add(centre, Matrix3d::Zero(), whole);
  EXPECT_EQ(e.n(), 7);
  EXPECT_EQ(e.n_set_aside(), 5);
  EXPECT_TRUE(e.mean().isApprox(centre));
  // Within the gate's floor sigma of the whole's centre (a side 6 cm short) a view is whole.
  const double floor = p.gate_floor_sigma_m;
  EXPECT_EQ(e.add(centre, Matrix3d::Zero(), whole - Vector2d(0, 1.9 * floor)),
            RefinementEstimator::Verdict::kAccepted);
  EXPECT_EQ(e.add(centre, Matrix3d::Zero(), whole - Vector2d(0, 2.1 * floor)),
            RefinementEstimator::Verdict::kSetAside);
}

TEST(RefinementTest, WaypointsWithoutASizeAreWhole) {
  RefinementParams p;
  p.gate_min_n = 100;
  RefinementEstimator e(p);
  e.add(Vector3d(1, 0, 0), Matrix3d::Zero(), Vector2d(1.0, 0.8));
  EXPECT_EQ(e.add(Vector3d(2, 0, 0)), RefinementEstimator::Verdict::kAccepted);
  EXPECT_EQ(e.add(Vector3d(3, 0, 0), Matrix3d::Zero(), Vector2d(1.0, 0.8)),
            RefinementEstimator::Verdict::kAccepted);
  EXPECT_EQ(e.n(), 3);
  EXPECT_DOUBLE_EQ(partial_view_slack_m(Vector2d(1.0, 0.8), Vector2d(0.4, 0.0)), 0.5);
  EXPECT_DOUBLE_EQ(partial_view_slack_m(Vector2d(1.0, 0.8), Vector2d(1.2, 0.9)), 0.0);
  EXPECT_EQ(partial_view_slack_m(Vector2d(1.0, 0.8),
                                 Vector2d::Constant(RefinementEstimator::kUnmeasured)),
            0.0);
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

// A frame that walks (the onboard estimate's drift): waypoint k is the fixed target seen from the
// frame as it is then, plus the waypoints' noise; the frame's stated covariance grows by q per
// waypoint. Returns the target in the frame at the last waypoint.
Vector3d drifting_waypoints(RefinementEstimator& e, std::mt19937_64& rng, int n, double q,
                            double sigma, Matrix3d* frame_cov_out = nullptr) {
  std::normal_distribution<double> N(0.0, 1.0);
  const Vector3d target(1.0, 0.5, 0.2);
  Vector3d walk = Vector3d::Zero();
  Matrix3d frame_cov = Matrix3d::Zero();
  for (int k = 0; k < n; ++k) {
    if (k > 0) {
      walk += std::sqrt(q) * Vector3d(N(rng), N(rng), 0.0);
      frame_cov.diagonal() += Vector3d(q, q, 0.0);
    }
    e.add(target + walk + sigma * Vector3d(N(rng), N(rng), N(rng)), frame_cov);
  }
  if (frame_cov_out) *frame_cov_out = frame_cov;
  return target + walk;
}

TEST(RefinementDriftTest, WithoutDriftTheFilterIsTheMeanBitForBit) {
  RefinementParams p;
  RefinementEstimator e(p);
  std::mt19937_64 rng(5);
  drifting_waypoints(e, rng, 12, 0.0, 0.01);
  EXPECT_EQ(e.filter().x, e.mean());
  EXPECT_TRUE(e.filter().P.isApprox(e.waypoint_noise() / e.n()));
}

// Over many draws: the filter's and the mean's RMS horizontal error against the frame now, and the
// filter's mean NEES (2 dimensions: 2 when its covariance states its error).
struct DriftScore {
  double rms_mean = 0, rms_filter = 0, nees = 0;
};
DriftScore score_drift(const RefinementParams& p, double q, double sigma, int n, uint64_t seed) {
  std::mt19937_64 rng(seed);
  DriftScore d;
  const int trials = 300;
  for (int t = 0; t < trials; ++t) {
    RefinementEstimator e(p);
    const Vector3d now = drifting_waypoints(e, rng, n, q, sigma);
    const auto f = e.filter();
    const Vector2d err = (f.x - now).head<2>();
    d.rms_mean += (e.mean() - now).head<2>().squaredNorm() / trials;
    d.rms_filter += err.squaredNorm() / trials;
    d.nees += err.dot(f.P.topLeftCorner<2, 2>().ldlt().solve(err)) / trials;
  }
  d.rms_mean = std::sqrt(d.rms_mean);
  d.rms_filter = std::sqrt(d.rms_filter);
  return d;
}

TEST(RefinementDriftTest, InADriftingFrameTheFilterFollowsTheFrameAndStatesItsError) {
  RefinementParams p;
  p.gate_min_n = 1000;  // the filter alone (the gate judges the views, not the drift)
  // 1.5 cm of drift per waypoint, 1 cm of waypoint noise under the 3 cm floor (as flown): the
  // mean lags the frame by half the refinement's drift; the filter, whose R is the floor, follows
  // it and states no less than its error.
  const DriftScore a = score_drift(p, 0.015 * 0.015, 0.01, 20, 11);
  EXPECT_LT(a.rms_filter, 0.5 * a.rms_mean) << a.rms_filter << " vs " << a.rms_mean;
  EXPECT_GT(a.nees, 0.5);
  EXPECT_LT(a.nees, 2.3);
  // Waypoints noisier than the floor (4 cm) and a slower drift (0.5 cm per waypoint): R is read
  // from the waypoints, the filter still beats the mean and is consistent.
  const DriftScore b = score_drift(p, 0.005 * 0.005, 0.04, 20, 12);
  EXPECT_LT(b.rms_filter, b.rms_mean) << b.rms_filter << " vs " << b.rms_mean;
  EXPECT_NEAR(b.nees, 2.0, 0.6);
}

TEST(RefinementDriftTest, TheWaypointNoiseIsReadWithoutTheDrift) {
  RefinementParams p;
  p.gate_min_n = 100000;  // no leave-one-out pass: it is quadratic in n
  p.gate_floor_sigma_m = 0.001;
  RefinementEstimator e(p);
  std::mt19937_64 rng(3);
  drifting_waypoints(e, rng, 2000, 0.02 * 0.02, 0.01);
  const Matrix3d R = e.waypoint_noise();
  EXPECT_NEAR(std::sqrt(R(0, 0)), 0.01, 0.0015);
  EXPECT_NEAR(std::sqrt(R(1, 1)), 0.01, 0.0015);
  EXPECT_NEAR(std::sqrt(R(2, 2)), 0.01, 0.0015);
  // And never below the floor (identical waypoints).
  RefinementEstimator same(p);
  for (int k = 0; k < 5; ++k) same.add(Vector3d(1, 2, 3));
  EXPECT_NEAR(same.waypoint_noise()(0, 0), 1e-6, 1e-12);
}

TEST(RefinementDriftTest, OnlyTheGrowthOfTheFramesCovarianceIsDrift) {
  Matrix3d from = Matrix3d::Zero(), to = Matrix3d::Zero();
  from.diagonal() << 0.01, 0.01, 0.04;
  to.diagonal() << 0.02, 0.01, 0.01;  // x grew, z shrank (a height fix)
  const Matrix3d d = frame_drift(from, to);
  EXPECT_NEAR(d(0, 0), 0.01, 1e-15);
  EXPECT_NEAR(d(1, 1), 0.0, 1e-15);
  EXPECT_NEAR(d(2, 2), 0.0, 1e-15);
}

TEST(RefinementTest, TheComponentwiseMedianIgnoresAStrayAndTakesTheUpperMiddle) {
  EXPECT_EQ(componentwise_median({{1, 5, 0}, {9, 4, 0}, {2, 6, 7}}), Vector3d(2, 5, 0));
  EXPECT_EQ(componentwise_median({{1, 0, 0}, {3, 0, 0}}), Vector3d(3, 0, 0));
}

TEST(ApproachAnchorTest, FollowsTheFrameOneDwellAtATimeAndRefusesAJump) {
  TargetFilter start{Vector3d(1, 0.5, 0.2), 1e-4 * Matrix3d::Identity()};
  const Matrix3d R = 1e-4 * Matrix3d::Identity();
  Matrix3d frame_cov = Matrix3d::Zero();
  ApproachAnchor a(start, R, frame_cov, 0.5, 16.27);
  // The frame has drifted 5 cm in x (stated: 5 cm sigma of growth) while the vehicle flew over.
  frame_cov.diagonal() << 0.0025, 0.0025, 0.0;
  int64_t t = 0;
  EXPECT_FALSE(a.add(Vector3d(1.05, 0.5, 0.2), 0.0, t, frame_cov)) << "no waypoint before a dwell";
  std::optional<Vector3d> x;
  for (int i = 0; i < 60 && !x; ++i) {
    t += 50'000;
    // One stray frame among the dwell's: the median ignores it.
    x = a.add(Vector3d(i == 3 ? 1.5 : 1.05, 0.5, 0.2), 0.0, t, frame_cov);
  }
  ASSERT_TRUE(x);
  EXPECT_EQ(a.n_updates(), 1);
  EXPECT_NEAR(x->x(), 1.05, 0.004) << "the drift is stated: the waypoint moves the estimate";
  // No further drift: a waypoint 20 cm off is beyond the gate and refused.
  std::optional<Vector3d> y;
  for (int i = 0; i < 20; ++i) {
    t += 50'000;
    y = a.add(Vector3d(1.25, 0.5, 0.2), 0.0, t, frame_cov);
    EXPECT_FALSE(y);
  }
  EXPECT_GE(a.n_refused(), 1);
  EXPECT_NEAR(a.filter().x.x(), x->x(), 1e-12);
}

TEST(ApproachAnchorTest, WithoutDriftTheEstimateBarelyMoves) {
  // The refinement's estimate from 10 waypoints of 1 cm: a later waypoint 2 cm off moves it by a
  // tenth of that, as an eleventh waypoint would the mean.
  const Matrix3d R = 1e-4 * Matrix3d::Identity();
  ApproachAnchor a({Vector3d(1, 0.5, 0.2), R / 10}, R, Matrix3d::Zero(), 0.5, 16.27);
  std::optional<Vector3d> x;
  for (int64_t t = 0; !x; t += 50'000)
    x = a.add(Vector3d(1.02, 0.5, 0.2), 0.0, t, Matrix3d::Zero());
  EXPECT_NEAR(x->x(), 1.0 + 0.02 / 11, 1e-9);
}

TEST(ApproachAnchorTest, PartsOfTheTopFoundLowOverItAreNotTaken) {
  // Half a metre over a 46 x 24 cm top, vision finds 10-20 cm parts of it whose centres lie 5 cm
  // off (partial_view_slack_m 0.15-0.2 m): however much drift the frame states, they do not move
  // the estimate; a full view (slack within the waypoints' 1 cm noise) does.
  const Matrix3d R = 1e-4 * Matrix3d::Identity();
  Matrix3d frame_cov = Matrix3d::Zero();
  ApproachAnchor a({Vector3d(0.9, 0.7, 0.15), R}, R, frame_cov, 0.5, 16.27);
  frame_cov.diagonal() << 0.01, 0.01, 0.0;
  int64_t t = 0;
  for (int i = 0; i < 40; ++i, t += 50'000) {
    EXPECT_FALSE(a.add(Vector3d(0.95, 0.66, 0.15), 0.17, t, frame_cov));
  }
  EXPECT_EQ(a.n_partial(), 40);
  EXPECT_EQ(a.n_updates(), 0);
  EXPECT_EQ(a.filter().x, Vector3d(0.9, 0.7, 0.15));
  std::optional<Vector3d> x;
  for (int i = 0; i < 40 && !x; ++i, t += 50'000)
    x = a.add(Vector3d(0.92, 0.7, 0.15), 0.008, t, frame_cov);
  ASSERT_TRUE(x);
  EXPECT_GT(x->x(), 0.91);
  EXPECT_EQ(a.n_partial(), 40);
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
