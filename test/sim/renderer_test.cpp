#include "sim/renderer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "sim/simulator.hpp"
#include "sim_test_util.hpp"

namespace alight::sim {
namespace {

// Scenes of flat grey surfaces, lit so that adjacent faces differ: edges are the only structure.
Scenario flat(Scenario s) {
  s = test::quiet(s);
  auto grey = [](TextureSpec& t, double mean) {
    t.kind = "noise";
    t.size_px = 64;
    t.mean = mean;
    t.contrast = 0.0;
  };
  grey(s.floor_texture, 60);
  if (s.platform) grey(s.platform->texture, 200);
  if (s.wall) {
    grey(s.wall->texture, 200);
    grey(s.wall->room_texture, 40);
  }
  s.lighting.ambient = 0.0;
  s.lighting.diffuse = 1.0;
  return s;
}

float bilinear(const cv::Mat& img, const Vector2d& p) {
  cv::Mat patch;
  cv::getRectSubPix(img, cv::Size(1, 1), cv::Point2f(float(p.x()), float(p.y())), patch, CV_32F);
  return patch.at<float>(0, 0);
}

// A straight image edge through points measured where the intensity crosses half-way between
// the two sides, on profiles across the edge at 4-16 px from `corner` towards `along`.
cv::Vec4f measure_edge(const cv::Mat& img, const Vector2d& corner, const Vector2d& along) {
  const Vector2d e = (along - corner).normalized();
  const Vector2d nrm(-e.y(), e.x());
  std::vector<cv::Point2f> pts;
  for (double s = 4; s <= 16; s += 1.0) {
    const Vector2d c = corner + s * e;
    std::vector<float> prof;
    for (double k = -4; k <= 4.001; k += 0.125) prof.push_back(bilinear(img, c + k * nrm));
    const float mid = 0.5f * (prof.front() + prof.back());
    for (size_t i = 0; i + 1 < prof.size(); ++i) {
      if ((prof[i] - mid) * (prof[i + 1] - mid) <= 0 && prof[i] != prof[i + 1]) {
        const double k = -4 + 0.125 * (i + (mid - prof[i]) / (prof[i + 1] - prof[i]));
        const Vector2d q = c + k * nrm;
        pts.emplace_back(float(q.x()), float(q.y()));
        break;
      }
    }
  }
  EXPECT_GE(pts.size(), 10u);
  cv::Vec4f line;
  cv::fitLine(pts, line, cv::DIST_L2, 0, 1e-4, 1e-4);
  return line;
}

Vector2d intersect(const cv::Vec4f& a, const cv::Vec4f& b) {
  // p = pa + s da = pb + t db
  Eigen::Matrix2d A;
  A << a[0], -b[0], a[1], -b[1];
  const Vector2d s = A.colPivHouseholderQr().solve(Vector2d(b[2] - a[2], b[3] - a[3]));
  return Vector2d(a[2] + s[0] * a[0], a[3] + s[0] * a[1]);
}

Vector2d project(const CameraModel& m, const Isometry3d& X_WC, const Vector3d& p_W) {
  const auto px = m.project(X_WC.inverse() * p_W);
  EXPECT_TRUE(px.has_value());
  return px.value_or(Vector2d(-1, -1));
}

// Corner c of a polygon whose neighbours are a and b: the rendered corner, from its two edges.
double corner_error(const cv::Mat& img, const CameraModel& m, const Isometry3d& X_WC,
                    const Vector3d& c, const Vector3d& a, const Vector3d& b) {
  const Vector2d pc = project(m, X_WC, c);
  const Vector2d measured = intersect(measure_edge(img, pc, project(m, X_WC, a)),
                                      measure_edge(img, pc, project(m, X_WC, b)));
  return (measured - pc).norm();
}

TEST(SimRendererTest, PlatformCornersProjectOntoTheRenderedCorners) {
  Scenario sc = flat(test::scenario("landing_a"));
  sc.lighting.light_dir_W = Vector3d(0, 0, 1);
  sc.platform->yaw_deg = 17.0;
  const Scene scene = build_scene(sc, 1);
  const Box& box = scene.boxes.at(0);
  for (const bool distorted : {false, true}) {
    SCOPED_TRACE(distorted ? "with distortion" : "ideal lens");
    CameraModel model = CameraModel::firefly_mv_4mm();
    if (distorted) model.D = {-0.25, 0.08, 0.001, -0.001, 0.0};
    Renderer renderer(model, 4);
    // Above the platform's top (no side faces in view), tilted and turned a little.
    const Vector3d C_W = box.center_W + Vector3d(0.04, -0.03, 1.0);
    const Isometry3d X_WC =
        make_transform(rotation_from_rpy(0.06, -0.04, 0.4) * R_BC_downward(), C_W);
    const cv::Mat img = renderer.render(scene, X_WC);
    std::vector<Vector3d> top;
    for (const auto& [sx, sy] : {std::pair{1, 1}, {-1, 1}, {-1, -1}, {1, -1}})
      top.push_back(box.center_W + box.R_WO() * Vector3d(sx * box.half_size_m.x(),
                                                         sy * box.half_size_m.y(),
                                                         box.half_size_m.z()));
    for (int i = 0; i < 4; ++i) {
      const double err = corner_error(img, model, X_WC, top[i], top[(i + 1) % 4], top[(i + 3) % 4]);
      EXPECT_LT(err, 0.5) << "corner " << i;
    }
  }
}

// A photograph printed on a top shows whole: its centre at the top's centre, its border at the
// top's rims. A white square in the middle half of a black photograph is white at the top's
// centre and black near its corners (rolled about the texture's origin, the photograph's black
// corners would meet at the centre).
TEST(SimRendererTest, APhotographOnATopIsCentredOnIt) {
  Scenario sc = flat(test::scenario("landing_a"));
  sc.lighting.light_dir_W = Vector3d(0, 0, 1);
  sc.platform->yaw_deg = 23.0;
  cv::Mat photo(256, 256, CV_8U, cv::Scalar(0));
  photo(cv::Rect(64, 64, 128, 128)).setTo(255);
  TextureSpec& t = sc.platform->texture;
  t.kind = "image";
  t.image = photo;
  const Scene probe = build_scene(sc, 1);
  const Vector3d half = probe.boxes.at(0).half_size_m;
  t.texel_m = 1.1 * 2.0 * half.head<2>().maxCoeff() / 256.0;  // the photo a little larger
  const Scene scene = build_scene(sc, 1);
  const Box& box = scene.boxes.at(0);
  const CameraModel model = CameraModel::firefly_mv_4mm();
  Renderer renderer(model, 4);
  const Vector3d top_W = box.center_W + box.R_WO() * Vector3d(0, 0, half.z());
  const Isometry3d X_WC = make_transform(rotation_from_rpy(0.03, -0.02, 0.3) * R_BC_downward(),
                                         top_W + Vector3d(0.02, 0.01, 0.9));
  cv::Mat img;
  renderer.render(scene, X_WC).convertTo(img, CV_32F);
  const float centre = bilinear(img, project(model, X_WC, top_W));
  for (const auto& [sx, sy] : {std::pair{1, 1}, {-1, 1}, {-1, -1}, {1, -1}}) {
    const Vector3d near_corner_W =
        top_W + box.R_WO() * Vector3d(0.85 * sx * half.x(), 0.85 * sy * half.y(), 0.0);
    const float corner = bilinear(img, project(model, X_WC, near_corner_W));
    EXPECT_GT(centre, corner + 100.f) << "corner " << sx << " " << sy;
  }
}

TEST(SimRendererTest, OpeningCornersProjectOntoTheRenderedCorners) {
  Scenario sc = flat(test::scenario("ingress"));
  sc.lighting.light_dir_W = Vector3d(-1, 0, 0);  // the wall's face lit, the opening's sides dark
  const Scene scene = build_scene(sc, 1);
  const OpeningTruth o = *scene.opening;
  const CameraModel model = CameraModel::firefly_mv_4mm();
  Renderer renderer(model, 4);
  const Vector3d C_W = o.center_W + Vector3d(-1.3, 0.05, 0.03);
  const Isometry3d X_WC =
      make_transform(rotation_from_rpy(0.03, 0.05, -0.06) * R_BC_forward(), C_W);
  const cv::Mat img = renderer.render(scene, X_WC);
  const double w = 0.5 * o.size_m.x(), h = 0.5 * o.size_m.y();
  std::vector<Vector3d> c;
  for (const auto& [sy, sz] : {std::pair{1, 1}, {-1, 1}, {-1, -1}, {1, -1}})
    c.push_back(o.center_W + Vector3d(0, sy * w, sz * h));
  for (int i = 0; i < 4; ++i)
    EXPECT_LT(corner_error(img, model, X_WC, c[i], c[(i + 1) % 4], c[(i + 3) % 4]), 0.5) << i;
}

TEST(SimRendererTest, TwoViewsOfTheFloorAreRelatedByThePlaneHomography) {
  const Scenario sc = test::quiet(test::scenario("landing_none"));
  const Scene scene = build_scene(sc, 3);
  const CameraModel model = CameraModel::firefly_mv_4mm();
  const Renderer renderer(model, 1);
  const Isometry3d X_WC1 = make_transform(rotation_from_rpy(0.02, 0.03, 0.1) * R_BC_downward(),
                                          Vector3d(0.3, -0.2, 1.4));
  const Isometry3d X_WC2 = make_transform(rotation_from_rpy(-0.03, 0.05, 0.16) * R_BC_downward(),
                                          Vector3d(0.45, -0.12, 1.3));
  const cv::Mat img1 = renderer.render(scene, X_WC1), img2 = renderer.render(scene, X_WC2);

  // X_C2 = R X_C1 + t; the floor is n^T X_C1 = -d with n its upward normal in C1 and d the
  // height of C1: H = K (R - t n^T / d) K^-1.
  const Matrix3d R = X_WC2.linear().transpose() * X_WC1.linear();
  const Vector3d t = X_WC2.linear().transpose() * (X_WC1.translation() - X_WC2.translation());
  const Vector3d n = X_WC1.linear().transpose() * Vector3d::UnitZ();
  const double d = X_WC1.translation().z();
  const Matrix3d K = model.K();
  const Matrix3d H = K * (R - t * n.transpose() / d) * K.inverse();
  auto apply = [](const Matrix3d& M, const Vector2d& p) {
    return (M * p.homogeneous()).hnormalized();
  };

  // Measured correspondences: template matching with sub-pixel peaks around the prediction.
  std::vector<cv::Point2f> p1, p2;
  const int half = 12, search = 6;
  for (int v = 60; v <= 420; v += 40) {
    for (int u = 60; u <= 580; u += 40) {
      const Vector2d q = apply(H, Vector2d(u, v));
      const cv::Rect tpl_rect(u - half, v - half, 2 * half + 1, 2 * half + 1);
      const cv::Rect win(int(std::lround(q.x())) - half - search,
                         int(std::lround(q.y())) - half - search, 2 * (half + search) + 1,
                         2 * (half + search) + 1);
      if ((win & cv::Rect(0, 0, 640, 480)) != win) continue;
      cv::Mat score;
      cv::matchTemplate(img2(win), img1(tpl_rect), score, cv::TM_CCOEFF_NORMED);
      double best;
      cv::Point at;
      cv::minMaxLoc(score, nullptr, &best, nullptr, &at);
      if (best < 0.9 || at.x < 1 || at.y < 1 || at.x >= score.cols - 1 || at.y >= score.rows - 1)
        continue;
      auto peak = [](float a, float b, float c) { return 0.5f * (a - c) / (a - 2 * b + c); };
      const float dx = peak(score.at<float>(at.y, at.x - 1), score.at<float>(at.y, at.x),
                            score.at<float>(at.y, at.x + 1));
      const float dy = peak(score.at<float>(at.y - 1, at.x), score.at<float>(at.y, at.x),
                            score.at<float>(at.y + 1, at.x));
      p1.emplace_back(float(u), float(v));
      p2.emplace_back(float(win.x + half + at.x + dx), float(win.y + half + at.y + dy));
    }
  }
  ASSERT_GT(p1.size(), 60u);
  const cv::Mat Hm = cv::findHomography(p1, p2, 0);
  ASSERT_FALSE(Hm.empty());
  Matrix3d H_est;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) H_est(r, c) = Hm.at<double>(r, c);
  double worst = 0;
  for (const Vector2d& corner :
       {Vector2d(0, 0), Vector2d(639, 0), Vector2d(639, 479), Vector2d(0, 479)})
    worst = std::max(worst, (apply(H_est, corner) - apply(H, corner)).norm());
  EXPECT_LT(worst, 0.3);
}

TEST(SimRendererTest, TheLampsFalloffIsFixedInTheWorldAndFramesStillMatch) {
  const Scene even = build_scene(test::quiet(test::scenario("landing_none")), 3);
  Scene lit = even;
  lit.lighting.falloff = 0.3;  // beyond the scenarios' 0.2
  lit.lighting.lamp_W = Vector3d(1.0, -0.5, 3.0);
  const CameraModel model = CameraModel::firefly_mv_4mm();
  const Renderer renderer(model, 1);
  const Isometry3d X_WC1 = make_transform(rotation_from_rpy(0.02, 0.03, 0.1) * R_BC_downward(),
                                          Vector3d(0.3, -0.2, 1.4));
  const Isometry3d X_WC2 = make_transform(rotation_from_rpy(-0.05, 0.08, 0.3) * R_BC_downward(),
                                          Vector3d(0.55, -0.05, 1.2));
  auto radiance = [&](const Scene& scene, const Isometry3d& X_WC) {
    cv::Mat acc(model.height, model.width, CV_32F, cv::Scalar(0));
    renderer.accumulate(scene, X_WC, 1.f, acc);
    return acc;
  };
  // Each pixel is brightened or dimmed by the lamp's falloff at the floor point it sees: a
  // function of the world point alone, so it is the same from any view (no flicker).
  for (const Isometry3d& X_WC : {X_WC1, X_WC2}) {
    const cv::Mat a = radiance(even, X_WC), b = radiance(lit, X_WC);
    double lo = 10, hi = 0;
    for (int v = 10; v < 480; v += 37) {
      for (int u = 10; u < 640; u += 41) {
        const Vector3d d_W = X_WC.linear() * model.ray(Vector2d(u, v));
        const Vector3d p_W = X_WC.translation() - X_WC.translation().z() / d_W.z() * d_W;
        const double expected = lit.illumination(p_W);
        if (a.at<float>(v, u) < 10) continue;  // too dark a texel for a ratio
        EXPECT_NEAR(b.at<float>(v, u) / a.at<float>(v, u), expected, 1e-3) << u << ", " << v;
        lo = std::min(lo, expected);
        hi = std::max(hi, expected);
      }
    }
    EXPECT_GT(hi - lo, 0.01);  // the falloff is there across the view...
    EXPECT_LT(hi - lo, 0.1);   // ...and gentle, as in a hall
  }
  // Vision's features still match between the two views as well as under even light.
  auto inliers = [&](const Scene& scene) {
    cv::Mat i1, i2;
    radiance(scene, X_WC1).convertTo(i1, CV_8U);
    radiance(scene, X_WC2).convertTo(i2, CV_8U);
    auto orb = cv::ORB::create(1000);
    std::vector<cv::KeyPoint> k1, k2;
    cv::Mat d1, d2;
    orb->detectAndCompute(i1, cv::noArray(), k1, d1);
    orb->detectAndCompute(i2, cv::noArray(), k2, d2);
    std::vector<cv::DMatch> matches;
    cv::BFMatcher(cv::NORM_HAMMING, true).match(d1, d2, matches);
    std::vector<cv::Point2f> p1, p2;
    for (const auto& m : matches) {
      p1.push_back(k1[m.queryIdx].pt);
      p2.push_back(k2[m.trainIdx].pt);
    }
    cv::Mat mask;
    cv::findHomography(p1, p2, cv::RANSAC, 1.0, mask);
    return cv::countNonZero(mask);
  };
  const int n_even = inliers(even), n_lit = inliers(lit);
  EXPECT_GT(n_lit, 100);
  EXPECT_GT(n_lit, 0.85 * n_even) << n_lit << " inliers under the lamp, " << n_even
                                  << " under even light";
}

// Cast shadows (LightingParams::shadows, casters) under a low sun: a surface point whose way
// towards the light meets the platform or a caster keeps the ambient share of its shade, every
// other point is lit as without shadows. The truth is Scene::cast_ray from the point towards
// the light, in double precision, with the caster added to the scene as a box.
TEST(SimRendererTest, ALowSunCastsThePlatformsAndACastersShadowsOnFloorAndTop) {
  Scene off = build_scene(test::quiet(test::scenario("landing_a")), 5);
  ASSERT_TRUE(off.platform);
  off.lighting.ambient = 0.3;
  off.lighting.diffuse = 0.7;
  off.lighting.gain = 1.0;
  off.lighting.falloff = 0.0;
  const Vector3d sun = Vector3d(0.8, 0.3, 0.45).normalized();  // about 25 deg above the horizon
  off.lighting.light_dir_W = sun;
  const Vector3d top = off.platform->top_center_W;
  // A 20 cm mast 3 m towards the sun, tall enough for its shadow to cross the top.
  const Vector2d at = top.head<2>() + 3.0 * sun.head<2>().normalized();
  const double mast_h = 3.5 * sun.z() / sun.head<2>().norm() + 0.5;
  Scene on = off;
  on.lighting.shadows = true;
  Box mast;
  mast.half_size_m = Vector3d(0.1, 0.1, 0.5 * mast_h);
  mast.center_W = Vector3d(at.x(), at.y(), 0.5 * mast_h);
  on.shadow_casters.push_back(mast);
  Scene truth = off;
  truth.boxes.push_back(mast);

  const CameraModel model = CameraModel::firefly_mv_4mm();
  const Renderer renderer(model, 1);
  const Isometry3d X_WC = make_transform(rotation_from_rpy(0.0, 0.0, 0.2) * R_BC_downward(),
                                         Vector3d(top.x() - 0.2, top.y(), 1.6));
  auto radiance = [&](const Scene& scene) {
    cv::Mat acc(model.height, model.width, CV_32F, cv::Scalar(0));
    renderer.accumulate(scene, X_WC, 1.f, acc);
    return acc;
  };
  const cv::Mat a = radiance(off), b = radiance(on);
  const auto in_shadow = [&](const Vector3d& p_W) {
    return truth.cast_ray(p_W + 1e-3 * sun, sun, 100.0).has_value();
  };
  int floor_shadowed = 0, top_shadowed = 0, lit = 0;
  for (int v = 5; v < model.height; v += 7) {
    for (int u = 5; u < model.width; u += 7) {
      const Vector3d d_W = X_WC.linear() * model.ray(Vector2d(u, v));
      const auto hit = off.cast_ray(X_WC.translation(), d_W, 100.0);
      if (!hit || a.at<float>(v, u) < 10) continue;
      const Vector3d p_W = X_WC.translation() + hit->distance_m * d_W.normalized();
      // Away from a shadow's edge by 5 mm either way along the surface: the float ray is not
      // the double one.
      const Vector3d e1 = sun.cross(Vector3d::UnitZ()).normalized() * 5e-3;
      const Vector3d e2 = Vector3d(sun.x(), sun.y(), 0).normalized() * 5e-3;
      const bool shadowed = in_shadow(p_W);
      bool clear = true;
      for (const Vector3d& e : {Vector3d(e1), Vector3d(-e1), Vector3d(e2), Vector3d(-e2)})
        if (in_shadow(p_W + e) != shadowed) clear = false;
      if (!clear) continue;
      const bool on_top = hit->box == off.platform_box && hit->normal_W.z() > 0.9;
      if (hit->box >= 0 && !on_top) continue;  // the sides
      const double lit_share = 0.3 + 0.7 * std::max(0.0, hit->normal_W.dot(sun));
      const double expected = shadowed ? 0.3 / lit_share : 1.0;
      EXPECT_NEAR(b.at<float>(v, u) / a.at<float>(v, u), expected, 2e-3)
          << u << ", " << v << (on_top ? " top" : " floor") << (shadowed ? " shadowed" : " lit");
      if (shadowed)
        ++(on_top ? top_shadowed : floor_shadowed);
      else
        ++lit;
    }
  }
  // The view holds the platform's own shadow on the floor, the mast's across the top, and sun.
  EXPECT_GT(floor_shadowed, 20);
  EXPECT_GT(top_shadowed, 20);
  EXPECT_GT(lit, 500);
  // Without shadows the casters change nothing.
  Scene casters_only = off;
  casters_only.shadow_casters.push_back(mast);
  EXPECT_EQ(cv::norm(radiance(casters_only), a, cv::NORM_INF), 0.0);
}

TEST(SimRendererTest, AWetTopMirrorsTheSkyWhereTheReflectedRayMeetsIt) {
  const Scene matte = build_scene(test::quiet(test::scenario("landing_a")), 5);
  ASSERT_TRUE(matte.platform);
  Scene wet = matte;
  wet.boxes[wet.platform_box].reflectance = 0.3;
  // A ceiling 4 m above of 1 m squares: a mirrored ray lands well inside one on most pixels.
  const TextureSpec sky{"checker", 3, 256, 0.05, 150, 1.0, 1.0, {}, {}};
  wet.sky_texture = static_cast<int>(wet.textures.size());
  wet.textures.push_back(Texture::make(sky, 1));
  const Vector3d top = matte.platform->top_center_W;
  wet.sky_z_m = top.z() + 4.0;
  const Texture& sky_tex = wet.textures[wet.sky_texture];
  const Box& box = matte.boxes[matte.platform_box];

  const CameraModel model = CameraModel::firefly_mv_4mm();
  const Renderer renderer(model, 1);
  // Straight down from 0.8 m over the top, and from 1.5 m beside it, 0.6 m up, looking at it
  // (incidence about 68 deg, where Fresnel's reflectance has grown).
  const Vector3d beside(top.x() - 1.5, top.y(), top.z() + 0.6);
  const Vector3d z_C = (top - beside).normalized();
  const Vector3d x_C = z_C.cross(Vector3d::UnitZ()).normalized();
  Matrix3d R_oblique;
  R_oblique << x_C, z_C.cross(x_C), z_C;
  const std::vector<Isometry3d> views = {make_transform(R_BC_downward(), top + Vector3d(0, 0, 0.8)),
                                         make_transform(R_oblique, beside)};
  for (const Isometry3d& X_WC : views) {
    SCOPED_TRACE(X_WC.translation().transpose());
    auto radiance = [&](const Scene& scene) {
      cv::Mat acc(model.height, model.width, CV_32F, cv::Scalar(0));
      renderer.accumulate(scene, X_WC, 1.f, acc);
      return acc;
    };
    const cv::Mat a = radiance(matte), b = radiance(wet);
    int on_top = 0, elsewhere = 0;
    double max_F = 0;
    for (int v = 3; v < model.height; v += 5) {
      for (int u = 3; u < model.width; u += 5) {
        const Vector3d d = (X_WC.linear() * model.ray(Vector2d(u, v))).normalized();
        const auto hit = matte.cast_ray(X_WC.translation(), d, 100.0);
        if (!hit) continue;
        const Vector3d p_W = X_WC.translation() + hit->distance_m * d;
        // Clear of the top's outline by a centimetre: the float ray is not the double one.
        const Vector3d q = box.to_local(p_W);
        const double outside = (q.head<2>().cwiseAbs() - box.half_size_m.head<2>()).maxCoeff();
        if (hit->box != matte.platform_box || hit->normal_W.z() < 0.9) {
          if (outside < 0.01) continue;
          EXPECT_EQ(b.at<float>(v, u), a.at<float>(v, u)) << u << ", " << v;
          ++elsewhere;
          continue;
        }
        if (outside > -0.01) continue;
        const double cos_i = -d.z();
        const Vector3d r = d + 2 * cos_i * Vector3d::UnitZ();
        const Vector3d at = p_W + (wet.sky_z_m - p_W.z()) / r.z() * r;
        const auto sky_at = [&](double dx, double dy) {
          return sky_tex.sample(float(at.x() + dx), float(at.y() + dy), 1e-4f);
        };
        const float mirrored = sky_at(0, 0);
        bool inside = true;  // of one square of the ceiling
        for (const double e : {-0.1, 0.1})
          inside = inside && sky_at(e, 0) == mirrored && sky_at(0, e) == mirrored;
        if (!inside) continue;
        const double F = 0.3 + 0.7 * std::pow(1 - cos_i, 5);
        max_F = std::max(max_F, F);
        const double expected =
            a.at<float>(v, u) + F * (wet.lighting.gain * mirrored - a.at<float>(v, u));
        EXPECT_NEAR(b.at<float>(v, u), expected, 0.05) << u << ", " << v;
        ++on_top;
      }
    }
    EXPECT_GT(on_top, 100);
    EXPECT_GT(elsewhere, 1000);
    if (X_WC.translation() == beside) {
      EXPECT_GT(max_F, 0.35) << "Fresnel's rise towards grazing";
    }
  }
}

TEST(SimRendererTest, TexturesGiveHundredsOfFeaturesOnFloorPlatformAndWall) {
  const CameraModel model = CameraModel::firefly_mv_4mm();
  const Renderer renderer(model, 1);
  auto corners = [&](const cv::Mat& img, const cv::Mat& mask = cv::Mat()) {
    std::vector<cv::Point2f> pts;
    cv::goodFeaturesToTrack(img, pts, 2000, 0.01, 5, mask);
    return pts.size();
  };
  {
    const Scene scene = build_scene(test::quiet(test::scenario("landing_a")), 1);
    const Box& box = scene.boxes.at(0);
    const Isometry3d X_WC = make_transform(rotation_from_rpy(0, 0, 0.3) * R_BC_downward(),
                                           box.center_W + Vector3d(0.2, 0.1, 1.4));
    const cv::Mat img = renderer.render(scene, X_WC);
    EXPECT_GT(corners(img), 300u);
    // On the platform's top alone.
    cv::Mat mask = cv::Mat::zeros(img.size(), CV_8U);
    std::vector<cv::Point> poly;
    for (const auto& [sx, sy] : {std::pair{1, 1}, {-1, 1}, {-1, -1}, {1, -1}}) {
      const Vector3d p =
          box.center_W + box.R_WO() * Vector3d(0.9 * sx * box.half_size_m.x(),
                                               0.9 * sy * box.half_size_m.y(), box.half_size_m.z());
      const Vector2d px = project(model, X_WC, p);
      poly.emplace_back(int(px.x()), int(px.y()));
    }
    cv::fillConvexPoly(mask, poly, 255);
    EXPECT_GT(corners(img, mask), 30u);
  }
  {
    const Scene scene = build_scene(test::quiet(test::scenario("ingress_solid")), 1);
    const Isometry3d X_WC = make_transform(R_BC_forward(), Vector3d(1.5, 0.0, 1.2));
    EXPECT_GT(corners(renderer.render(scene, X_WC)), 300u);
  }
}

// The tiled floor of issue 15: flat tiles of the given side whose only corners are where the
// grout lines cross, and a texture that wraps without a seam (a whole number of tiles).
TEST(SimRendererTest, TilesTextureHasCornersOnlyWhereTheGroutCrosses) {
  TextureSpec spec;
  spec.kind = "tiles";
  spec.size_px = 512;
  spec.texel_m = 0.004;   // 2.048 m of floor
  spec.feature_m = 0.30;  // -> 7 tiles across, 73.14 px each
  spec.mean = 150;
  spec.contrast = 1.0;
  const cv::Mat img = make_procedural_texture(spec, 7);
  ASSERT_EQ(img.type(), CV_8UC1);
  ASSERT_EQ(img.rows, 512);
  const int tiles = 7;
  const double cell = 512.0 / tiles;
  cv::Mat wrapped;
  cv::copyMakeBorder(img, wrapped, 16, 16, 16, 16, cv::BORDER_WRAP);
  std::vector<cv::Point2f> pts;
  cv::goodFeaturesToTrack(wrapped, pts, 1000, 0.05, 5);
  ASSERT_GE(pts.size(), static_cast<size_t>(tiles * tiles));
  for (const cv::Point2f& p : pts) {
    const double x = p.x - 16, y = p.y - 16;
    const double dx = std::abs(x / cell - std::round(x / cell)) * cell;
    const double dy = std::abs(y / cell - std::round(y / cell)) * cell;
    EXPECT_LT(std::max(dx, dy), 6.0) << "a corner inside a tile at " << x << ", " << y;
  }
  // Seamless wrap: the grout columns are evenly spaced across the wrap too (whole tiles).
  cv::Mat column_mean;
  cv::reduce(img, column_mean, 0, cv::REDUCE_AVG, CV_32F);
  std::vector<int> starts;
  for (int x = 0; x < 512; ++x) {
    const bool dark = column_mean.at<float>(0, x) < 150 - 20;
    const bool was_dark = column_mean.at<float>(0, (x + 511) % 512) < 150 - 20;
    if (dark && !was_dark) starts.push_back(x);
  }
  ASSERT_EQ(starts.size(), static_cast<size_t>(tiles));
  for (size_t i = 0; i < starts.size(); ++i) {
    const int next = i + 1 < starts.size() ? starts[i + 1] : starts[0] + 512;
    EXPECT_NEAR(next - starts[i], cell, 1.5) << "grout " << i;
  }
  // Different seeds give different tones, the same seed the same texture.
  EXPECT_EQ(cv::norm(img, make_procedural_texture(spec, 7), cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(img, make_procedural_texture(spec, 8), cv::NORM_INF), 0.0);
}

TEST(SimRendererTest, DistantFloorIsFilteredLikeASupersampledReference) {
  // Far, oblique floor: many texels per pixel. Mip-mapping must give what 16 rays per pixel
  // average to, not the aliased value of one texel.
  const Scene scene = build_scene(test::quiet(test::scenario("landing_none")), 2);
  const CameraModel model = CameraModel::firefly_mv_4mm();
  const Renderer fast(model, 1), reference(model, 4);
  const Isometry3d X_WC =
      make_transform(rotation_from_rpy(0, 0.6, 0) * R_BC_forward(), Vector3d(0, 0, 2.5));
  cv::Mat a, b;
  fast.render(scene, X_WC).convertTo(a, CV_32F);
  reference.render(scene, X_WC).convertTo(b, CV_32F);
  const cv::Rect far_rows(0, 260, 640, 120);  // floor 3-6 m away
  cv::Mat diff = a(far_rows) - b(far_rows);
  cv::Scalar mu, sd, ref_mu, ref_sd;
  cv::meanStdDev(diff, mu, sd);
  cv::meanStdDev(b(far_rows), ref_mu, ref_sd);
  EXPECT_LT(sd[0], 0.35 * ref_sd[0]) << "difference " << sd[0] << " of contrast " << ref_sd[0];
  // And moving by a fraction of a texel changes the image only a little (no shimmer).
  const Isometry3d X_WC_moved =
      make_transform(X_WC.linear(), X_WC.translation() + Vector3d(0.0011, 0.0007, 0));
  cv::Mat c;
  fast.render(scene, X_WC_moved).convertTo(c, CV_32F);
  cv::meanStdDev(c(far_rows) - a(far_rows), mu, sd);
  EXPECT_LT(sd[0], 0.2 * ref_sd[0]);
}

TEST(SimRendererTest, CameraFramesArriveAtTheirRateStampedAtMidExposureWithNoise) {
  Scenario sc = test::quiet(test::scenario("landing_none"));
  sc.camera.enabled = true;
  sc.camera.rate_hz = 30;
  sc.camera.exposure_s = 0.006;
  sc.camera.noise_sigma = 3.0;
  const CameraRig rig = load_camera_rig(test::config_path("vehicles/starmac.yaml"), "downward");
  Simulator sim(sc, test::starmac(), 4, rig);
  test::place(sim, Vector3d(0, 0, 1.0));
  std::vector<CameraFrame> frames;
  for (int i = 0; i < 100; ++i) {  // 1 s, polled every 10 ms
    sim.step(test::hover(test::starmac()), sim.now_utime() + 10000);
    if (auto f = sim.take_camera()) frames.push_back(*f);
  }
  ASSERT_GE(frames.size(), 29u);
  for (size_t i = 1; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].seq, frames[i - 1].seq + 1);
    EXPECT_NEAR(frames[i].utime - frames[i - 1].utime, 33333, 1);
  }
  EXPECT_EQ((frames[0].utime - sc.start_utime) % 33333, 0);  // t_k = start + k / rate
  EXPECT_EQ(frames[0].pixels.type(), CV_8UC1);
  EXPECT_EQ(frames[0].pixels.size(), cv::Size(640, 480));
  // The vehicle hovers still: two frames differ by noise alone (sqrt(2) sigma).
  cv::Mat d;
  cv::subtract(frames[10].pixels, frames[11].pixels, d, cv::noArray(), CV_32F);
  cv::Scalar mu, sd;
  cv::meanStdDev(d, mu, sd);
  EXPECT_NEAR(sd[0], std::sqrt(2.0) * 3.0, 0.4);
  // Frames rendered agree with render() from the mid-exposure pose.
  const cv::Mat clean = sim.render(
      rig.mount, rig.model, make_transform(sim.state().q_WB.toRotationMatrix(), sim.state().p_W_B));
  cv::subtract(frames.back().pixels, clean, d, cv::noArray(), CV_32F);
  cv::meanStdDev(d, mu, sd);
  EXPECT_NEAR(sd[0], 3.0, 0.4);
}

// The camera's automatic gain (issue 15, landing_lowtex: a bright scene drawn with the light's
// gain 1.3 clipped a paper top white, 255 from rim to rim, and no feature was left on it).
cv::Mat ramp_image(double top_grey) {  // grey levels rising from 0 to top_grey, row by row
  cv::Mat m(120, 160, CV_32F);
  for (int v = 0; v < m.rows; ++v) m.row(v).setTo(top_grey * v / (m.rows - 1));
  return m;
}

// Meters `scene` (grey levels at unit gain) as the camera saw it with the gain it had.
double meter(AutoGain& ag, const cv::Mat& scene) {
  ag.update(ag.gain() * scene, ag.gain());
  return ag.gain();
}

double q99_of(const cv::Mat& m) {
  std::vector<float> v(m.begin<float>(), m.end<float>());
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(0.99 * v.size())];
}

TEST(AutoGainTest, AViewBelowTheTargetKeepsTheGainAtOne) {
  AutoGain ag;
  for (int frame = 0; frame < 30; ++frame) EXPECT_EQ(meter(ag, ramp_image(240)), 1.0);
  // Flicker scales the frame, not the scene: metered at unit gain it stays below the target.
  ag.update(1.1 * ramp_image(240), 1.1);
  EXPECT_EQ(ag.gain(), 1.0);
}

TEST(AutoGainTest, ABrightViewIsDimmedOverAFewFramesUntilItsHighlightsFit) {
  const CameraParams p;
  const cv::Mat scene = ramp_image(400);  // at unit gain: its 99th percentile near 396
  AutoGain ag(p);
  double last = 1.0;
  std::vector<double> gains;
  for (int frame = 0; frame < 60; ++frame) {
    gains.push_back(meter(ag, scene));
    EXPECT_LE(gains.back(), last) << frame;  // from above, never overshooting
    last = gains.back();
  }
  // Not at once: a camera's exposure control settles over frames (10 at 30 fps: a third of a
  // second).
  EXPECT_LT(gains[4], 1.0);
  EXPECT_GT(gains[4], gains.back() + 0.1);
  // Within the tolerance, and 2 % more: the quantile is metered on every fourth pixel of every
  // fourth row.
  EXPECT_NEAR(ag.gain() * q99_of(scene), p.auto_gain_target,
              (p.auto_gain_tolerance + 0.02) * p.auto_gain_target);
}

TEST(AutoGainTest, TheGainClimbsBackWhenTheViewDarkensAndHoldsOnAStillView) {
  const CameraParams p;
  AutoGain ag(p);
  for (int frame = 0; frame < 40; ++frame) meter(ag, ramp_image(400));
  for (int frame = 0; frame < 60; ++frame) meter(ag, ramp_image(150));
  EXPECT_GE(ag.gain(), 1.0 / (1.0 + p.auto_gain_tolerance) - 1e-9);
  // A small bright patch at the quantile flips the metering frame to frame (issue 15,
  // landing_photo seed 10212: hovering over a bright top the gain hunted between 0.80 and 0.88
  // from frame to frame): averaged and with hysteresis the gain settles and holds.
  cv::Mat a = ramp_image(200), b = ramp_image(200);
  a.rowRange(a.rows - 8, a.rows).setTo(400);  // 2 of the 30 rows metered: q99 on the patch
  AutoGain hunt(p);
  std::vector<double> gains;
  for (int frame = 0; frame < 60; ++frame) gains.push_back(meter(hunt, frame % 2 ? a : b));
  const auto [lo, hi] = std::minmax_element(gains.begin() + 30, gains.end());
  EXPECT_LT(*lo, 1.0);
  EXPECT_EQ(*lo, *hi);
}

TEST(AutoGainTest, NeverBelowItsMinimumAndOffLeavesTheGainAlone) {
  CameraParams p;
  p.auto_gain_min = 0.5;
  AutoGain ag(p);
  for (int frame = 0; frame < 40; ++frame) meter(ag, 4 * ramp_image(400));
  EXPECT_DOUBLE_EQ(ag.gain(), 0.5);
  p.auto_gain = false;
  AutoGain off(p);
  EXPECT_EQ(meter(off, 4 * ramp_image(400)), 1.0);
}

TEST(SimRendererTest, ABrightSceneIsDimmedSoItsTopIsNotClippedWhite) {
  Scenario sc = test::quiet(test::scenario("landing_c"));
  sc.camera.enabled = true;
  sc.lighting.gain = 1.6;  // the paper top and much of the floor past full scale at unit gain
  const CameraRig rig = load_camera_rig(test::config_path("vehicles/starmac.yaml"), "downward");
  auto last_frame = [&](bool auto_gain) {
    Scenario s = sc;
    s.camera.auto_gain = auto_gain;
    Simulator sim(s, test::starmac(), 3, rig);
    test::place(sim, Vector3d(sc.platform->center_xy_m.x(), sc.platform->center_xy_m.y(), 1.3));
    std::optional<CameraFrame> last;
    for (int i = 0; i < 100; ++i) {  // 1 s, polled every 10 ms
      sim.step(test::hover(test::starmac()), sim.now_utime() + 10000);
      if (auto f = sim.take_camera()) last = std::move(f);
    }
    return last.value();  // throws (the test fails) when no frame came
  };
  auto clipped_share = [](const cv::Mat& m) {
    return static_cast<double>(cv::countNonZero(m >= 255)) / m.total();
  };
  const CameraFrame fixed = last_frame(false), dimmed = last_frame(true);
  EXPECT_EQ(fixed.gain, 1.0);
  EXPECT_GT(clipped_share(fixed.pixels), 0.1);
  EXPECT_LT(dimmed.gain, 0.9);
  EXPECT_LT(clipped_share(dimmed.pixels), 0.02);
  // The exposure time, and so the blur, is the scene's.
  EXPECT_EQ(dimmed.exposure_s, fixed.exposure_s);
}

TEST(SimRendererTest, SameSeedGivesIdenticalFramesOnAnyNumberOfThreads) {
  Scenario sc = test::scenario("landing_c");
  sc.camera.gain_jitter = 0.05;
  const CameraRig rig = load_camera_rig(test::config_path("vehicles/starmac.yaml"), "downward");
  auto frames = [&](uint64_t seed, int threads) {
    Simulator sim(sc, test::starmac(), seed, rig);
    sim.set_render_threads(threads);
    test::place(sim, Vector3d(0.9, 0.4, 1.2));
    std::vector<cv::Mat> out;
    while (out.size() < 3) {
      AttitudeCommand cmd = test::hover(test::starmac());
      cmd.roll_rad = 0.05;
      sim.step(cmd, sim.now_utime() + 5000);
      if (auto f = sim.take_camera()) out.push_back(f->pixels);
    }
    return out;
  };
  const auto a = frames(11, 1), b = frames(11, 2), c = frames(12, 1);
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(cv::norm(a[i], b[i], cv::NORM_INF), 0.0) << i;
    EXPECT_GT(cv::norm(a[i], c[i], cv::NORM_L1), 0.0) << i;  // another seed: another scene
  }
}

// Ingress without motion capture (issue 17): the forward camera for the vision and the downward
// one for the estimator's flow, each at its own rate; the flow camera's frames are the downward
// view, and rendering them leaves the forward camera's frames bit for bit as they were.
TEST(SimRendererTest, TheFlowCameraRendersTheFloorBesidesTheForwardCameraChangingNothingElse) {
  Scenario sc = test::scenario("ingress_wide");
  sc.flow_camera.enabled = true;
  sc.flow_camera.rate_hz = 20;
  const std::string vehicle = test::config_path("vehicles/starmac.yaml");
  const CameraRig forward = load_camera_rig(vehicle, "forward");
  const CameraRig downward = load_camera_rig(vehicle, "downward");
  struct Frames {
    std::vector<CameraFrame> camera, flow;
  };
  auto fly = [&](bool with_flow) {
    Simulator sim(sc, test::starmac(), 5, forward,
                  with_flow ? std::optional<CameraRig>(downward) : std::nullopt);
    test::place(sim, Vector3d(1.0, 0.1, 1.2));
    Frames out;
    for (int i = 0; i < 100; ++i) {  // 0.5 s, polled every 5 ms
      sim.step(test::hover(test::starmac()), sim.now_utime() + 5000);
      if (auto f = sim.take_camera()) out.camera.push_back(*f);
      if (auto f = sim.take_flow_camera()) out.flow.push_back(*f);
    }
    if (with_flow) {
      // The flow camera's last frame is the downward view from its mid-exposure pose.
      const Isometry3d X_WB = out.flow.back().X_WC * downward.mount.X_BC().inverse();
      const cv::Mat clean = sim.render(downward.mount, downward.model, X_WB);
      cv::Mat d;
      cv::subtract(out.flow.back().pixels, clean, d, cv::noArray(), CV_32F);
      cv::Scalar mu, sd;
      cv::meanStdDev(d, mu, sd);
      EXPECT_NEAR(sd[0], sc.flow_camera.noise_sigma, 0.4);
    }
    return out;
  };
  const Frames with = fly(true), without = fly(false);
  EXPECT_TRUE(without.flow.empty());
  ASSERT_GE(with.flow.size(), 9u);  // 20 Hz
  for (size_t i = 1; i < with.flow.size(); ++i)
    EXPECT_NEAR(with.flow[i].utime - with.flow[i - 1].utime, 50000, 1);
  EXPECT_EQ(with.flow[0].pixels.size(), cv::Size(downward.model.width, downward.model.height));
  // Downward: the optical axis points at the floor; forward: at the wall.
  EXPECT_LT(with.flow[0].X_WC.rotation().col(2).z(), -0.9);
  EXPECT_GT(with.camera[0].X_WC.rotation().col(2).x(), 0.9);
  ASSERT_GE(with.camera.size(), 14u);  // 30 Hz
  ASSERT_EQ(with.camera.size(), without.camera.size());
  for (size_t i = 0; i < with.camera.size(); ++i) {
    EXPECT_EQ(with.camera[i].utime, without.camera[i].utime);
    EXPECT_EQ(cv::norm(with.camera[i].pixels, without.camera[i].pixels, cv::NORM_INF), 0.0) << i;
  }
}

TEST(SimRendererTest, MotionBlurSmearsAFastMovingView) {
  Scenario sc = test::quiet(test::scenario("landing_none"));
  sc.camera.enabled = true;
  sc.camera.noise_sigma = 0.0;
  sc.camera.exposure_s = 0.02;
  const CameraRig rig = load_camera_rig(test::config_path("vehicles/starmac.yaml"), "downward");
  auto sharpness = [&](int samples) {
    sc.camera.motion_blur_samples = samples;
    Simulator sim(sc, test::starmac(), 4, rig);
    test::place(sim, Vector3d(0, 0, 1.0));
    VehicleState s = sim.state();
    s.v_W_B = Vector3d(2.0, 0, 0);  // 2 m/s at 1 m: ~27 px during the exposure
    sim.set_state(s);
    std::optional<CameraFrame> f;
    while (!f) {
      sim.step(test::hover(test::starmac()), sim.now_utime() + 1000);
      f = sim.take_camera();
    }
    cv::Mat gx;
    cv::Sobel(f->pixels, gx, CV_32F, 0, 1);  // image v runs along body x (downward camera)
    return cv::norm(gx);
  };
  EXPECT_LT(sharpness(8), 0.7 * sharpness(1));
}

}  // namespace
}  // namespace alight::sim
