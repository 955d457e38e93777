// The simulated camera's effects (issue 41, sim/camera_effects.hpp): each checked against what
// its model predicts, on deterministic flights (no timing).
#include "sim/camera_effects.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <vector>

#include "common/build_paths.hpp"
#include "common/image_msg.hpp"
#include "common/msg_convert.hpp"
#include "common/params.hpp"
#include "sim/params.hpp"
#include "sim/sim_msgs.hpp"
#include "sim/simulator.hpp"
#include "sim_test_util.hpp"

namespace alight::sim {
namespace {

using test::config_path;

CameraRig downward_rig() {
  return load_camera_rig(config_path("vehicles/starmac.yaml"), "downward");
}

/// landing_a without randomisation, noise, flicker or automatic gain; flat grey floor (60) and
/// a flat white top (220) without the lamp, so a rendered edge is a clean step.
Scenario flat_scene() {
  Scenario s = test::scenario("landing_a");
  s.randomize = RandomizeParams{};
  s.wind = WindParams{};
  s.camera.noise_sigma = 0;
  s.camera.gain_jitter = 0;
  s.camera.motion_blur_samples = 1;
  s.camera.auto_gain = false;
  s.lighting.falloff = 0;
  s.floor_texture.contrast = 0;
  s.floor_texture.mean = 60;
  s.platform->texture.kind = "noise";
  s.platform->texture.contrast = 0;
  s.platform->texture.mean = 220;
  s.platform->center_xy_m = Vector2d(0.0, 0.0);
  s.platform->size_m = Vector3d(1.0, 0.6, 0.05);
  s.platform->yaw_deg = 0;
  return s;
}

/// Without drag, level at hover thrust: the vehicle keeps its velocity.
VehicleParams dragless() {
  VehicleParams v = test::starmac();
  v.drag_linear_Nspm = 0;
  v.drag_quadratic_Ns2pm2 = 0;
  return v;
}

/// Where the bright top gives way to the dark floor along row v, by the 140 crossing [px]; NaN
/// when the row has none.
double edge_column(const cv::Mat& img, int v) {
  const uchar* r = img.ptr<uchar>(v);
  for (int u = 1; u < img.cols; ++u) {
    const double a = r[u - 1], b = r[u];
    if ((a - 140) * (b - 140) < 0 || (b == 140 && a != 140)) return u - 1 + (140 - a) / (b - a);
  }
  return std::nan("");
}

struct Flight {
  std::vector<CameraFrame> frames;
  std::map<int64_t, VehicleState> states;  // by utime, every physics step
};

/// Flies level at hover thrust from p0 with velocity v0 for `seconds`, taking every frame.
Flight fly(Simulator& sim, const Vector3d& p0, const Vector3d& v0, double seconds,
           const VehicleParams& v) {
  test::place(sim, p0);
  VehicleState s = sim.state();
  s.v_W_B = v0;
  sim.set_state(s);
  Flight f;
  const int64_t end = sim.now_utime() + std::llround(seconds * 1e6);
  while (sim.now_utime() < end) {
    sim.step(test::hover(v), sim.now_utime() + 1000);
    f.states[sim.now_utime()] = sim.state();
    if (auto frame = sim.take_camera()) f.frames.push_back(std::move(*frame));
  }
  return f;
}

TEST(CameraEffectsTest, RollingShutterShearsAnEdgeByTheMotionDuringReadout) {
  // Moving sideways (world y: the image's u for the downward camera) at 1 m/s, 1 m above the
  // top: row v is exposed v x 40 us after row 0, so the top's edge along x shifts by
  // fx x v x t / depth = 666.7 x 1 m/s x 19.16 ms / 1 m = 12.8 px from the first row to the last.
  Scenario s = flat_scene();
  s.camera.effects.rolling_shutter = true;
  s.camera.effects.line_delay_s = 40e-6;
  const VehicleParams v = dragless();
  const CameraRig rig = downward_rig();
  Simulator sim(s, v, 1, rig);
  const double top_z = 0.05;
  // The camera 5 cm forward of the body origin and 6 cm below it (starmac.yaml).
  const double body_z = top_z + 1.0 - rig.mount.t_B_C.z();
  const Flight f = fly(sim, Vector3d(0, -0.1, body_z), Vector3d(0, 1.0, 0), 0.2, v);
  ASSERT_GE(f.frames.size(), 4u);
  const CameraFrame& frame = f.frames[3];
  EXPECT_DOUBLE_EQ(frame.line_delay_s, 40e-6);
  // The edge's predicted column in row v: the edge y = 0.3 projected from the pose at row v's
  // time (rows are rendered in bands of 8 from their middle row's time: within 0.1 px).
  const double y_edge = 0.5 * s.platform->size_m.y();
  auto predicted = [&](int row) {
    const int64_t t = frame.utime + std::llround(row * 40.0);
    auto it = f.states.lower_bound(t);
    const VehicleState& st = it->second;
    const Isometry3d X_WC =
        camera_in_world(make_transform(st.q_WB.toRotationMatrix(), st.p_W_B), rig.mount.X_BC());
    // A point of the edge seen near row `row`: vary x until its projection lands there.
    const Vector3d C = X_WC.translation();
    const double depth = C.z() - top_z;
    const double x = C.x() - (row - rig.model.cy) / rig.model.fy * depth;  // y_C = -x_B
    return rig.model.project(X_WC.inverse() * Vector3d(x, y_edge, top_z))->x();
  };
  double first = std::nan(""), last = std::nan("");
  for (int row : {4, 100, 240, 380, 475}) {
    SCOPED_TRACE(row);
    const double measured = edge_column(frame.pixels, row);
    ASSERT_TRUE(std::isfinite(measured));
    EXPECT_NEAR(measured, predicted(row), 0.75);
    if (row == 4) first = measured;
    if (row == 475) last = measured;
  }
  const double expected_shear = rig.model.fx * 1.0 * (471 * 40e-6) / 1.0;
  EXPECT_NEAR(std::abs(last - first), expected_shear, 1.0);
  EXPECT_GT(std::abs(last - first), 10.0);

  // A global shutter: the same flight's edge is straight.
  Scenario g = s;
  g.camera.effects.rolling_shutter = false;
  Simulator sim_g(g, v, 1, rig);
  const Flight fg = fly(sim_g, Vector3d(0, -0.1, body_z), Vector3d(0, 1.0, 0), 0.2, v);
  ASSERT_GE(fg.frames.size(), 4u);
  EXPECT_NEAR(edge_column(fg.frames[3].pixels, 4), edge_column(fg.frames[3].pixels, 475), 0.75);
  EXPECT_EQ(fg.frames[3].line_delay_s, 0.0);
}

// The pixels of row v between the floor's grey (60) and the top's (220), exclusive of both
// ends' 10 levels: the width of the top's edges the row crosses [px].
int edge_width_px(const cv::Mat& img, int v) {
  int n = 0;
  for (int u = 0; u < img.cols; ++u) n += img.at<uchar>(v, u) > 70 && img.at<uchar>(v, u) < 210;
  return n;
}

TEST(CameraEffectsTest, AMovingTopIsSmearedByItsMotionRelativeToTheCamera) {
  // A cart at 1 m/s along world y (the image's u for the downward camera) under a 20 ms
  // exposure, 1 m below the camera: seen from a vehicle keeping pace with it, its edges across
  // the rows are sharp over the exposure; seen from a vehicle standing still, each is smeared
  // over fx x 1 m/s x 20 ms / 1 m = 13.3 px.
  Scenario s = flat_scene();
  s.camera.exposure_s = 0.02;
  s.camera.motion_blur_samples = 16;
  s.platform->moving = true;
  s.platform->motion.path = "line";
  s.platform->motion.speed_mps = 1.0;
  s.platform->motion.path_heading_deg = 90;
  s.platform->motion.path_length_m = 2.0;
  s.platform->motion.path_radius_m = 0.6;
  s.validate();
  const VehicleParams v = dragless();
  const CameraRig rig = downward_rig();
  const double body_z = 0.05 + 1.0 - rig.mount.t_B_C.z();
  const double smear_px = rig.model.fx * 1.0 * 0.02 / 1.0;
  const auto width = [&](const Vector3d& v0) {
    Simulator sim(s, v, 1, rig);
    const Flight f = fly(sim, Vector3d(0, 0, body_z), v0, 0.2, v);
    EXPECT_GE(f.frames.size(), 4u);
    return f.frames.size() < 4 ? -1 : edge_width_px(f.frames[3].pixels, 240);
  };
  const int keeping_pace = width(Vector3d(0, 1.0, 0));
  const int standing = width(Vector3d::Zero());
  EXPECT_LE(keeping_pace, 4);  // two edges, a pixel or two each
  EXPECT_NEAR(standing, 2 * smear_px, 4.0);
}

TEST(CameraEffectsTest, TheLineDelayGoesOutAsImageMetadata) {
  CameraFrame f;
  f.pixels = cv::Mat(4, 4, CV_8U, cv::Scalar(0));
  f.exposure_s = 0.004;
  EXPECT_FALSE(metadata_int(to_msg(f), "line_delay_ns").has_value());
  f.line_delay_s = 25e-6;
  const image_t m = to_msg(f);
  EXPECT_EQ(metadata_int(m, "line_delay_ns"), 25000);
  const auto img = image_from_msg(m, true, nullptr);
  ASSERT_TRUE(img);
  ASSERT_TRUE(img->line_delay_s);
  EXPECT_DOUBLE_EQ(*img->line_delay_s, 25e-6);
}

TEST(CameraEffectsTest, AnExposureStepSettlesAfterItsLag) {
  CameraEffects e;
  e.exposure_steps = true;
  e.ae_max_ev = 2;
  e.ae_rate_hz = 1e-9;  // no step of its own
  e.ae_lag_frames = 4;
  ExposureSteps ae(e, 30);
  std::mt19937_64 rng(1);
  EXPECT_EQ(ae.next_ev(rng), 0.0);
  ae.start(2.0);
  const std::vector<double> expected{2.0, 1.5, 1.0, 0.5, 0.0, 0.0};
  for (double ev : expected) EXPECT_DOUBLE_EQ(ae.next_ev(rng), ev);
}

TEST(CameraEffectsTest, AnExposureStepScalesTheBrightnessBy2PowEv) {
  // A hovering camera over a flat floor (mean 40 grey levels: +2 EV stays below clipping):
  // each frame's mean is the settled frames' mean times 2^EV of its step.
  Scenario s = flat_scene();
  s.platform.reset();
  s.floor_texture.mean = 40;
  s.camera.effects.exposure_steps = true;
  s.camera.effects.ae_max_ev = 2;
  s.camera.effects.ae_rate_hz = 6;
  s.camera.effects.ae_lag_frames = 3;
  const VehicleParams v = dragless();
  Simulator sim(s, v, 3, downward_rig());
  const Flight f = fly(sim, Vector3d(0, 0, 1.2), Vector3d::Zero(), 4.0, v);
  ASSERT_GT(f.frames.size(), 100u);
  double settled = 0;
  int n_settled = 0, n_steps = 0;
  for (const auto& fr : f.frames)
    if (fr.exposure_ev == 0.0) {
      settled += cv::mean(fr.pixels)[0];
      ++n_settled;
    }
  ASSERT_GT(n_settled, 10);
  settled /= n_settled;
  double largest = 0;
  for (size_t i = 0; i < f.frames.size(); ++i) {
    const auto& fr = f.frames[i];
    EXPECT_NEAR(cv::mean(fr.pixels)[0] / settled, std::exp2(fr.exposure_ev), 0.02);
    largest = std::max(largest, std::abs(fr.exposure_ev));
    // A step's frame is followed by lag_frames - 1 smaller ones, then a settled one (unless a
    // new step began).
    if (i > 0 && std::abs(fr.exposure_ev) > std::abs(f.frames[i - 1].exposure_ev)) ++n_steps;
  }
  EXPECT_GT(n_steps, 5);
  EXPECT_GT(largest, 1.0);
  EXPECT_LE(largest, 2.0);
}

TEST(CameraEffectsTest, TheGyroSeesTheVibrationAveragedOverItsSample) {
  // Same seed with and without vibration: the IMU's noise streams are the same, so the gyro's
  // difference is the vibration's mean rate over each 5 ms sample, exactly.
  Scenario s = test::quiet(test::scenario("landing_a"));
  s.vibration.enabled = true;
  s.vibration.base_hz = 80;
  s.vibration.harmonics = 1;
  s.vibration.angle_rad = 0.002;
  s.vibration.linear_m = 0;
  Scenario off = s;
  off.vibration.enabled = false;
  const VehicleParams v = test::starmac();
  Simulator a(s, v, 5), b(off, v, 5);
  a.step(AttitudeCommand{}, a.now_utime() + 2'000'000);
  b.step(AttitudeCommand{}, b.now_utime() + 2'000'000);
  const auto ia = a.take_imu(), ib = b.take_imu();
  ASSERT_EQ(ia.size(), ib.size());
  ASSERT_GT(ia.size(), 300u);
  double sum2 = 0;
  int n = 0;
  for (size_t k = 1; k < ia.size(); ++k) {
    const double t1 = (ia[k].utime - s.start_utime) * 1e-6,
                 t0 = (ia[k - 1].utime - s.start_utime) * 1e-6;
    const Vector3d diff = ia[k].gyro_B - ib[k].gyro_B;
    EXPECT_LT((diff - a.vibration().mean_rate(t0, t1)).norm(), 1e-9);
    sum2 += diff.squaredNorm();
    n += 3;
  }
  // A sinusoid of amplitude A = 0.002 x 2 pi 80 averaged over 5 ms keeps sinc(80 x 0.005) of
  // it: RMS A 0.757 / sqrt(2) = 0.538 rad/s per axis.
  const double A = 0.002 * 2 * M_PI * 80, sinc = std::sin(M_PI * 0.4) / (M_PI * 0.4);
  EXPECT_NEAR(std::sqrt(sum2 / n), A * sinc / std::sqrt(2.0), 0.03);
}

TEST(CameraEffectsTest, VibrationUnderARollingShutterWobblesAnEdgeRowByRow) {
  // Hovering still, 1 m above the top: the mount's 0.005 rad at 100 Hz moves the image by up to
  // fx x 0.005 = 3.3 px; a rolling shutter sees it differently in each row (a wavy edge), a
  // global shutter in all rows alike (a straight, blurred edge).
  Scenario s = flat_scene();
  s.vibration.enabled = true;
  s.vibration.base_hz = 100;
  s.vibration.harmonics = 1;
  s.vibration.angle_rad = 0.005;
  s.vibration.linear_m = 0;
  s.camera.exposure_s = 0.001;
  s.camera.effects.rolling_shutter = true;
  s.camera.effects.line_delay_s = 40e-6;
  const VehicleParams v = dragless();
  const CameraRig rig = downward_rig();
  const double body_z = 0.05 + 1.0 - rig.mount.t_B_C.z();
  // The edge's largest departure from a straight line (a rotation about the optical axis
  // tilts it, straight, in either case).
  auto spread = [&](const Scenario& sc) {
    Simulator sim(sc, v, 2, rig);
    const Flight f = fly(sim, Vector3d(0, 0.1, body_z), Vector3d::Zero(), 0.2, v);
    const cv::Mat& img = f.frames.at(4).pixels;
    std::vector<double> rows, cols;
    for (int row = 20; row < 460; row += 4) {
      rows.push_back(row);
      cols.push_back(edge_column(img, row));
    }
    const double n = rows.size();
    double sr = 0, sc2 = 0, srr = 0, src = 0;
    for (size_t i = 0; i < rows.size(); ++i) {
      sr += rows[i];
      sc2 += cols[i];
      srr += rows[i] * rows[i];
      src += rows[i] * cols[i];
    }
    const double slope = (n * src - sr * sc2) / (n * srr - sr * sr);
    const double icept = (sc2 - slope * sr) / n;
    double worst = 0;
    for (size_t i = 0; i < rows.size(); ++i)
      worst = std::max(worst, std::abs(cols[i] - (icept + slope * rows[i])));
    return worst;
  };
  EXPECT_GT(spread(s), 1.5);
  Scenario g = s;
  g.camera.effects.rolling_shutter = false;
  EXPECT_LT(spread(g), 0.75);
}

TEST(CameraEffectsTest, VignettingDarkensTheCornersToTheirRatio) {
  const CameraModel m = CameraModel::firefly_mv_4mm();
  const cv::Mat map = vignetting_map(m, 0.5);
  EXPECT_NEAR(map.at<float>(240, 320), 1.0, 1e-4);
  // Pixel (0, 0) is 399.4 px from the principal point, the corner itself 400 px.
  EXPECT_NEAR(map.at<float>(0, 0), 0.5, 0.005);
  EXPECT_NEAR(map.at<float>(479, 639), 0.5, 0.005);
  // The rendered frame of an evenly lit floor: corner / centre as the map says.
  Scenario s = flat_scene();
  s.platform.reset();
  s.floor_texture.mean = 200;
  s.camera.effects.vignetting = true;
  s.camera.effects.vignetting_corner = 0.5;
  const VehicleParams v = dragless();
  Simulator sim(s, v, 1, downward_rig());
  const Flight f = fly(sim, Vector3d(0, 0, 1.2), Vector3d::Zero(), 0.1, v);
  const cv::Mat& img = f.frames.at(1).pixels;
  const double centre = cv::mean(img(cv::Rect(310, 230, 20, 20)))[0];
  const double corner = cv::mean(img(cv::Rect(0, 0, 4, 4)))[0];
  EXPECT_NEAR(corner / centre, 0.5, 0.02);
}

TEST(CameraEffectsTest, AFisheyeProjectsAsTheEquidistantModel) {
  CameraModel m = CameraModel::firefly_mv_4mm();
  m.distortion = CameraModel::Distortion::kEquidistant;
  m.D = {0.05, -0.01, 0.002, -0.0005, 0.0};
  const Vector3d p(0.6, -0.45, 1.0);
  const double r = std::hypot(p.x(), p.y()), th = std::atan(r);
  const double th_d = th * (1 + 0.05 * std::pow(th, 2) - 0.01 * std::pow(th, 4) +
                            0.002 * std::pow(th, 6) - 0.0005 * std::pow(th, 8));
  const auto px = m.project(p);
  ASSERT_TRUE(px);
  EXPECT_NEAR(px->x(), m.fx * th_d * p.x() / r + m.cx, 1e-9);
  EXPECT_NEAR(px->y(), m.fy * th_d * p.y() / r + m.cy, 1e-9);
  // ... and the ray through that pixel is the point's (what the vision undistorts with).
  EXPECT_LT((m.ray(*px) - p / p.z()).norm(), 1e-9);
  EXPECT_TRUE(m.has_distortion());
  // camera_info round trip.
  const auto dir = std::filesystem::path(alight::build::binary_dir()) / "test_tmp" / "sim";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "fisheye.yaml").string();
  save_camera_info(path, m);
  const CameraModel back = load_camera_info(path);
  EXPECT_EQ(back.distortion, CameraModel::Distortion::kEquidistant);
  for (int i = 0; i < 5; ++i) EXPECT_DOUBLE_EQ(back.D[i], m.D[i]);
  // The scenario's lens: the simulator renders with it, and says so.
  Scenario s = flat_scene();
  s.camera.effects.lens = true;
  s.camera.effects.lens_model = "equidistant";
  s.camera.effects.lens_coefficients = m.D;
  Simulator sim(s, dragless(), 1, downward_rig());
  ASSERT_TRUE(sim.camera_model());
  EXPECT_EQ(sim.camera_model()->distortion, CameraModel::Distortion::kEquidistant);
  EXPECT_EQ(with_lens(CameraModel{}, s.camera.effects).D, m.D);
}

TEST(CameraEffectsTest, AFisheyeFrameShowsAnEdgeWhereTheModelProjectsIt) {
  // The top's edge y = 0.3 seen 1 m below the camera: in the fisheye frame it crosses row 240
  // where the equidistant model projects it, not where the pinhole would.
  Scenario s = flat_scene();
  s.camera.effects.lens = true;
  s.camera.effects.lens_model = "equidistant";
  s.camera.effects.lens_coefficients = {-0.1, 0.0, 0.0, 0.0, 0.0};
  const VehicleParams v = dragless();
  const CameraRig rig = downward_rig();
  Simulator sim(s, v, 1, rig);
  const double body_z = 0.05 + 1.0 - rig.mount.t_B_C.z();
  const Flight f = fly(sim, Vector3d(0, 0.0, body_z), Vector3d::Zero(), 0.1, v);
  const CameraFrame& fr = f.frames.at(1);
  const CameraModel m = *sim.camera_model();
  const Isometry3d X_CW = fr.X_WC.inverse();
  // The point of the edge on the optical axis's row (x of the camera centre).
  const Vector3d edge_W(fr.X_WC.translation().x(), 0.3, 0.05);
  const Vector2d px = *m.project(X_CW * edge_W);
  const Vector2d pinhole = *CameraModel{}.project(X_CW * edge_W);
  ASSERT_GT(std::abs(px.x() - pinhole.x()), 5.0);
  EXPECT_NEAR(edge_column(fr.pixels, static_cast<int>(std::lround(px.y()))), px.x(), 0.75);
}

TEST(CameraEffectsTest, TheDriverDropsRepeatsAndJittersFrames) {
  Scenario s = flat_scene();
  s.camera.effects.driver = true;
  s.camera.effects.drop_prob = 0.1;
  s.camera.effects.dup_prob = 0.1;
  s.camera.effects.stamp_jitter_s = 0.001;
  s.floor_texture.contrast = 1;
  const VehicleParams v = dragless();
  Simulator sim(s, v, 4, downward_rig());
  // Over a textured floor, so every new frame differs from the one before.
  const Flight f = fly(sim, Vector3d(0, -0.4, 1.2), Vector3d(0, 0.1, 0), 10.0, v);
  const int64_t period = std::llround(1e6 / s.camera.rate_hz);
  const int n = static_cast<int>(f.frames.size());
  int gaps = 0, dups = 0;
  double sum2 = 0;
  for (size_t i = 0; i < f.frames.size(); ++i) {
    const CameraFrame& fr = f.frames[i];
    // The exposure's true time is start + seq x period; the stamp carries the jitter.
    const int64_t nominal = s.start_utime + fr.seq * period;
    sum2 += std::pow((fr.utime - nominal) * 1e-6, 2);
    if (i == 0) continue;
    const CameraFrame& prev = f.frames[i - 1];
    EXPECT_GT(fr.utime, prev.utime);
    gaps += static_cast<int>(fr.seq - prev.seq - 1);
    if (fr.duplicate) {
      ++dups;
      EXPECT_EQ(cv::norm(fr.pixels, prev.pixels, cv::NORM_INF), 0.0);
    } else {
      // The vehicle moves: a new frame differs from the one before.
      EXPECT_GT(cv::norm(fr.pixels, prev.pixels, cv::NORM_INF), 0.0);
    }
  }
  EXPECT_EQ(gaps + (f.frames.front().seq - 1), sim.camera_frames_dropped());
  // 10 % of the frames, 10 % of those delivered: within four binomial standard deviations.
  const double m = static_cast<double>(f.frames.back().seq);
  EXPECT_NEAR(sim.camera_frames_dropped(), 0.1 * m, 4 * std::sqrt(0.09 * m));
  EXPECT_NEAR(dups, 0.1 * n, 4 * std::sqrt(0.09 * n));
  EXPECT_GT(dups, 0);
  EXPECT_EQ(n + sim.camera_frames_dropped(), f.frames.back().seq);
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.001, 0.0002);
}

TEST(CameraEffectsTest, EachEffectIsOffByDefaultAndItsKeysAreChecked) {
  const CameraEffects e;
  EXPECT_FALSE(e.rolling_shutter || e.exposure_steps || e.vignetting || e.lens || e.driver);
  EXPECT_FALSE(VibrationParams{}.enabled);
  const auto dir = std::filesystem::path(alight::build::binary_dir()) / "test_tmp" / "sim";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "bad_effects.yaml").string();
  std::ofstream(path) << "name: bad\ncamera:\n  effects:\n    rolling_shutter:\n"
                         "      enabled: true\n      line_delay_s: 0.5\n";
  try {
    load_scenario(path);
    FAIL() << "no error";
  } catch (const ParamError& err) {
    EXPECT_NE(std::string(err.what()).find("camera.effects.rolling_shutter.line_delay_s"),
              std::string::npos)
        << err.what();
  }
  std::ofstream(path) << "name: bad\ncamera:\n  effects:\n    lens:\n      model: equidistant\n"
                         "      coefficients: [0.1, 0, 0, 0, 0.2]\n";
  try {
    load_scenario(path);
    FAIL() << "no error";
  } catch (const ParamError& err) {
    EXPECT_NE(std::string(err.what()).find("camera.effects.lens.coefficients"), std::string::npos)
        << err.what();
  }
  std::ofstream(path) << "name: bad\nvibration:\n  base_hz: 40\n";
  EXPECT_THROW(load_scenario(path), ParamError);
}

}  // namespace
}  // namespace alight::sim
