// The moving top's inlier count: the candidates a similarity carries within their tolerance, and
// the AVX2 variant bit for bit equal to the scalar reference (the same indices, including
// candidates exactly at their tolerance and counts that leave padding lanes).
#include "vision/landing/similarity_inliers.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace alight::vision {
namespace {

TEST(SimilarityInliersTest, CountsTheCandidatesTheSimilarityCarriesWithinTheirTolerance) {
  const Similarity2 S{1.02, 0.3, Vector2d(0.25, -0.1)};
  std::vector<Vector2d> p1, p2;
  std::vector<double> tol;
  std::vector<size_t> expected;
  for (int k = 0; k < 11; ++k) {
    const Vector2d p(0.05 * k - 0.2, 0.03 * (k % 4));
    p1.push_back(p);
    const bool inlier = k % 3 != 1;
    // Inliers 1 cm off their image under a 2 cm tolerance; outliers 5 cm off.
    p2.push_back(S.apply(p) + Vector2d(inlier ? 0.01 : 0.05, 0));
    tol.push_back(0.02);
    if (inlier) expected.push_back(size_t(k));
  }
  const SimilarityCandidates cand(p1, p2, tol);
  EXPECT_EQ(cand.size(), 11u);
  std::vector<size_t> in;
  EXPECT_EQ(similarity_inliers(S, cand, &in), expected.size());
  EXPECT_EQ(in, expected);
  EXPECT_EQ(similarity_inliers(S, cand, nullptr), expected.size());
  // An empty set counts nothing.
  const SimilarityCandidates none({}, {}, {});
  EXPECT_EQ(similarity_inliers(S, none, &in), 0u);
  EXPECT_TRUE(in.empty());
}

TEST(SimilarityInliersTest, VectorisedEqualsScalarBitForBit) {
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<double> u(-1, 1);
  size_t boundary = 0, total_in = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const size_t n = size_t(trial % 13) + 1 + size_t(trial / 13) * 17;  // every padding length
    const Similarity2 S{1 + 0.1 * u(rng), 3.2 * u(rng), Vector2d(u(rng), u(rng))};
    std::vector<Vector2d> p1, p2;
    std::vector<double> tol;
    for (size_t k = 0; k < n; ++k) {
      const Vector2d p(0.4 * u(rng), 0.3 * u(rng));
      const Vector2d q = S.apply(p) + 0.03 * Vector2d(u(rng), u(rng));
      p1.push_back(p), p2.push_back(q);
      if (k % 4 == 2) {
        // Exactly at the tolerance, in the count's own arithmetic: kept by both or by neither.
        tol.push_back((S.apply(p) - q).norm());
        ++boundary;
      } else {
        tol.push_back(0.02 * (1 + u(rng)));
      }
    }
    const SimilarityCandidates cand(p1, p2, tol);
    std::vector<size_t> fast, reference;
    const size_t n_fast = similarity_inliers(S, cand, &fast);
    const size_t n_ref = similarity_inliers_scalar(S, cand, &reference);
    ASSERT_EQ(n_fast, n_ref) << "trial " << trial;
    ASSERT_EQ(fast, reference) << "trial " << trial;
    EXPECT_EQ(n_ref, reference.size());
    EXPECT_LE(n_ref, n);
    total_in += n_ref;
  }
  EXPECT_GT(boundary, 0u);
  EXPECT_GT(total_in, 0u);  // the draws hold inliers and outliers both
}

}  // namespace
}  // namespace alight::vision
