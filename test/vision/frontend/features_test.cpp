// STAR + sub-pixel refinement, upright SURF with the known-rotation option, matching: known
// answers on synthetic blobs, warped photo-like images with known homographies, degenerate
// images.
#include <gtest/gtest.h>

#include <cstdio>
#include <numeric>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "test/vision/test_images.hpp"
#include "vision/frontend/matcher.hpp"
#include "vision/frontend/star_detector.hpp"
#include "vision/frontend/surf_descriptor.hpp"
#include "vision/geometry/homography.hpp"

namespace alight::vision {
namespace {

using testing::from_cv;
using testing::procedural_photo;
using testing::view_homography;
using testing::view_of;

constexpr double kDeg = M_PI / 180.0;

struct PairResult {
  double corner_error_px = 1e9;
  int n_matches = 0, n_inliers = 0;
  int n_correct = 0;  ///< matches within 1.5 px of the true homography
  bool ok = false;
};

/// Full front end on two views: detect, describe (pattern angles), match, fit H.
PairResult run_pair(const cv::Mat& a, const cv::Mat& b, const Matrix3d& H_true, StarParams sp,
                    double angle_a = 0.0, double angle_b = 0.0, const SurfParams& surf = {},
                    HomographyParams hp = {}) {
  PairResult r;
  const cv::Mat ia = integral_image(a), ib = integral_image(b);
  const auto ka = detect_star(a, ia, sp), kb = detect_star(b, ib, sp);
  if (!ka || !kb) return r;
  const cv::Mat da = describe_surf(ia, *ka, surf, angle_a);
  const cv::Mat db = describe_surf(ib, *kb, surf, angle_b);
  const auto sa = response_signs(*ka), sb = response_signs(*kb);
  const auto m = match_descriptors(da, db, MatchParams{}, &sa, &sb);
  r.n_matches = int(m.size());
  std::vector<Vector2d> x1, x2;
  for (const auto& mm : m) {
    x1.emplace_back((*ka)[mm.i1].x, (*ka)[mm.i1].y);
    x2.emplace_back((*kb)[mm.i2].x, (*kb)[mm.i2].y);
    r.n_correct += transfer_error(H_true, x1.back(), x2.back()) < 1.5;
  }
  hp.threshold_px = 1.5;
  const auto fit = fit_homography(x1, x2, hp);
  if (!fit) return r;
  r.ok = true;
  r.n_inliers = fit->n_inliers;
  r.corner_error_px = corner_error(fit->H, H_true, 640, 480);
  return r;
}

TEST(StarDetectorTest, BlankImageHasTooFewFeatures) {
  const cv::Mat blank(480, 640, CV_8UC1, cv::Scalar(90));
  const auto k = detect_star(blank, integral_image(blank), StarParams{});
  EXPECT_FALSE(k);
  EXPECT_EQ(k.reason(), Reason::kTooFewFeatures);
}

TEST(StarDetectorTest, WrongTypeOrTinyImageIsBadImage) {
  const cv::Mat colour(480, 640, CV_8UC3, cv::Scalar(1, 2, 3));
  EXPECT_EQ(detect_star(colour, cv::Mat(), StarParams{}).reason(), Reason::kBadImage);
  const cv::Mat tiny(10, 10, CV_8UC1, cv::Scalar(0));
  EXPECT_EQ(detect_star(tiny, integral_image(tiny), StarParams{}).reason(), Reason::kBadImage);
  EXPECT_EQ(detect_star(cv::Mat(), cv::Mat(), StarParams{}).reason(), Reason::kBadImage);
}

TEST(StarDetectorTest, FindsABlobAtItsSubPixelCentreAndSignAndScale) {
  // A bright anti-aliased Gaussian blob at a fractional position, on a grey background.
  cv::Mat img(120, 160, CV_32F, cv::Scalar(80));
  const double cx = 70.3, cy = 55.7, sigma = 2.5;
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x)
      img.at<float>(y, x) +=
          float(120 * std::exp(-((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (2 * sigma * sigma)));
  cv::Mat g;
  img.convertTo(g, CV_8U);
  StarParams p;
  p.max_size = 5;
  const auto k = detect_star(g, integral_image(g), p);
  ASSERT_TRUE(k || k.reason() == Reason::kTooFewFeatures);
  // Fewer than 4 peaks is "too few features" by contract; detect with the blob replicated.
  cv::Mat four;
  cv::hconcat(std::vector<cv::Mat>{g, g}, four);
  cv::vconcat(std::vector<cv::Mat>{four, four}, four);
  p.subpixel = true;
  const auto ks = detect_star(four, integral_image(four), p);
  p.subpixel = false;
  const auto ki = detect_star(four, integral_image(four), p);
  ASSERT_TRUE(ks && ki);
  auto nearest = [&](const std::vector<Keypoint>& kps) {
    const Keypoint* best = nullptr;
    for (const auto& kp : kps)
      if (!best || std::hypot(kp.x - cx, kp.y - cy) < std::hypot(best->x - cx, best->y - cy))
        best = &kp;
    return *best;
  };
  const Keypoint s = nearest(*ks), i = nearest(*ki);
  EXPECT_GT(s.response, 0);  // bright blob
  EXPECT_LT(std::hypot(s.x - cx, s.y - cy), 0.15);
  EXPECT_LT(std::hypot(s.x - cx, s.y - cy), std::hypot(i.x - cx, i.y - cy));
  EXPECT_GE(s.size, 1.0);
  EXPECT_LE(s.size, 4.0);  // blob radius ~ 2.5 sigma / 2: a small filter
}

TEST(StarDetectorTest, KeepsAtMostMaxFeaturesStrongestFirst) {
  const cv::Mat img =
      view_of(procedural_photo(900, 700, 1), view_homography(900, 700, 0, 1, 0, 0, 0, 0));
  StarParams p;
  p.max_features = 100;
  const auto k = detect_star(img, integral_image(img), p);
  ASSERT_TRUE(k);
  EXPECT_EQ(k->size(), 100u);
  p.max_features = 0;
  const auto all = detect_star(img, integral_image(img), p);
  ASSERT_TRUE(all);
  EXPECT_GT(all->size(), 300u);
  float weakest_kept = 1e9;
  for (const auto& kp : *k) weakest_kept = std::min(weakest_kept, std::abs(kp.response));
  int stronger = 0;
  for (const auto& kp : *all) stronger += std::abs(kp.response) > weakest_kept;
  EXPECT_LE(stronger, 100);
}

// Regression, landing_photo 9901 (issue 15): a smooth photographed top over a busy printed floor
// kept 4-11 matches (12 needed) because the floor's stronger peaks took the feature budget of
// every grid cell the top shares with it. The pipeline's default budget (finer grid, more
// features) leaves a smooth top of about a cell its share in both views.
TEST(StarDetectorTest, PipelineBudgetLeavesASmoothTopOverABusyFloorItsMatches) {
  const StarParams legacy = [] {
    StarParams s;
    s.grid_cols = 4, s.grid_rows = 3, s.max_features = 600;
    return s;
  }();
  const StarParams now = PipelineParams{}.star;
  const cv::Rect top(400, 110, 140, 190);  // about the 9901 top's size at 1.4 m
  const Matrix3d H_ab = view_homography(640, 480, 2 * kDeg, 1.03, 6, -4, 0, 0);
  int legacy_fewer = 0;
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    cv::Mat scene = procedural_photo(640, 480, seed);
    cv::Mat busy;  // the floor: contrast doubled, as a circuit board against fruit
    scene.convertTo(busy, CV_8U, 2.0, -128.0);
    cv::Mat smooth;  // the top: another texture, a quarter of the contrast, out of focus
    procedural_photo(top.width, top.height, 100 + seed).convertTo(smooth, CV_8U, 0.25, 96.0);
    cv::GaussianBlur(smooth, smooth, cv::Size(0, 0), 1.5);
    smooth.copyTo(busy(top));
    const cv::Mat a = busy;
    cv::Mat b;
    cv::warpPerspective(a, b, testing::to_cv(H_ab), a.size(), cv::INTER_LINEAR,
                        cv::BORDER_REFLECT101);
    auto correct_on_top = [&](const StarParams& sp) {
      const cv::Mat ia = integral_image(a), ib = integral_image(b);
      const auto ka = detect_star(a, ia, sp), kb = detect_star(b, ib, sp);
      if (!ka || !kb) return 0;
      const auto sa = response_signs(*ka), sb = response_signs(*kb);
      const auto m = match_descriptors(describe_surf(ia, *ka, {}), describe_surf(ib, *kb, {}),
                                       MatchParams{}, &sa, &sb);
      int n = 0;
      for (const auto& mm : m) {
        const Vector2d x1((*ka)[mm.i1].x, (*ka)[mm.i1].y), x2((*kb)[mm.i2].x, (*kb)[mm.i2].y);
        n +=
            top.contains(cv::Point(int(x1.x()), int(x1.y()))) && transfer_error(H_ab, x1, x2) < 1.5;
      }
      return n;
    };
    const int n_now = correct_on_top(now), n_legacy = correct_on_top(legacy);
    EXPECT_GE(n_now, 2 * LandingParams{}.min_platform_inliers) << "seed " << seed;
    legacy_fewer += n_legacy < n_now;
    std::printf("seed %d: correct matches on the top %d (legacy budget %d)\n", int(seed), n_now,
                n_legacy);
  }
  EXPECT_EQ(legacy_fewer, 5);  // the budget is what this measures
}

TEST(MatcherTest, MatchesAPermutationOfItselfExactly) {
  std::mt19937_64 rng(2);
  std::normal_distribution<float> g(0, 1);
  cv::Mat d(300, 64, CV_32F);
  for (int r = 0; r < d.rows; ++r) {
    for (int c = 0; c < 64; ++c) d.at<float>(r, c) = g(rng);
    cv::normalize(d.row(r), d.row(r));
  }
  std::vector<int> perm(300);
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), rng);
  cv::Mat e(300, 64, CV_32F);
  for (int r = 0; r < 300; ++r) d.row(perm[r]).copyTo(e.row(r));
  const auto m = match_descriptors(d, e, MatchParams{});
  ASSERT_EQ(m.size(), 300u);
  for (const auto& mm : m) {
    EXPECT_EQ(perm[mm.i2], mm.i1);
    EXPECT_NEAR(mm.distance, 0.f, 1e-3);
  }
}

TEST(MatcherTest, RatioTestRejectsAmbiguousMatchesAndSignsSplitTheSets) {
  cv::Mat a(1, 4, CV_32F), b(2, 4, CV_32F);
  cv::Mat(cv::Matx14f(1, 0, 0, 0)).copyTo(a.row(0));
  cv::Mat(cv::Matx14f(0.99f, 0.141f, 0, 0)).copyTo(b.row(0));
  cv::Mat(cv::Matx14f(0.99f, 0, 0.141f, 0)).copyTo(b.row(1));
  EXPECT_TRUE(match_descriptors(a, b, MatchParams{}).empty());  // two equally good candidates
  std::vector<int8_t> sa = {1}, sb = {1, -1};
  const auto m = match_descriptors(a, b, MatchParams{}, &sa, &sb);  // only one of the same sign
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].i2, 0);
  EXPECT_TRUE(match_descriptors(cv::Mat(), b, MatchParams{}).empty());
}

TEST(FeaturesTest, WarpedPhotoCornerErrorIsBelowHalfAPixel) {
  // Rotations within the upright range, scale, perspective, blur and noise.
  const cv::Mat src = procedural_photo(1000, 800, 11);
  const Matrix3d H1 = view_homography(1000, 800, 0.0, 1.0, 0, 0, 0, 0);
  const cv::Mat a = view_of(src, H1, 0, 2.0, 1);
  struct Case {
    double angle_deg, scale, tilt_x, tilt_y, blur, noise;
  };
  for (const Case c : {Case{5, 1.0, 0, 0, 0, 2}, Case{-10, 1.1, 1e-4, 0, 0.5, 2},
                       Case{12, 0.9, 0, -1.5e-4, 0.8, 3}, Case{0, 1.2, 1e-4, 1e-4, 0, 4}}) {
    const Matrix3d H2 =
        view_homography(1000, 800, c.angle_deg * kDeg, c.scale, 15, -10, c.tilt_x, c.tilt_y);
    const cv::Mat b = view_of(src, H2, c.blur, c.noise, 2);
    const PairResult r = run_pair(a, b, H2 * H1.inverse(), StarParams{});
    ASSERT_TRUE(r.ok) << c.angle_deg;
    EXPECT_LT(r.corner_error_px, 0.5) << "angle " << c.angle_deg << " scale " << c.scale;
    std::printf("warp %+5.1f deg x%.2f: corner error %.3f px, %d matches, %d inliers\n",
                c.angle_deg, c.scale, r.corner_error_px, r.n_matches, r.n_inliers);
    EXPECT_GT(r.n_inliers, 100) << c.angle_deg;
  }
}

// Real photographs (OpenCV's sample images, Debian package opencv-doc, installed by
// scripts/setup): aerial views like the paper's downward camera, a building facade like its
// ingress wall, graffiti on a wall and a baboon's fur (fine, self-similar texture), warped by the
// same known homographies.
// graf1 (0.52 px at +12 deg x0.9) and baboon (no homography at +12 deg x0.9) failed here until
// three changes (see WarpedRealPhotographs* regressions below): the smallest STAR filter n = 1
// is no longer used (its peaks on fine texture do not survive blur and scale), SURF's
// sub-regions overlap as in MU-SURF, and the final refinement of H is Cauchy-weighted.
const std::string kPhotoDir = "/usr/share/doc/opencv-doc/examples/data/";

struct WarpCase {
  double angle_deg, scale, tilt_x, tilt_y, blur, noise;
};
constexpr WarpCase kWarpCases[] = {{5, 1.0, 0, 0, 0, 2},
                                   {-10, 1.1, 1e-4, 0, 0.5, 2},
                                   {12, 0.9, 0, -1.5e-4, 0.8, 3},
                                   {0, 1.2, 1e-4, 1e-4, 0, 4}};

/// Two views of a photograph: the unrotated one, and the one warped by case c; H_true maps the
/// first to the second.
struct PhotoPair {
  cv::Mat a, b;
  Matrix3d H_true;
};
PhotoPair photo_pair(const cv::Mat& src, const WarpCase& c) {
  const Matrix3d H1 = view_homography(src.cols, src.rows, 0.0, 1.0, 0, 0, 0, 0);
  const Matrix3d H2 =
      view_homography(src.cols, src.rows, c.angle_deg * kDeg, c.scale, 15, -10, c.tilt_x, c.tilt_y);
  return {view_of(src, H1, 0, 2.0, 1), view_of(src, H2, c.blur, c.noise, 2), H2 * H1.inverse()};
}

cv::Mat load_photo(const char* name) {
  const cv::Mat src = cv::imread(kPhotoDir + name, cv::IMREAD_GRAYSCALE);
  EXPECT_FALSE(src.empty()) << kPhotoDir << name << " missing: scripts/setup installs opencv-doc";
  return src;
}

TEST(FeaturesTest, WarpedRealPhotographsCornerErrorIsBelowHalfAPixel) {
  for (const char* name : {"aero1.jpg", "aero3.jpg", "building.jpg", "graf1.png", "baboon.jpg"}) {
    const cv::Mat src = load_photo(name);
    ASSERT_FALSE(src.empty());
    for (const WarpCase& c : kWarpCases) {
      const PhotoPair p = photo_pair(src, c);
      const PairResult r = run_pair(p.a, p.b, p.H_true, StarParams{});
      ASSERT_TRUE(r.ok) << name << " " << c.angle_deg;
      EXPECT_LT(r.corner_error_px, 0.5) << name << " angle " << c.angle_deg << " scale " << c.scale;
      EXPECT_GT(r.n_inliers, 50) << name << " " << c.angle_deg;
      std::printf("%-13s %+5.1f deg x%.2f: corner error %.3f px, %d matches, %d inliers\n", name,
                  c.angle_deg, c.scale, r.corner_error_px, r.n_matches, r.n_inliers);
    }
  }
}

// Regression (graf1 / baboon): SURF's disjoint sub-regions lost the correct match of a point
// on fine texture under 12 deg of rotation, x0.9 scale and blur; MU-SURF's overlapping,
// Gaussian-weighted ones keep it.
TEST(FeaturesTest, WarpedRealPhotographsOverlappingSubRegionsGiveMoreCorrectMatches) {
  const WarpCase& c = kWarpCases[2];  // +12 deg, x0.9, tilted, blurred, noisy
  int overlapping = 0, disjoint = 0;
  for (const char* name : {"graf1.png", "baboon.jpg", "aero3.jpg"}) {
    const cv::Mat src = load_photo(name);
    ASSERT_FALSE(src.empty());
    const PhotoPair p = photo_pair(src, c);
    SurfParams surf;
    const PairResult o = run_pair(p.a, p.b, p.H_true, StarParams{}, 0, 0, surf);
    surf.overlapping_subregions = false;
    const PairResult d = run_pair(p.a, p.b, p.H_true, StarParams{}, 0, 0, surf);
    std::printf("%-11s correct matches: overlapping %d of %d, disjoint %d of %d\n", name,
                o.n_correct, o.n_matches, d.n_correct, d.n_matches);
    EXPECT_GT(o.n_correct, d.n_correct) << name;
    overlapping += o.n_correct, disjoint += d.n_correct;
  }
  EXPECT_GT(overlapping, 1.2 * disjoint);
}

// Regression (baboon): with the 3 x 3 / 5 x 5 filter (min_size 1) the fur's single-pixel peaks
// filled the feature budget and did not survive blur and scale (with SURF's sub-regions 7
// correct matches and no homography; with MU-SURF's about 25). Without it the same budget goes
// to blobs that are found again.
TEST(FeaturesTest, WarpedRealPhotographsSmallestFilterOnFineTextureLosesTheHomography) {
  const cv::Mat src = load_photo("baboon.jpg");
  ASSERT_FALSE(src.empty());
  const PhotoPair p = photo_pair(src, kWarpCases[2]);
  StarParams sp;
  const PairResult two = run_pair(p.a, p.b, p.H_true, sp);
  sp.min_size = 1;
  const PairResult one = run_pair(p.a, p.b, p.H_true, sp);
  std::printf(
      "baboon +12 deg: min_size 2: %d correct of %d matches, %d inliers, %.3f px; "
      "min_size 1: %d correct of %d, %d inliers\n",
      two.n_correct, two.n_matches, two.n_inliers, two.corner_error_px, one.n_correct,
      one.n_matches, one.n_inliers);
  ASSERT_TRUE(two.ok);
  EXPECT_GT(two.n_correct, 2 * one.n_correct);
  EXPECT_LT(two.corner_error_px, 0.5);
}

// Regression (graf1): the residuals of real matches are heavy-tailed, and the plain
// least-squares refinement let the near misses just inside the inlier threshold pull H (0.52 px
// at +12 deg). Summed over the photographs and cases, the Cauchy-weighted refinement is better.
TEST(FeaturesTest, WarpedRealPhotographsRobustRefinementLowersTheCornerError) {
  double robust = 0, plain = 0;
  for (const char* name : {"graf1.png", "building.jpg", "aero3.jpg"}) {
    const cv::Mat src = load_photo(name);
    ASSERT_FALSE(src.empty());
    for (const WarpCase& c : kWarpCases) {
      const PhotoPair p = photo_pair(src, c);
      HomographyParams hp;
      const PairResult r = run_pair(p.a, p.b, p.H_true, StarParams{}, 0, 0, SurfParams{}, hp);
      hp.robust_refinement = false;
      const PairResult l = run_pair(p.a, p.b, p.H_true, StarParams{}, 0, 0, SurfParams{}, hp);
      ASSERT_TRUE(r.ok && l.ok) << name;
      robust += r.corner_error_px, plain += l.corner_error_px;
    }
  }
  std::printf("sum of corner errors over 12 warps: robust %.3f px, least squares %.3f px\n", robust,
              plain);
  EXPECT_LT(robust, 0.95 * plain);
}

TEST(FeaturesTest, SubPixelStarImprovesCornerErrorAndInliers) {
  const cv::Mat src = procedural_photo(1000, 800, 5);
  const Matrix3d H1 = view_homography(1000, 800, 0.0, 1.0, 0, 0, 0, 0);
  const cv::Mat a = view_of(src, H1, 0, 1.5, 3);
  double err_sub = 0, err_int = 0;
  int in_sub = 0, in_int = 0;
  for (int k = 0; k < 6; ++k) {
    const Matrix3d H2 = view_homography(1000, 800, (k - 3) * 2.5 * kDeg, 0.95 + 0.02 * k, 3.3 * k,
                                        -2.7 * k, 5e-5 * k, -4e-5 * k);
    const cv::Mat b = view_of(src, H2, 0.3, 1.5, 10 + k);
    StarParams p;
    const PairResult s = run_pair(a, b, H2 * H1.inverse(), p);
    p.subpixel = false;
    const PairResult i = run_pair(a, b, H2 * H1.inverse(), p);
    ASSERT_TRUE(s.ok && i.ok);
    err_sub += s.corner_error_px, err_int += i.corner_error_px;
    in_sub += s.n_inliers, in_int += i.n_inliers;
  }
  std::printf("sub-pixel: %.3f px %d inliers; integer: %.3f px %d inliers\n", err_sub / 6, in_sub,
              err_int / 6, in_int);
  EXPECT_LT(err_sub, 0.95 * err_int)
      << "sub-pixel " << err_sub / 6 << " px, integer " << err_int / 6 << " px";
  EXPECT_GT(in_sub, in_int);
}

TEST(FeaturesTest, KnownYawRotationKeepsLargeRotationsMatchable) {
  const cv::Mat src = procedural_photo(1000, 800, 17);
  const Matrix3d H1 = view_homography(1000, 800, 0.0, 1.0, 0, 0, 0, 0);
  const Matrix3d H2 = view_homography(1000, 800, 60 * kDeg, 1.0, 0, 0, 0, 0);
  const cv::Mat a = view_of(src, H1), b = view_of(src, H2, 0, 1.0, 4);
  const PairResult upright = run_pair(a, b, H2 * H1.inverse(), StarParams{});
  const PairResult rotated = run_pair(a, b, H2 * H1.inverse(), StarParams{}, 0.0, 60 * kDeg);
  std::printf("60 deg: upright %d inliers, rotated pattern %d inliers %.3f px\n", upright.n_inliers,
              rotated.n_inliers, rotated.corner_error_px);
  EXPECT_LT(upright.n_inliers, 30);  // upright SURF fails beyond about 15 deg
  ASSERT_TRUE(rotated.ok);
  EXPECT_GT(rotated.n_inliers, 150);
  EXPECT_LT(rotated.corner_error_px, 0.5);
}

}  // namespace
}  // namespace alight::vision
