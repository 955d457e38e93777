// Flow odometry (issue 17): t/d of the downward camera over the floor.
//   - the fit on synthetic correspondences (points on the floor projected with known R, t, d):
//     exact without noise, within its covariance with noise and 30 % outliers, consistent
//     covariance over many seeded motions, sensitivities to R and n, refusals;
//   - the front end on frames rendered by the simulator's renderer (sim/renderer.hpp): a textured
//     floor under a downward camera at 1-3 m, moving and rotating, for several textures, with a
//     platform partly in view, over many seeded random motions; determinism;
//   - the parameters (estimator.flow.* keys).
#include "estimator/flow_odometry.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "common/params.hpp"
#include "sim/renderer.hpp"
#include "sim/scene.hpp"
#include "sim/texture.hpp"
#include "test/common/expect_param_error.hpp"
#include "test/vision/test_images.hpp"

namespace alight::estimator {
namespace {

constexpr double kDeg = M_PI / 180.0;

// --- Synthetic correspondences -----------------------------------------------------------------

/// Two camera poses over the floor z = 0 (world z up).
struct Motion {
  Matrix3d R_WC1 = Matrix3d::Identity(), R_WC2 = Matrix3d::Identity();
  Vector3d p_W_C1 = Vector3d::Zero(), p_W_C2 = Vector3d::Zero();

  Matrix3d R_C2C1() const { return R_WC2.transpose() * R_WC1; }
  /// Up, in camera 1: from the floor towards the camera.
  Vector3d n_C1() const { return R_WC1.transpose() * Vector3d::UnitZ(); }
  Vector3d t_over_d() const { return R_WC1.transpose() * (p_W_C2 - p_W_C1) / p_W_C1.z(); }
};

/// A downward camera (body level = optical axis down) at `height_m`, body attitude rpy, moving by
/// v dt and turning by omega_B dt (body rates).
Motion make_motion(double height_m, const Vector3d& rpy, const Vector3d& v_W_mps,
                   const Vector3d& omega_B_rps, double dt_s) {
  Motion m;
  const Matrix3d R_WB1 = rotation_from_rpy(rpy.x(), rpy.y(), rpy.z());
  const Vector3d w = omega_B_rps * dt_s;
  const Matrix3d R_WB2 =
      R_WB1 * (w.norm() > 0 ? Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix()
                            : Matrix3d::Identity());
  m.R_WC1 = R_WB1 * R_BC_downward();
  m.R_WC2 = R_WB2 * R_BC_downward();
  m.p_W_C1 = Vector3d(0.3, -0.2, height_m);
  m.p_W_C2 = m.p_W_C1 + v_W_mps * dt_s;
  return m;
}

/// A random motion of a flying vehicle between two frames 1/30 s apart: height 1-3 m, tilt up to
/// 15 deg, any heading, speed up to 1.5 m/s (vertical up to 0.5), body rates up to 60 deg/s.
Motion random_motion(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1), h(1.0, 3.0);
  const Vector3d rpy(15 * kDeg * u(rng), 15 * kDeg * u(rng), M_PI * u(rng));
  const Vector3d v(1.5 * u(rng), 1.5 * u(rng), 0.5 * u(rng));
  Vector3d v_lim = v;
  if (v_lim.head<2>().norm() > 1.5) v_lim.head<2>() *= 1.5 / v_lim.head<2>().norm();
  const Vector3d omega(60 * kDeg * u(rng), 60 * kDeg * u(rng), 60 * kDeg * u(rng));
  return make_motion(h(rng), rpy, v_lim, omega, 1.0 / 30);
}

struct Corrs {
  std::vector<Vector3d> r1, r2;
};

/// `n` floor points seen in both images (random pixels of image 1), with Gaussian pixel noise.
/// `plane_z_m` lifts the plane (for off-floor outliers).
Corrs floor_points(const Motion& m, const CameraModel& cam, int n, std::mt19937_64& rng,
                   double noise_px, double plane_z_m = 0.0) {
  Corrs c;
  std::uniform_real_distribution<double> ux(10, cam.width - 11), uy(10, cam.height - 11);
  std::normal_distribution<double> g(0.0, noise_px > 0 ? noise_px : 1.0);
  auto noise = [&] { return noise_px > 0 ? Vector2d(g(rng), g(rng)) : Vector2d::Zero(); };
  for (int tries = 0; static_cast<int>(c.r1.size()) < n && tries < 100 * n; ++tries) {
    const Vector2d px1(ux(rng), uy(rng));
    const Vector3d d_W = m.R_WC1 * cam.ray(px1);
    if (d_W.z() > -1e-3) continue;
    const double s = (plane_z_m - m.p_W_C1.z()) / d_W.z();
    const Vector3d p_W = m.p_W_C1 + s * d_W;
    const auto px2 = cam.project(m.R_WC2.transpose() * (p_W - m.p_W_C2));
    if (!px2 || !cam.in_image(*px2, 10)) continue;
    c.r1.push_back(cam.ray(px1 + noise()));
    c.r2.push_back(cam.ray(*px2 + noise()));
  }
  return c;
}

/// Replaces a fraction of the correspondences: half by random pixels in image 2, half by points of
/// a plane 0.5 m above the floor (a consistent wrong motion, like a box top).
void add_outliers(Corrs& c, const Motion& m, const CameraModel& cam, double fraction,
                  std::mt19937_64& rng, std::vector<uint8_t>* is_outlier) {
  const int n = static_cast<int>(c.r1.size());
  const int k = static_cast<int>(std::round(fraction * n));
  std::vector<int> idx(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) idx[static_cast<size_t>(i)] = i;
  std::shuffle(idx.begin(), idx.end(), rng);
  const Corrs high = floor_points(m, cam, k, rng, 0.0, 0.5 * m.p_W_C1.z());
  std::uniform_real_distribution<double> ux(0, cam.width - 1), uy(0, cam.height - 1);
  if (is_outlier) is_outlier->assign(static_cast<size_t>(n), 0);
  for (int j = 0; j < k; ++j) {
    const auto i = static_cast<size_t>(idx[static_cast<size_t>(j)]);
    if (j % 2 == 0 || static_cast<size_t>(j) >= high.r1.size()) {
      c.r2[i] = cam.ray(Vector2d(ux(rng), uy(rng)));
    } else {
      c.r1[i] = high.r1[static_cast<size_t>(j)];
      c.r2[i] = high.r2[static_cast<size_t>(j)];
    }
    if (is_outlier) (*is_outlier)[i] = 1;
  }
}

double nees(const FlowFit& f, const Vector3d& truth) {
  const Vector3d e = f.t_over_d_C1 - truth;
  return e.dot(f.cov.ldlt().solve(e));
}

const CameraModel kCam = CameraModel::firefly_mv_4mm();

TEST(FlowFitTest, NoiseFreeFloorGivesTheExactTOverD) {
  std::mt19937_64 rng(1);
  const FlowFitParams params;
  struct Case {
    double h, roll, pitch, yaw;
    Vector3d v, omega;
  };
  const Case cases[] = {
      {1.0, 0, 0, 0, Vector3d(1, 0, 0), Vector3d::Zero()},                    // straight ahead
      {1.5, 5, -8, 30, Vector3d(0.4, -0.9, 0.2), Vector3d(0.3, -0.5, 1.0)},   // turning, climbing
      {3.0, -12, 10, -120, Vector3d(-1.2, 0.3, -0.5), Vector3d(-1, 0.2, 0)},  // descending, rolling
      {2.0, 0, 0, 45, Vector3d::Zero(), Vector3d(0, 0, 1.5)},                 // hover, yawing
  };
  for (const Case& c : cases) {
    const Motion m = make_motion(c.h, Vector3d(c.roll, c.pitch, c.yaw) * kDeg, c.v, c.omega, 0.05);
    const Corrs k = floor_points(m, kCam, 150, rng, 0.0);
    ASSERT_EQ(k.r1.size(), 150u);
    const FlowFit f = fit_t_over_d(k.r1, k.r2, m.R_C2C1(), m.n_C1(), kCam.fx, params);
    ASSERT_EQ(f.reason, FlowReason::kOk) << to_string(f.reason);
    EXPECT_EQ(f.inliers, 150);
    EXPECT_LT((f.t_over_d_C1 - m.t_over_d()).norm(), 1e-9)
        << f.t_over_d_C1.transpose() << " vs " << m.t_over_d().transpose();
    EXPECT_LT(f.residual_rms_px, 1e-6);
  }
}

TEST(FlowFitTest, NoiseAndThirtyPercentOutliersStayWithinTheCovariance) {
  std::mt19937_64 rng(2);
  const FlowFitParams params;
  for (int trial = 0; trial < 20; ++trial) {
    const Motion m = random_motion(rng);
    Corrs k = floor_points(m, kCam, 200, rng, 0.3);
    std::vector<uint8_t> outlier;
    add_outliers(k, m, kCam, 0.3, rng, &outlier);
    const FlowFit f = fit_t_over_d(k.r1, k.r2, m.R_C2C1(), m.n_C1(), kCam.fx, params);
    ASSERT_EQ(f.reason, FlowReason::kOk) << trial << ": " << to_string(f.reason);
    const Vector3d err = f.t_over_d_C1 - m.t_over_d();
    // 0.3 px at f = 667 px over ~140 points: a few 1e-4 at most.
    EXPECT_LT(err.norm(), 1e-3) << trial;
    EXPECT_LT(nees(f, m.t_over_d()), 20.0) << trial;  // chi2(3) 0.9997
    int caught = 0, wrong = 0;
    for (size_t i = 0; i < outlier.size(); ++i) {
      if (outlier[i] && !f.inlier[i]) ++caught;
      if (!outlier[i] && !f.inlier[i]) ++wrong;
    }
    // Random pixels are always caught; points of the raised plane close to the camera's
    // translation direction move almost like floor points and may pass. The 1 px threshold is
    // 2.4 sigma of the two images' noise together: about 6 % of the floor points fall outside.
    EXPECT_GE(caught, 45) << trial;
    EXPECT_LE(wrong, 20) << trial;
  }
}

TEST(FlowFitTest, CovarianceIsConsistentOverManySeededMotions) {
  // Property: the normalised estimation error squared of a correct covariance is chi2(3): mean 3.
  // Noise up to 0.4 px in each image (0.57 px together, against the 1 px inlier threshold) and
  // 20 % outliers: measured mean 3.27, 3 of 300 above the 99 % bound. Without the truncation
  // correction 3.8 and 9, with sigma^2 (J^T W J)^-1 instead of Huber's sandwich 4.9 and 29.
  std::mt19937_64 rng(3);
  const FlowFitParams params;
  double sum = 0;
  int n = 0, above_99 = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Motion m = random_motion(rng);
    const double noise = std::uniform_real_distribution<double>(0.05, 0.4)(rng);
    Corrs k = floor_points(m, kCam, 120, rng, noise);
    add_outliers(k, m, kCam, 0.2, rng, nullptr);
    const FlowFit f = fit_t_over_d(k.r1, k.r2, m.R_C2C1(), m.n_C1(), kCam.fx, params);
    ASSERT_EQ(f.reason, FlowReason::kOk) << trial;
    const double q = nees(f, m.t_over_d());
    sum += q;
    ++n;
    if (q > 11.34) ++above_99;  // chi2(3) 0.99
  }
  const double mean = sum / n;
  std::printf("NEES over %d motions: mean %.2f, %d above the 99 %% bound\n", n, mean, above_99);
  EXPECT_GT(mean, 2.0);
  EXPECT_LT(mean, 4.0);
  EXPECT_LE(above_99, 9);
}

TEST(FlowFitTest, SensitivitiesMatchRefitsWithPerturbedRotationAndNormal) {
  std::mt19937_64 rng(4);
  const FlowFitParams params;
  for (int trial = 0; trial < 5; ++trial) {
    const Motion m = random_motion(rng);
    const Corrs k = floor_points(m, kCam, 150, rng, 0.0);
    const FlowFit f = fit_t_over_d(k.r1, k.r2, m.R_C2C1(), m.n_C1(), kCam.fx, params);
    ASSERT_EQ(f.reason, FlowReason::kOk);
    const double h = 1e-6;
    for (int j = 0; j < 3; ++j) {
      const Matrix3d R = m.R_C2C1() * Eigen::AngleAxisd(h, Vector3d::Unit(j)).toRotationMatrix();
      const FlowFit g = fit_t_over_d(k.r1, k.r2, R, m.n_C1(), kCam.fx, params);
      ASSERT_EQ(g.reason, FlowReason::kOk);
      const Vector3d fd = (g.t_over_d_C1 - f.t_over_d_C1) / h;
      EXPECT_LT((fd - f.J_rotation.col(j)).norm(), 1e-3 * (1 + fd.norm())) << trial << " " << j;

      const Vector3d n = (m.n_C1() + h * Vector3d::Unit(j)).normalized();
      const FlowFit gn = fit_t_over_d(k.r1, k.r2, m.R_C2C1(), n, kCam.fx, params);
      ASSERT_EQ(gn.reason, FlowReason::kOk);
      const Vector3d fdn = (gn.t_over_d_C1 - f.t_over_d_C1) / h;
      EXPECT_LT((fdn - f.J_normal.col(j)).norm(), 1e-3 * (1 + fdn.norm())) << trial << " " << j;
    }
    // A rotation error about the axes across the optical axis moves the image like a
    // translation: about d t/d = 1 per radian (the bas-relief ambiguity).
    EXPECT_GT((f.J_rotation.topLeftCorner<2, 2>().norm()), 0.5);
  }
}

TEST(FlowFitTest, SameInputsGiveIdenticalOutputs) {
  std::mt19937_64 rng(5);
  const Motion m = random_motion(rng);
  Corrs k = floor_points(m, kCam, 150, rng, 0.5);
  add_outliers(k, m, kCam, 0.3, rng, nullptr);
  const FlowFit a = fit_t_over_d(k.r1, k.r2, m.R_C2C1(), m.n_C1(), kCam.fx, FlowFitParams{});
  const FlowFit b = fit_t_over_d(k.r1, k.r2, m.R_C2C1(), m.n_C1(), kCam.fx, FlowFitParams{});
  ASSERT_EQ(a.reason, FlowReason::kOk);
  EXPECT_EQ(a.t_over_d_C1, b.t_over_d_C1);
  EXPECT_EQ(a.cov, b.cov);
  EXPECT_EQ(a.inlier, b.inlier);
}

TEST(FlowFitTest, RefusesDegenerateAndNonFiniteInputs) {
  std::mt19937_64 rng(6);
  const FlowFitParams params;
  const Motion m = make_motion(1.5, Vector3d::Zero(), Vector3d(0.5, 0, 0), Vector3d::Zero(), 0.05);
  const Corrs k = floor_points(m, kCam, 100, rng, 0.2);
  const Matrix3d R = m.R_C2C1();
  const Vector3d n = m.n_C1();
  auto fit = [&](const Corrs& c, const Matrix3d& R_, const Vector3d& n_) {
    return fit_t_over_d(c.r1, c.r2, R_, n_, kCam.fx, params).reason;
  };
  ASSERT_EQ(fit(k, R, n), FlowReason::kOk);

  const double nan = std::numeric_limits<double>::quiet_NaN();
  Matrix3d R_nan = R;
  R_nan(1, 2) = nan;
  EXPECT_EQ(fit(k, R_nan, n), FlowReason::kBadRotation);
  EXPECT_EQ(fit(k, 1.01 * R, n), FlowReason::kBadRotation);
  EXPECT_EQ(fit(k, -R, n), FlowReason::kBadRotation);  // det -1
  EXPECT_EQ(fit(k, R, Vector3d(nan, 0, 1)), FlowReason::kBadNormal);
  EXPECT_EQ(fit(k, R, 2.0 * n), FlowReason::kBadNormal);
  EXPECT_EQ(fit(k, R, Vector3d::Zero()), FlowReason::kBadNormal);
  // The camera looking up at the floor's normal: no ray meets the plane.
  EXPECT_EQ(fit(k, R, -n), FlowReason::kPlaneNotInView);

  // Too few correspondences; non-finite rays are dropped, not fatal.
  Corrs few = k;
  few.r1.resize(5);
  few.r2.resize(5);
  EXPECT_EQ(fit(few, R, n), FlowReason::kTooFewTracks);
  EXPECT_EQ(fit(Corrs{}, R, n), FlowReason::kTooFewTracks);
  Corrs holes = k;
  for (size_t i = 0; i < holes.r1.size(); i += 3) holes.r1[i].x() = nan;
  for (size_t i = 1; i < holes.r2.size(); i += 3) holes.r2[i].y() = -INFINITY;
  EXPECT_EQ(fit(holes, R, n), FlowReason::kOk);
  Corrs mismatched = k;
  mismatched.r2.resize(50);  // only the common length is used
  EXPECT_EQ(fit(mismatched, R, n), FlowReason::kOk);

  // Everything at one spot of the image: the vertical part is not fixed.
  Corrs cluster;
  for (int i = 0; i < 50; ++i) {
    const Vector2d px(320 + 0.05 * i, 240 - 0.03 * i);
    cluster.r1.push_back(kCam.ray(px));
    cluster.r2.push_back(kCam.ray(px + Vector2d(10, 0)));
  }
  EXPECT_EQ(fit(cluster, R, n), FlowReason::kDegenerate);

  // Unrelated points: no floor.
  Corrs noise = k;
  std::uniform_real_distribution<double> ux(0, 639), uy(0, 479);
  for (auto& r : noise.r2) r = kCam.ray(Vector2d(ux(rng), uy(rng)));
  EXPECT_EQ(fit(noise, R, n), FlowReason::kTooFewInliers);
}

// --- Parameters --------------------------------------------------------------------------------

FlowParams read_flow(const std::string& yaml) {
  const ParamNode root = ParamNode::from_string(yaml, "v.yaml");
  FlowParams p;
  FlowParams::schema().read(root.child("estimator").child("flow"), p);
  return p;
}

TEST(FlowParamsTest, DefaultsAreValidAndKeysAreRead) {
  EXPECT_NO_THROW(FlowParams{}.validate());
  const FlowParams p = read_flow(
      "estimator: {flow: {max_gap_s: 0.1, track: {max_features: 300, downsample: 1}, "
      "fit: {inlier_threshold_px: 1.5, seed: 3}}}");
  EXPECT_EQ(p.max_gap_s, 0.1);
  EXPECT_EQ(p.track.max_features, 300);
  EXPECT_EQ(p.fit.inlier_threshold_px, 1.5);
  EXPECT_EQ(p.fit.seed, 3u);
}

TEST(FlowParamsTest, ErrorsNameTheFullKey) {
  auto error = [](const std::string& yaml) {
    return test::expect_param_error([&] { read_flow(yaml); });
  };
  EXPECT_EQ(error("estimator: {flow: {fit: {min_inliers: 1}}}").key(),
            "estimator.flow.fit.min_inliers");
  EXPECT_EQ(error("estimator: {flow: {track: {max_features: 50, min_tracks: 60}}}").key(),
            "estimator.flow.track.min_tracks");
  EXPECT_EQ(error("estimator: {flow: {max_gap_s: -1}}").key(), "estimator.flow.max_gap_s");
  EXPECT_EQ(error("estimator: {flow: {track: {downsample: 3}}}").key(),
            "estimator.flow.track.downsample");
  EXPECT_EQ(error("estimator: {flow: {fit: {ransac_confidence: 1}}}").key(),
            "estimator.flow.fit.ransac_confidence");
  EXPECT_EQ(error("estimator: {flow: {fitt: {}}}").key(), "estimator.flow.fitt");
  const ParamError e = error("estimator: {flow: {track: {max_fb_error_px: 0}}}");
  EXPECT_EQ(e.file(), "v.yaml");
  EXPECT_NE(std::string(e.what()).find("px"), std::string::npos) << e.what();
}

}  // namespace
}  // namespace alight::estimator
