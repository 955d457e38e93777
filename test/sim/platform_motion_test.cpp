// Moving platforms (issue 40): the pose against the analytic motion, the simulator's platform
// following it, a vehicle standing on a moving deck carried with it, the limits refused with the
// key named, and a platform standing still left as it was.
#include "sim/platform_motion.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "common/build_paths.hpp"
#include "common/params.hpp"
#include "sim/sim_msgs.hpp"
#include "sim_test_util.hpp"

namespace alight::sim {
namespace {

constexpr double kMotionDeg = M_PI / 180.0;

PlatformMotionParams motion_path(const std::string& kind, double speed, double radius,
                                 double length = 2.0) {
  PlatformMotionParams p;
  p.path = kind;
  p.speed_mps = speed;
  p.path_radius_m = radius;
  p.path_length_m = length;
  return p;
}

TEST(PlatformMotionTest, PathsAgainstTheirClosedForms) {
  const Vector3d top0(1.0, 2.0, 0.1);
  const double r = 0.6, v = 1.0;
  // Circle, turning left from +x: a quarter turn later it is r ahead and r to the left.
  {
    PlatformMotion m(motion_path("circle", v, r), top0, 0.3, 1);
    const double t = 0.5 * M_PI * r / v;
    const PlatformPose P = m.at(t);
    EXPECT_TRUE(P.top_center_W.isApprox(top0 + Vector3d(r, r, 0), 1e-12)) << P.top_center_W;
    EXPECT_TRUE(P.v_W.isApprox(Vector3d(0, v, 0), 1e-12)) << P.v_W;
    EXPECT_NEAR(P.yaw_rad, 0.3, 1e-12);  // keeps its heading
    EXPECT_TRUE(m.at(2 * M_PI * r / v).top_center_W.isApprox(top0, 1e-12));
  }
  // Line (a stadium) turned by 90 deg: out along +y, over to -x, back along -y.
  {
    PlatformMotionParams p = motion_path("line", v, r, 2.0);
    p.path_heading_deg = 90;
    PlatformMotion m(p, top0, 0.0, 1);
    EXPECT_TRUE(m.at(1.0).top_center_W.isApprox(top0 + Vector3d(0, 1.0, 0), 1e-12));
    EXPECT_TRUE(m.at(2.0 + M_PI * r).top_center_W.isApprox(top0 + Vector3d(-2 * r, 2.0, 0), 1e-9));
    EXPECT_TRUE(m.at(2.0 + M_PI * r).v_W.isApprox(Vector3d(0, -v, 0), 1e-9));
    const double period = (4.0 + 2 * M_PI * r) / v;
    EXPECT_TRUE(m.at(period).top_center_W.isApprox(top0, 1e-9));
  }
  // Figure eight: at half its period it is back at the start heading the same way, then turns
  // right: a quarter turn on, r ahead and r to the right.
  {
    PlatformMotion m(motion_path("figure_eight", v, r), top0, 0.0, 1);
    const double lobe = 2 * M_PI * r / v;
    EXPECT_TRUE(m.at(lobe).top_center_W.isApprox(top0, 1e-9));
    EXPECT_TRUE(m.at(lobe).v_W.isApprox(Vector3d(v, 0, 0), 1e-9));
    EXPECT_TRUE(m.at(lobe * 1.25).top_center_W.isApprox(top0 + Vector3d(r, -r, 0), 1e-9));
  }
  // Drift and a constant turn; a heading that follows a circle turns at v / r.
  {
    PlatformMotionParams p = motion_path("circle", 0.5, 2.5);
    p.velocity_mps = Vector2d(0.1, -0.2);
    p.heading_follows_path = true;
    p.yaw_rate_dps = 3.0;
    PlatformMotion m(p, top0, 0.0, 1);
    const PlatformPose P = m.at(2.0);
    const double phi = 0.5 * 2.0 / 2.5;
    const Vector3d expected =
        top0 + Vector3d(2.5 * std::sin(phi) + 0.2, 2.5 * (1 - std::cos(phi)) - 0.4, 0);
    EXPECT_TRUE(P.top_center_W.isApprox(expected, 1e-12)) << P.top_center_W;
    EXPECT_NEAR(P.yaw_rad, phi + 6.0 * kMotionDeg, 1e-12);
    EXPECT_NEAR(P.omega_W.z(), 0.5 / 2.5 + 3.0 * kMotionDeg, 1e-12);
  }
}

// A cart that slows for its turns (max_course_rate_dps): the turns at radius times the bound,
// the straights entered and left at that speed, the speed continuous and its change at most
// kTurnAccelMps2, the velocity the pose's derivative, back at the start after one period.
TEST(PlatformMotionTest, ACartSlowsForItsTurns) {
  const double r = 0.6, v = 1.0, bound_dps = 15.0, L = 2.0;
  const double v_turn = r * bound_dps * kMotionDeg;  // 0.157 m/s
  const double a = PlatformMotionParams::kTurnAccelMps2;
  PlatformMotionParams p = motion_path("line", v, r, L);
  p.max_course_rate_dps = bound_dps;
  p.heading_follows_path = true;
  EXPECT_NEAR(p.turn_speed_mps(), v_turn, 1e-12);
  EXPECT_NEAR(p.peak_yaw_rate_dps(), bound_dps, 1e-9);
  const Vector3d top0(0.5, -0.5, 0.2);
  PlatformMotion m(p, top0, 0.0, 1);
  // The straight: up from v_turn to v over (v^2 - v_turn^2) / 2a, cruising, down again.
  const double ramp_m = (v * v - v_turn * v_turn) / (2 * a), ramp_s = (v - v_turn) / a;
  const double straight_s = 2 * ramp_s + (L - 2 * ramp_m) / v, half_s = M_PI * r / v_turn;
  EXPECT_NEAR(PlatformMotion::travel(p, ramp_s).s_m, ramp_m, 1e-9);
  EXPECT_NEAR(PlatformMotion::travel(p, ramp_s).speed_mps, v, 1e-9);
  EXPECT_NEAR(PlatformMotion::travel(p, straight_s).s_m, L, 1e-9);
  EXPECT_NEAR(PlatformMotion::travel(p, straight_s + 0.5 * half_s).speed_mps, v_turn, 1e-12);
  EXPECT_NEAR(PlatformMotion::travel(p, straight_s + half_s).s_m, L + M_PI * r, 1e-9);
  const double period = 2 * (straight_s + half_s);
  EXPECT_TRUE(m.at(period).top_center_W.isApprox(top0, 1e-9)) << m.at(period).top_center_W;
  EXPECT_NEAR(PlatformMotion::travel(p, 3 * period).s_m, 3 * (2 * L + 2 * M_PI * r), 1e-8);
  double last_speed = v_turn;
  for (double t = 0.0; t < 2 * period; t += 0.01) {
    SCOPED_TRACE(t);
    const PlatformPose P = m.at(t);
    const double speed = P.v_W.head<2>().norm();
    EXPECT_LE(speed, v + 1e-12);
    EXPECT_GE(speed, v_turn - 1e-12);
    EXPECT_LE(std::abs(speed - last_speed), a * 0.01 + 1e-9);  // no step in speed
    last_speed = speed;
    EXPECT_LE(std::abs(P.omega_W.z()), bound_dps * kMotionDeg + 1e-12);
    const double h = 1e-6;
    const Vector3d dp = (m.at(t + h).top_center_W - m.at(t - h).top_center_W) / (2 * h);
    EXPECT_LT((dp - P.v_W).norm(), 1e-6) << dp.transpose() << " / " << P.v_W.transpose();
  }
  // A straight too short to reach speed_mps peaks where speeding up meets slowing down.
  PlatformMotionParams shortp = motion_path("line", v, r, 0.5);
  shortp.max_course_rate_dps = bound_dps;
  const double peak = std::sqrt(v_turn * v_turn + a * 0.5);
  EXPECT_NEAR(PlatformMotion::travel(shortp, (peak - v_turn) / a).speed_mps, peak, 1e-9);
  EXPECT_NEAR(PlatformMotion::travel(shortp, (peak - v_turn) / a).s_m, 0.25, 1e-9);
  // A circle is a turn throughout: at the bound's speed, the course turning at the bound.
  PlatformMotionParams circle = motion_path("circle", v, r);
  circle.max_course_rate_dps = bound_dps;
  EXPECT_NEAR(PlatformMotion(circle, top0, 0, 1).at(3.0).v_W.norm(), v_turn, 1e-12);
  // No bound, or one the speed keeps within: the constant speed, as before.
  PlatformMotionParams loose = motion_path("line", 0.1, r, L);
  loose.max_course_rate_dps = bound_dps;
  EXPECT_DOUBLE_EQ(PlatformMotion::travel(loose, 7.0).s_m, 0.1 * 7.0);
  EXPECT_DOUBLE_EQ(PlatformMotion::travel(motion_path("line", v, r, L), 7.0).s_m, 7.0);
}

TEST(PlatformMotionTest, DeckSinesAndTheirRates) {
  PlatformMotionParams p;
  p.heave_amplitude_m = 0.05;
  p.heave_frequency_hz = 0.3;
  p.heave_phase_deg = 30;
  p.roll_amplitude_deg = 3;
  p.roll_frequency_hz = 0.4;
  p.pitch_amplitude_deg = 2;
  p.pitch_frequency_hz = 0.25;
  p.pitch_phase_deg = 90;
  const Vector3d top0(0, 0, 0.2);
  PlatformMotion m(p, top0, 0.5, 1);
  for (double t : {0.0, 0.7, 1.9, 4.2}) {
    const PlatformPose P = m.at(t);
    EXPECT_NEAR(P.top_center_W.z(), 0.2 + 0.05 * std::sin(2 * M_PI * 0.3 * t + 30 * kMotionDeg),
                1e-12);
    EXPECT_NEAR(P.roll_rad, 3 * kMotionDeg * std::sin(2 * M_PI * 0.4 * t), 1e-12);
    EXPECT_NEAR(P.pitch_rad, 2 * kMotionDeg * std::sin(2 * M_PI * 0.25 * t + 90 * kMotionDeg),
                1e-12);
    EXPECT_TRUE(P.R_WO.isApprox(rotation_from_rpy(P.roll_rad, P.pitch_rad, 0.5), 1e-12));
    // Velocities against finite differences of the pose.
    const double h = 1e-6;
    const PlatformPose A = m.at(t - h), B = m.at(t + h);
    EXPECT_TRUE(P.v_W.isApprox((B.top_center_W - A.top_center_W) / (2 * h), 1e-6));
    const Matrix3d dR = (B.R_WO - A.R_WO) / (2 * h) * P.R_WO.transpose();  // [omega]x
    const Vector3d omega(dR(2, 1), dR(0, 2), dR(1, 0));
    EXPECT_LT((omega - P.omega_W).norm(), 1e-6)
        << omega.transpose() << " / " << P.omega_W.transpose();
  }
}

TEST(PlatformMotionTest, SeaStateStaysWithinItsBoundsAndFollowsTheSeed) {
  PlatformMotionParams p;
  p.sea_heave_m = 0.05;
  p.sea_roll_deg = 3;
  p.sea_pitch_deg = 3;
  const PlatformMotion a(p, Vector3d::Zero(), 0, 7), b(p, Vector3d::Zero(), 0, 7),
      c(p, Vector3d::Zero(), 0, 8);
  ASSERT_EQ(a.sea_heave().size(), 4u);
  for (const auto& s : a.sea_roll()) {
    EXPECT_GE(s.frequency_hz, 0.2);
    EXPECT_LE(s.frequency_hz, 0.5);
    EXPECT_NEAR(s.amplitude, 0.75 * kMotionDeg, 1e-15);
  }
  double max_heave = 0, max_roll = 0;
  for (double t = 0; t < 120; t += 0.05) {
    const PlatformPose P = a.at(t);
    max_heave = std::max(max_heave, std::abs(P.top_center_W.z()));
    max_roll = std::max(max_roll, std::abs(P.roll_rad));
    EXPECT_EQ(P.top_center_W, b.at(t).top_center_W);
  }
  EXPECT_LE(max_heave, 0.05);
  EXPECT_GT(max_heave, 0.02);  // it does move
  EXPECT_LE(max_roll, 3 * kMotionDeg);
  EXPECT_NE(a.at(3.0).top_center_W.z(), c.at(3.0).top_center_W.z());
}

Scenario moving_platform_scenario() {
  Scenario s = test::quiet(test::scenario("landing_a"));
  s.platform->moving = true;
  s.platform->center_xy_m = Vector2d(-0.5, 1.1);
  s.platform->motion = motion_path("line", 0.5, 0.6, 2.0);
  s.platform->motion.heave_amplitude_m = 0.03;
  s.platform->motion.roll_amplitude_deg = 2.0;
  s.platform->motion.pitch_amplitude_deg = 2.0;
  s.platform->motion.pitch_frequency_hz = 0.45;
  s.validate();
  return s;
}

TEST(PlatformMotionTest, TheSimulatorsPlatformFollowsTheMotion) {
  const Scenario sc = moving_platform_scenario();
  Simulator sim(sc, test::starmac(), 3);
  ASSERT_NE(sim.platform_motion(), nullptr);
  const Vector3d top0(-0.5, 1.1, sc.platform->size_m.z());
  const PlatformMotion analytic(sc.platform->motion, top0, 0.0, 0);
  const int64_t t0 = sim.now_utime();
  AttitudeCommand idle;
  for (double t_s : {0.5, 3.0, 6.4}) {
    sim.step(idle, t0 + static_cast<int64_t>(t_s * 1e6));
    const Truth truth = sim.truth();
    const PlatformPose P = analytic.at(t_s);
    ASSERT_TRUE(truth.platform && truth.platform->moving);
    EXPECT_LT((truth.platform->top_center_W - P.top_center_W).norm(), 1e-9) << t_s;
    EXPECT_NEAR(truth.platform->roll_rad, P.roll_rad, 1e-12);
    EXPECT_LT((truth.platform->v_W - P.v_W).norm(), 1e-9);
    // The box the contacts and the renderer use: its top face's centre is the truth's.
    const Box& b = sim.scene().boxes[static_cast<size_t>(sim.scene().platform_box)];
    EXPECT_LT((b.center_W + b.R_WO().col(2) * b.half_size_m.z() - P.top_center_W).norm(), 1e-12);
    // The rangefinder's ray meets the moving top.
    const auto hit =
        sim.scene().cast_ray(P.top_center_W + Vector3d(0, 0, 1.0), -Vector3d::UnitZ(), 5);
    ASSERT_TRUE(hit);
    EXPECT_NEAR(hit->distance_m, 1.0, 1e-9);
    // SIM_PLATFORM carries it.
    const auto msg = platform_msg(truth);
    ASSERT_TRUE(msg);
    EXPECT_EQ(msg->version, platform_truth_t::VERSION);
    EXPECT_DOUBLE_EQ(msg->top_center_W[0], P.top_center_W.x());
    EXPECT_DOUBLE_EQ(msg->vel_W[1], P.v_W.y());
  }
}

// Regression: the landing diagnostic drew its truth with build_scene(scenario, seed), while the
// simulator draws its scene from a stream of the seed of its own; on the shipped cart (randomize
// on) its per-frame errors read 35 cm off a landing 3.8 cm off. simulated_scene is the
// simulator's own scene.
TEST(PlatformMotionTest, TheSimulatedSceneIsTheOneTheSimulatorFlies) {
  const Scenario sc = test::scenario("landing_moving_cart");
  ASSERT_GT(sc.randomize.platform_xy_m, 0.0);
  for (uint64_t seed : {1, 7, 12}) {
    Simulator sim(sc, test::starmac(), seed);
    const Scene scene = simulated_scene(sc, seed);
    ASSERT_TRUE(sim.scene().platform && scene.platform);
    EXPECT_EQ(sim.scene().platform->top_center_W, scene.platform->top_center_W) << seed;
    EXPECT_EQ(sim.scene().platform->yaw_rad, scene.platform->yaw_rad) << seed;
  }
}

TEST(PlatformMotionTest, TheCameraSeesThePlatformWhereItIs) {
  const Scenario sc = moving_platform_scenario();  // a bright paper top on a darker floor
  const CameraRig rig = load_camera_rig(test::config_path("vehicles/starmac.yaml"), "downward");
  Simulator sim(sc, test::starmac(), 3, rig);
  const Vector3d before = sim.truth().platform->top_center_W;
  sim.step(AttitudeCommand{}, sim.now_utime() + 2'000'000);  // 1 m on along x
  const Vector3d after = sim.truth().platform->top_center_W;
  ASSERT_GT((after - before).norm(), 0.9);
  const Isometry3d X_WB =
      make_transform(Matrix3d::Identity(), Vector3d(0.5 * (before.x() + after.x()), 1.1, 1.6));
  const cv::Mat img = sim.render(rig.mount, rig.model, X_WB);
  const Isometry3d X_WC = camera_in_world(X_WB, rig.mount.X_BC());
  const auto grey = [&](const Vector3d& p_W) {
    const auto px = rig.model.project(X_WC.inverse() * p_W);
    EXPECT_TRUE(px);
    double sum = 0;  // a 41 x 41 patch (8 cm): the print and the floor's texture vary
    for (int dv = -20; dv <= 20; ++dv)
      for (int du = -20; du <= 20; ++du)
        sum += img.at<uchar>(static_cast<int>(std::lround(px->y())) + dv,
                             static_cast<int>(std::lround(px->x())) + du);
    return sum / (41 * 41);
  };
  EXPECT_GT(grey(after), 170);  // the top is where the platform is now
  EXPECT_LT(grey(Vector3d(before.x(), before.y(), 0.0)), 150);  // and the floor where it was
}

TEST(PlatformMotionTest, AVehicleRestingOnAMovingDeckIsCarriedWithIt) {
  const Scenario sc = moving_platform_scenario();
  Simulator sim(sc, test::starmac(), 3);
  // Disarmed on the deck, at its place and speed at the start.
  const PlatformPose P0 = sim.platform_motion()->at(0.0);
  const Vector3d on_deck(P0.top_center_W.x(), P0.top_center_W.y(),
                         sim.dynamics().resting_height(P0.top_center_W.z()));
  test::place(sim, on_deck, /*armed=*/false);
  VehicleState s = sim.state();
  s.v_W_B = P0.velocity_at(on_deck);
  sim.set_state(s);
  const auto offset_in_deck = [&] {
    const Truth t = sim.truth();
    const Matrix3d R =
        rotation_from_rpy(t.platform->roll_rad, t.platform->pitch_rad, t.platform->yaw_rad);
    return Vector3d(R.transpose() * (t.state.p_W_B - t.platform->top_center_W));
  };
  const Vector3d offset0 = offset_in_deck();
  const int64_t t0 = sim.now_utime();
  AttitudeCommand idle;
  bool landed_seen = false;
  // Through the first straight, a half turn and part of the way back (12 s at 0.5 m/s).
  for (int k = 1; k <= 120; ++k) {
    sim.step(idle, t0 + k * 100'000);
    const Truth t = sim.truth();
    ASSERT_FALSE(t.tipped) << k;
    EXPECT_EQ(t.contact, Contact::kPlatformTop) << k;
    EXPECT_LT((offset_in_deck() - offset0).head<2>().norm(), 0.02) << k;
    landed_seen = landed_seen || t.landed;
  }
  EXPECT_TRUE(landed_seen);  // at rest relative to the deck
  const Truth end = sim.truth();
  EXPECT_TRUE(end.landed);
  EXPECT_GT((end.state.p_W_B - on_deck).head<2>().norm(), 1.0);  // it went somewhere
}

TEST(PlatformMotionTest, AStillPlatformIsLeftAsItWas) {
  const Scenario sc = test::quiet(test::scenario("landing_a"));
  Simulator sim(sc, test::starmac(), 3);
  EXPECT_EQ(sim.platform_motion(), nullptr);
  const PlatformTruth before = *sim.truth().platform;
  sim.step(test::hover(test::starmac()), sim.now_utime() + 500'000);
  const Truth t = sim.truth();
  EXPECT_FALSE(t.platform->moving);
  EXPECT_EQ(t.platform->top_center_W, before.top_center_W);
  EXPECT_EQ(t.platform->yaw_rad, before.yaw_rad);
  EXPECT_FALSE(platform_msg(t).has_value());  // no SIM_PLATFORM
  EXPECT_FALSE(sim.scene().boxes[static_cast<size_t>(sim.scene().platform_box)].moving);
}

std::string write_motion_scenario(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::path(alight::build::binary_dir()) / "test_tmp" / "sim";
  std::filesystem::create_directories(dir);
  const auto path = dir / name;
  std::ofstream(path) << text;
  return path.string();
}

TEST(PlatformMotionTest, TheLimitsAreRefusedWithTheKeyNamed) {
  struct Case {
    const char* motion;
    const char* key;
  };
  const Case cases[] = {
      {"{path: line, speed_mps: 1.2}", "platform.motion.speed_mps"},
      {"{path: circle, speed_mps: 0.8, velocity_mps: [0.3, 0]}", "platform.motion.speed_mps"},
      {"{velocity_mps: [1.1, 0.2]}", "platform.motion.velocity_mps"},
      {"{yaw_rate_dps: 20}", "platform.motion.yaw_rate_dps"},
      {"{path: circle, speed_mps: 1.0, path_radius_m: 2.0, heading_follows_path: true}",
       "platform.motion.heading_follows_path"},
      {"{roll: {amplitude_deg: 6, frequency_hz: 0.5}}", "platform.motion.roll.amplitude_deg"},
      {"{pitch: {amplitude_deg: 3, frequency_hz: 0.5}, sea_state: {pitch_deg: 3}}",
       "platform.motion.pitch.amplitude_deg"},
      {"{sea_state: {roll_deg: 6, band_hz: [0.2, 0.5]}}", "platform.motion.sea_state.roll_deg"},
      {"{heave: {amplitude_m: 0.3, frequency_hz: 1.0}}", "platform.motion.heave.amplitude_m"},
      {"{sea_state: {band_hz: [0.5, 0.2]}}", "platform.motion.sea_state.band_hz"},
      {"{path: spiral}", "platform.motion.path"},
      {"{path: line, speed_mps: 1.0, path_radius_m: 0.6, heading_follows_path: true, "
       "max_course_rate_dps: 20}",
       "platform.motion.heading_follows_path"},
      {"{path: line, speed_mps: 1.0, max_course_rate_dps: -1}",
       "platform.motion.max_course_rate_dps"},
  };
  int i = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.motion);
    const std::string file = write_motion_scenario(
        "motion_limit_" + std::to_string(i++) + ".yaml",
        std::string("name: t\nplatform:\n  center_xy_m: [1.5, 1.0]\n  size_m: [0.4, 0.3, 0.1]\n"
                    "  motion: ") +
            c.motion + "\n");
    try {
      load_scenario(file);
      ADD_FAILURE() << "accepted";
    } catch (const ParamError& e) {
      EXPECT_EQ(e.key(), c.key) << e.what();
      EXPECT_EQ(e.file(), file);
    }
  }
  // At the limits exactly: accepted.
  EXPECT_NO_THROW(load_scenario(write_motion_scenario(
      "motion_at_limit.yaml",
      "name: t\nplatform:\n  center_xy_m: [1.5, 1.0]\n  size_m: [0.4, 0.3, 0.1]\n"
      "  motion: {path: figure_eight, speed_mps: 1.0, yaw_rate_dps: -15}\n")));
  // A cart turning with a path too tight for its speed, slowing for the turns: accepted.
  EXPECT_NO_THROW(load_scenario(write_motion_scenario(
      "motion_slowing_cart.yaml",
      "name: t\nplatform:\n  center_xy_m: [1.5, 1.0]\n  size_m: [0.4, 0.3, 0.1]\n"
      "  motion: {path: line, speed_mps: 1.0, path_radius_m: 0.6, heading_follows_path: true, "
      "max_course_rate_dps: 15}\n")));
}

TEST(PlatformMotionTest, TheShippedMovingScenariosLoad) {
  const Scenario cart = test::scenario("landing_moving_cart");
  ASSERT_TRUE(cart.platform && cart.platform->moving);
  EXPECT_EQ(cart.platform->motion.speed_mps, 1.0);
  EXPECT_EQ(cart.platform->motion.path, "line");
  // A cart turns with its path, slowed for its turns to the platform's turn bound.
  EXPECT_TRUE(cart.platform->motion.heading_follows_path);
  EXPECT_EQ(cart.platform->motion.max_course_rate_dps, 15.0);
  const Scenario fast = test::scenario("landing_moving_cart_fast_turns");
  ASSERT_TRUE(fast.platform && fast.platform->moving);
  EXPECT_EQ(fast.platform->motion.speed_mps, 1.0);
  EXPECT_FALSE(fast.platform->motion.heading_follows_path);
  EXPECT_EQ(fast.platform->motion.max_course_rate_dps, 0.0);
  const Scenario deck = test::scenario("landing_deck");
  ASSERT_TRUE(deck.platform && deck.platform->moving);
  EXPECT_EQ(deck.platform->motion.speed_mps, 0.5);
  EXPECT_EQ(deck.platform->motion.sea_heave_m, 0.05);
  EXPECT_EQ(deck.platform->motion.sea_roll_deg, 3.0);
  EXPECT_FALSE(test::scenario("landing_a").platform->moving);
}

}  // namespace
}  // namespace alight::sim
