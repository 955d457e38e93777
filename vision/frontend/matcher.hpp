#pragma once
// Descriptor matching (paper 3.1.1): nearest neighbour in Euclidean distance with Lowe's ratio
// test (Lowe, IJCV 2004) and a mutual (cross) check. Vectorised: for unit descriptors
// |a - b|^2 = 2 - 2 a.b, so all distances come from one dense product, computed block-wise
// against the transposed second set so the inner loop is a plain vector multiply-add. As in
// SURF (Bay et al. 2008), bright and dark blobs (sign of the CenSurE response) are matched only
// among themselves, which halves the work and removes impossible pairs.

#include <opencv2/core.hpp>
#include <vector>

#include "vision/frontend/star_detector.hpp"
#include "vision/params.hpp"

namespace alight::vision {

struct Match {
  int i1 = -1;         ///< row in the first descriptor set
  int i2 = -1;         ///< row in the second
  float distance = 0;  ///< Euclidean distance of the unit descriptors
};

/// Matches d1 against d2 (CV_32F rows of equal length, unit norm). signs1/signs2 (optional,
/// one per row: the sign of the keypoint response) restrict matches to equal signs when
/// params.same_sign_only.
std::vector<Match> match_descriptors(const cv::Mat& d1, const cv::Mat& d2,
                                     const MatchParams& params,
                                     const std::vector<int8_t>* signs1 = nullptr,
                                     const std::vector<int8_t>* signs2 = nullptr);

/// The same without the AVX2 variant (exposed for the test that both agree bit for bit).
std::vector<Match> match_descriptors_scalar(const cv::Mat& d1, const cv::Mat& d2,
                                            const MatchParams& params,
                                            const std::vector<int8_t>* signs1 = nullptr,
                                            const std::vector<int8_t>* signs2 = nullptr);

/// Signs of keypoint responses, for match_descriptors.
std::vector<int8_t> response_signs(const std::vector<Keypoint>& kps);

}  // namespace alight::vision
