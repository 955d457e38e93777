// The known floor's per-match verdict: floor matches carried within a hair, a top's matches at
// its inverse distance with an interval that holds it, the defaults where a match has no parallax
// or lies behind camera 2; and the AVX2 variant bit for bit equal to the scalar reference over
// random views, sizes that are not multiples of the vector width, and degenerate matches.
#include "vision/geometry/floor_classify.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

namespace alight::vision {
namespace {

// Two downward views dt apart over a floor 1.5 m below camera 1 and a top 0.3 m above it.
struct TwoViews {
  Matrix3d R;  // camera 1 -> camera 2
  Vector3d t;  // camera 1 -> camera 2, in camera 1 [m]
  Vector3d n = Vector3d::UnitZ();
  double d_floor = 1.5, d_top = 1.2;
  std::vector<Vector3d> x1, x2;
  std::vector<int> on;  // 0 floor, 1 top, 2 random
};

TwoViews views(std::mt19937_64& rng, int n_matches) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  TwoViews v;
  v.R = Eigen::AngleAxisd(0.05 * u(rng), Vector3d(u(rng), u(rng), u(rng)).normalized())
            .toRotationMatrix();
  v.t = Vector3d(0.3 * u(rng), 0.3 * u(rng), 0.1 * u(rng));
  for (int i = 0; i < n_matches; ++i) {
    const int kind = int(rng() % 3);
    Vector3d x1(0.6 * u(rng), 0.45 * u(rng), 1.0);
    const double d = kind == 1 ? v.d_top : v.d_floor;
    const Vector3d X = x1 * d;  // on the plane z = d in camera 1 (n = z)
    Vector3d X2 = v.R * (X - v.t);
    Vector3d x2 = X2 / X2.z();
    if (kind == 2) x2 = Vector3d(0.6 * u(rng), 0.45 * u(rng), 1.0);
    v.x1.push_back(x1);
    v.x2.push_back(x2);
    v.on.push_back(kind);
  }
  return v;
}

bool same_bits(const std::vector<PerMatch>& a, const std::vector<PerMatch>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(PerMatch)) == 0;
}

TEST(FloorClassifyTest, FloorCarriedAndTopAtItsInverseDistance) {
  std::mt19937_64 rng(3);
  const TwoViews v = views(rng, 203);
  const double f = 600, thr = 1.5;
  std::vector<PerMatch> pm;
  classify_floor_matches(v.x1, v.x2, v.R, v.t, v.n, 1.0 / v.d_floor, f, thr, &pm);
  ASSERT_EQ(pm.size(), v.x1.size());
  int tops = 0;
  for (size_t i = 0; i < pm.size(); ++i) {
    if (v.on[i] == 0) {
      EXPECT_LT(pm[i].err_floor, 1e-6) << i;
    }
    if (v.on[i] != 1) continue;
    EXPECT_GT(pm[i].err_floor, thr) << i;
    if (pm[i].half_width > 0.05) continue;  // little parallax: no verdict to check
    ++tops;
    EXPECT_LT(pm[i].err_rho, 1e-6) << i;
    EXPECT_NEAR(pm[i].rho, 1.0 / v.d_top, 1e-9) << i;
    EXPECT_GT(pm[i].half_width, 0) << i;
  }
  EXPECT_GT(tops, 30);
}

TEST(FloorClassifyTest, DefaultsWithoutParallaxOrBehindTheCamera) {
  const std::vector<Vector3d> x1{{0.1, 0.2, 1.0}, {0.1, 0.2, 1.0}};
  const std::vector<Vector3d> x2{{0.1, 0.2, 1.0}, {0.1, 0.2, 1.0}};
  std::vector<PerMatch> pm;
  // No translation: no match has parallax (rho undefined).
  classify_floor_matches(x1, x2, Matrix3d::Identity(), Vector3d::Zero(), Vector3d::UnitZ(), 0.5,
                         600, 1.5, &pm);
  for (const auto& m : pm) {
    EXPECT_EQ(m.err_floor, 0.0);
    EXPECT_EQ(m.rho, 0.0);
    EXPECT_EQ(m.err_rho, 1e9);
    EXPECT_EQ(m.half_width, 0.0);
  }
  // Camera 2 turned half a turn: everything behind it.
  classify_floor_matches(x1, x2, Eigen::AngleAxisd(M_PI, Vector3d::UnitX()).toRotationMatrix(),
                         Vector3d(0.1, 0, 0), Vector3d::UnitZ(), 0.5, 600, 1.5, &pm);
  for (const auto& m : pm) {
    EXPECT_EQ(m.err_floor, 1e9);
    EXPECT_EQ(m.err_rho, 1e9);
  }
}

TEST(FloorClassifyTest, VectorisedEqualsScalarBitForBit) {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 40; ++trial) {
    TwoViews v = views(rng, 1 + int(rng() % 300));
    // Degenerate matches among them: at the epipole of a pure forward motion, behind camera 2,
    // non-finite.
    if (trial % 4 == 1) v.t = Vector3d(0, 0, 0.2);
    if (trial % 5 == 2 && v.x1.size() > 3) {
      v.x1[1] = Vector3d(0, 0, 1);
      v.x2[2] = Vector3d(NAN, 0.1, 1);
      v.x1[3] = Vector3d(1e12, -1e12, 1);
    }
    if (trial % 7 == 3) v.R = Eigen::AngleAxisd(M_PI * 0.6, Vector3d::UnitY()).toRotationMatrix();
    std::vector<PerMatch> fast, reference;
    for (const double rho : {1.0 / v.d_floor, 0.0, 3.0}) {
      classify_floor_matches(v.x1, v.x2, v.R, v.t, v.n, rho, 600, 1.5, &fast);
      classify_floor_matches_scalar(v.x1, v.x2, v.R, v.t, v.n, rho, 600, 1.5, &reference);
      ASSERT_TRUE(same_bits(fast, reference)) << "trial " << trial << " rho " << rho;
    }
  }
}

}  // namespace
}  // namespace alight::vision
