#pragma once
// The moving top's RANSAC inlier count (moving_top.cpp, stage 2): every draw's similarity is
// checked against every candidate, up to 300 draws and three passes a frame. Vectorised four
// candidates at a time in Similarity2::apply's arithmetic and order (separate multiply and add,
// IEEE square root), so both give the same bits; the scalar loop is kept for machines without
// AVX2 and as the test's reference.

#include <cstddef>
#include <vector>

#include "vision/landing/moving_top.hpp"

namespace alight::vision {

/// Candidate correspondences p1[k] -> p2[k] on the top's plane [m], each with its own tolerance
/// [m], laid out as columns of four lanes (padded with candidates that fit nothing).
class SimilarityCandidates {
 public:
  SimilarityCandidates(const std::vector<Vector2d>& p1, const std::vector<Vector2d>& p2,
                       const std::vector<double>& tol_m);
  size_t size() const { return size_; }

 private:
  friend size_t similarity_inliers(const Similarity2&, const SimilarityCandidates&,
                                   std::vector<size_t>*);
  friend size_t similarity_inliers_scalar(const Similarity2&, const SimilarityCandidates&,
                                          std::vector<size_t>*);
  std::vector<double> p1x_, p1y_, p2x_, p2y_, tol_;
  size_t size_ = 0;
};

/// The candidates k with |S(p1[k]) - p2[k]| <= tol_m[k]: their count, and their indices in
/// increasing order into *in where given (a draw counts first and collects only a new best).
size_t similarity_inliers(const Similarity2& S, const SimilarityCandidates& cand,
                          std::vector<size_t>* in);

/// The same without the AVX2 variant (exposed for the test that both agree bit for bit).
size_t similarity_inliers_scalar(const Similarity2& S, const SimilarityCandidates& cand,
                                 std::vector<size_t>* in);

}  // namespace alight::vision
