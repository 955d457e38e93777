// The AVX2 variants of SURF description, descriptor matching and STAR's peak collection against
// their scalar references: bit for bit equal on random images, keypoints (near and at the
// border too, any pattern rotation, both sub-region layouts), descriptor sets (ties, near
// duplicates, set sizes that are not multiples of the vector width) and response images
// (plateaus), and the peaks equal to the OpenCV comparisons they replace. On a CPU without AVX2
// both calls take the scalar path.
#include <gtest/gtest.h>

#include <cstring>
#include <opencv2/imgproc.hpp>
#include <random>

#include "vision/frontend/matcher.hpp"
#include "vision/frontend/star_detector.hpp"
#include "vision/frontend/surf_descriptor.hpp"

namespace alight::vision {
namespace {

bool bitwise_equal(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return false;
  for (int r = 0; r < a.rows; ++r)
    if (std::memcmp(a.ptr(r), b.ptr(r), a.cols * a.elemSize()) != 0) return false;
  return true;
}

cv::Mat random_image(int rows, int cols, std::mt19937_64& rng) {
  cv::Mat g(rows, cols, CV_8UC1);
  cv::theRNG().state = rng();
  cv::randu(g, 0, 256);
  cv::GaussianBlur(g, g, cv::Size(0, 0), std::uniform_real_distribution<double>(0.5, 3.0)(rng));
  return g;
}

TEST(SurfSimdTest, EqualsScalarOnRandomImagesKeypointsAndRotations) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 24; ++trial) {
    const int rows = 200 + int(rng() % 300), cols = 260 + int(rng() % 420);
    const cv::Mat integral = integral_image(random_image(rows, cols, rng));
    std::uniform_real_distribution<float> ux(0.f, float(cols - 1)), uy(0.f, float(rows - 1));
    std::uniform_real_distribution<float> size(0.f, 7.f), unit(0.f, 1.f);
    std::vector<Keypoint> kps(500);
    for (auto& k : kps) {
      k.x = ux(rng), k.y = uy(rng), k.size = size(rng), k.response = unit(rng) - 0.5f;
      const float edge = unit(rng);  // a quarter at or next to the border
      if (edge < 0.05f)
        k.x = 0.f;
      else if (edge < 0.10f)
        k.y = float(rows - 1);
      else if (edge < 0.15f)
        k.x = std::min(float(cols - 1), 2.f + 30.f * unit(rng));
      else if (edge < 0.25f)
        k.y = std::min(float(rows - 1), 2.f + 30.f * unit(rng));
    }
    for (const bool overlapping : {true, false}) {
      SurfParams sp;
      sp.overlapping_subregions = overlapping;
      const double angle = trial == 0 ? 0.0 : (unit(rng) - 0.5) * 2.0 * M_PI;
      const cv::Mat fast = describe_surf(integral, kps, sp, angle);
      const cv::Mat reference = describe_surf_scalar(integral, kps, sp, angle);
      EXPECT_TRUE(bitwise_equal(fast, reference))
          << "trial " << trial << " overlapping " << overlapping << " angle " << angle;
    }
  }
}

TEST(SurfSimdTest, DescriptorRowsKeepTheKeypointsOrder) {
  // The fast path describes in another order (top to bottom); row k is still keypoint k's.
  std::mt19937_64 rng(3);
  const cv::Mat integral = integral_image(random_image(240, 320, rng));
  std::vector<Keypoint> kps = {
      {200.f, 180.f, 3.f, 1.f}, {100.f, 60.f, 2.f, 1.f}, {160.f, 120.f, 4.f, -1.f}};
  const cv::Mat all = describe_surf(integral, kps, SurfParams{}, 0.1);
  for (size_t k = 0; k < kps.size(); ++k) {
    const cv::Mat one = describe_surf(integral, {kps[k]}, SurfParams{}, 0.1);
    EXPECT_TRUE(bitwise_equal(all.row(int(k)), one)) << k;
  }
}

cv::Mat random_descriptors(int n, std::mt19937_64& rng) {
  std::normal_distribution<float> g(0.f, 1.f);
  cv::Mat d(n, kSurfLength, CV_32F);
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < kSurfLength; ++c) d.at<float>(r, c) = g(rng);
    cv::normalize(d.row(r), d.row(r));
  }
  return d;
}

void expect_equal(const std::vector<Match>& a, const std::vector<Match>& b, int trial) {
  ASSERT_EQ(a.size(), b.size()) << "trial " << trial;
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].i1, b[k].i1) << "trial " << trial;
    EXPECT_EQ(a[k].i2, b[k].i2) << "trial " << trial;
    EXPECT_EQ(std::memcmp(&a[k].distance, &b[k].distance, sizeof(float)), 0) << "trial " << trial;
  }
}

TEST(MatcherSimdTest, EqualsScalarOnRandomSetsWithTiesAndNearDuplicates) {
  std::mt19937_64 rng(11);
  std::normal_distribution<float> noise(0.f, 1.f);
  int matched = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const int n1 = 1 + int(rng() % 90), n2 = 1 + int(rng() % 90);
    cv::Mat d1 = random_descriptors(n1, rng);
    cv::Mat d2 = random_descriptors(n2, rng);
    for (int i = 1; i < n1; ++i)  // rows of d1 equal to an earlier one: ties within a column
      if (rng() % 5 == 0) d1.row(int(rng() % i)).copyTo(d1.row(i));
    // Some rows of d2 are noisy copies of rows of d1 (real matches), some exact copies, and
    // some exact copies of each other (ties for the first and the second best).
    for (int j = 0; j < n2; ++j) {
      const int kind = int(rng() % 4), i = int(rng() % n1);
      if (kind == 0) {
        for (int c = 0; c < kSurfLength; ++c)
          d2.at<float>(j, c) = d1.at<float>(i, c) + 0.03f * noise(rng);
        cv::normalize(d2.row(j), d2.row(j));
      } else if (kind == 1) {
        d1.row(i).copyTo(d2.row(j));
      } else if (kind == 2 && j > 0) {
        d2.row(int(rng() % j)).copyTo(d2.row(j));
      }
    }
    std::vector<int8_t> s1(n1), s2(n2);
    for (auto& s : s1) s = rng() % 3 ? 1 : -1;
    for (auto& s : s2) s = rng() % 3 ? 1 : -1;
    MatchParams mp;
    mp.mutual = trial % 3 != 0;
    mp.ratio = trial % 2 ? 0.8 : 0.95;
    mp.max_distance = trial % 5 ? 0.6 : 2.0;
    const auto fast = match_descriptors(d1, d2, mp, &s1, &s2);
    expect_equal(fast, match_descriptors_scalar(d1, d2, mp, &s1, &s2), trial);
    expect_equal(match_descriptors(d1, d2, mp), match_descriptors_scalar(d1, d2, mp), trial);
    matched += int(fast.size());
  }
  EXPECT_GT(matched, 100);  // the sets did produce matches to compare
}

}  // namespace
}  // namespace alight::vision

namespace alight::vision {
namespace {

/// The formulation star_peaks replaces: compare twice, and, collect.
std::vector<cv::Point> peaks_by_comparison(const cv::Mat& best_abs, const cv::Mat& dilated,
                                           const cv::Rect& inner, float threshold) {
  cv::Mat is_max, above;
  cv::compare(best_abs(inner), dilated(inner), is_max, cv::CMP_GE);
  cv::compare(best_abs(inner), threshold, above, cv::CMP_GT);
  cv::bitwise_and(is_max, above, is_max);
  std::vector<cv::Point> where;
  cv::findNonZero(is_max, where);
  for (auto& q : where) q += inner.tl();
  return where;
}

TEST(StarPeaksTest, EqualsTheComparisonsWithPlateausAndOddWidths) {
  std::mt19937_64 rng(5);
  size_t total = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const int rows = 8 + int(rng() % 100), cols = 8 + int(rng() % 150);
    cv::Mat b(rows, cols, CV_32F);
    // Few levels, so that a pixel equal to its window's maximum (a plateau) is common.
    std::uniform_int_distribution<int> level(0, trial % 2 ? 6 : 60);
    for (int y = 0; y < rows; ++y)
      for (int x = 0; x < cols; ++x) b.at<float>(y, x) = 0.5f * float(level(rng));
    const int k = 2 * int(rng() % 3) + 1;
    cv::Mat dilated;
    cv::dilate(b, dilated, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)));
    const int mx = int(rng() % 4), my = int(rng() % 4);
    const cv::Rect inner(mx, my, cols - mx - int(rng() % 4), rows - my - int(rng() % 4));
    const float threshold = trial % 3 == 0 ? 0.f : 1.5f;
    const auto expected = peaks_by_comparison(b, dilated, inner, threshold);
    EXPECT_EQ(star_peaks(b, dilated, inner, threshold), expected) << "trial " << trial;
    EXPECT_EQ(star_peaks(b, dilated, inner, threshold, false), expected) << "trial " << trial;
    total += expected.size();
  }
  EXPECT_GT(total, 1000u);
}

}  // namespace
}  // namespace alight::vision
