// Closed loop in-process with REAL vision (issue 6): alight_sim renders the camera, the vision
// pipeline (exactly the node's, converted to VISION_TARGET and back as autonomy receives it)
// finds the platform or the opening, autonomy and the outer loop fly the vehicle. Lockstep and
// deterministic (processing time is not simulated; the LCM stack's own timing is measured by
// scripts/montecarlo). One seed per paper platform and one ingress flight keep ctest short.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <tuple>

#include "closed_loop.hpp"
#include "common/build_paths.hpp"
#include "real_vision.hpp"
#include "sim/params.hpp"
#include "sim/simulator.hpp"
#include "vision/node/frame_pose_pairing.hpp"
#include "vision/params.hpp"

namespace alight::autonomy::test {
namespace {

std::string path(const std::string& rel) {
  return std::string(alight::build::source_dir()) + "/" + rel;
}

ClosedLoopConfig config(const std::string& scenario, Mission mission, uint64_t seed,
                        RealVision* vision) {
  ClosedLoopConfig c;
  c.vehicle_file = path("config/vehicles/pelican.yaml");
  c.scenario_file = path("config/scenarios/" + scenario + ".yaml");
  c.mission = mission;
  c.seed = seed;
  c.time_limit_s = 150;
  c.camera_vision = [vision](const sim::CameraFrame& f, const std::optional<PoseSample>& p) {
    return (*vision)(f, p);
  };
  return c;
}

class RealVisionLandingTest : public ::testing::TestWithParam<std::string> {};

TEST_P(RealVisionLandingTest, LandsOnThePlatform) {
  RealVision vision(path("config/vehicles/pelican.yaml"), Mission::kLanding);
  const auto r = fly_closed_loop(config(GetParam(), Mission::kLanding, 7, &vision));
  std::printf(
      "%s: %s, touchdown error %.4f m, estimate error %.4f m (z %+.4f), n %d, "
      "mission %.1f s, vision found %d of %d frames\n",
      GetParam().c_str(), r.reason.c_str(), r.touchdown_error_m, r.estimate_error_W.norm(),
      r.estimate_error_W.z(), r.n_measurements, r.mission_time_s, vision.found, vision.frames);
  EXPECT_EQ(r.phase, Phase::kLanded) << r.reason;
  EXPECT_TRUE(r.landed) << r.reason;
  EXPECT_FALSE(r.tipped);
  EXPECT_LT(r.touchdown_error_m, 0.03);
  EXPECT_LT(std::abs(r.estimate_error_W.z()), 0.01) << "platform height at convergence";
}

INSTANTIATE_TEST_SUITE_P(PapersPlatforms, RealVisionLandingTest,
                         ::testing::Values("landing_a", "landing_b", "landing_c"));

// Where the floor gives little (issue 15): flat grey tiles with features only at their corners.
// Drawn by `scripts/scenes landing_tiles --seed 101` and `--seed 103` (copied here so a change of
// the family does not change the test). With the paper's planes alone
// (vision.landing.floor_prior: off) both failed: the platform was found in 839 of 3022 and 1 of
// 1190 frames, the target lost three times, no landing. The known floor and motion
// (vision/geometry/known_floor.hpp) find the platform where the dominant fit fails.
class RealVisionWeakFloorTest : public ::testing::TestWithParam<std::string> {};

TEST_P(RealVisionWeakFloorTest, LandsOnThePlatformOverTiles) {
  RealVision vision(path("config/vehicles/pelican.yaml"), Mission::kLanding);
  ClosedLoopConfig c = config("landing_a", Mission::kLanding, 7, &vision);
  c.scenario_file = path("test/integration/scenarios/" + GetParam() + ".yaml");
  const auto r = fly_closed_loop(c);
  std::printf(
      "%s: %s, touchdown error %.4f m, estimate error %.4f m (z %+.4f), retries %d, n %d, "
      "mission %.1f s, vision found %d of %d frames\n",
      GetParam().c_str(), r.reason.c_str(), r.touchdown_error_m, r.estimate_error_W.norm(),
      r.estimate_error_W.z(), r.retries, r.n_measurements, r.mission_time_s, vision.found,
      vision.frames);
  EXPECT_EQ(r.phase, Phase::kLanded) << r.reason;
  EXPECT_TRUE(r.landed) << r.reason;
  EXPECT_FALSE(r.tipped);
  EXPECT_LT(r.touchdown_error_m, 0.025);
  EXPECT_LT(r.estimate_error_W.norm(), 0.01) << "platform centre and height at convergence";
}

INSTANTIATE_TEST_SUITE_P(TilesSeeds, RealVisionWeakFloorTest,
                         ::testing::Values("landing_tiles_101", "landing_tiles_103"));

// Close over a top on a bland floor (issue 15): drawn by `scripts/scenes landing_lowtex --seed
// 9917` (copied here), flown with sim seed 1. From 0.75 m down the approach sees the paper top
// alone, no match on the pale floor, and the known floor's pair had no floor: the target counted
// lost in the approach, a retry. The top alone (fit_known_top_alone) keeps it in sight.
TEST(RealVisionCloseViewTest, ApproachKeepsATopThatFillsTheViewOverABlandFloor) {
  RealVision vision(path("config/vehicles/pelican.yaml"), Mission::kLanding);
  ClosedLoopConfig c = config("landing_a", Mission::kLanding, 1, &vision);
  c.scenario_file = path("test/integration/scenarios/landing_lowtex_9917.yaml");
  const auto r = fly_closed_loop(c);
  std::printf(
      "landing_lowtex_9917 seed 1: %s, touchdown error %.4f m, estimate error %.4f m, retries %d, "
      "mission %.1f s, vision found %d of %d frames\n",
      r.reason.c_str(), r.touchdown_error_m, r.estimate_error_W.norm(), r.retries, r.mission_time_s,
      vision.found, vision.frames);
  EXPECT_EQ(r.phase, Phase::kLanded) << r.reason;
  EXPECT_EQ(r.retries, 0) << "the approach lost the top";
  EXPECT_FALSE(r.tipped);
  // One flight's estimate moves with the frames the vision keeps: 0.1, 0.5 and 1.2 cm on three
  // versions of it (the last refuses the frames smeared as refinement moves between vantage
  // points). Its spread over many draws is the families bench's; here: the top, not its edge.
  EXPECT_LT(r.estimate_error_W.norm(), 0.015) << "platform centre and height at convergence";
  // The gusts' share of the touch-down is a matter of their phase in one flight (1.4 cm and
  // 2.9 cm on two feature budgets, the estimate within 0.5 cm both times); its percentiles are
  // measured over many draws (alight_families_bench). Here: on the top, clear of its edges.
  EXPECT_LT(r.touchdown_error_m, 0.04);
}

// Without motion capture (issue 17): the onboard estimator's pose flies the mission, vision
// measures the platform in the estimator's frame, the truth only scores. Relative accuracy is
// what matters: the touch-down is judged against the true platform, the platform estimate through
// the final estimated pose.
class RealVisionNoMocapLandingTest : public ::testing::TestWithParam<uint64_t> {};

TEST_P(RealVisionNoMocapLandingTest, LandsOnPlatformAOnTheOnboardEstimate) {
  RealVision vision(path("config/vehicles/pelican.yaml"), Mission::kLanding);
  ClosedLoopConfig c = config("landing_a", Mission::kLanding, GetParam(), &vision);
  c.onboard_estimate = true;
  const auto r = fly_closed_loop(c);
  std::printf(
      "landing_a seed %d without motion capture: %s, touchdown error %.4f m, relative estimate "
      "error %.4f m (z %+.4f), pose error at the end %.3f m (largest in flight %.3f m, z %.3f m), "
      "retries %d, n %d, mission %.1f s, vision found %d of %d frames, flow fused %lld refused "
      "%lld (on the floor %lld), terrain resets %d, health not OK in %d+%d steps (%s)\n",
      static_cast<int>(GetParam()), r.reason.c_str(), r.touchdown_error_m,
      r.estimate_error_rel_W.norm(), r.estimate_error_rel_W.z(), r.pose_error_W.norm(),
      r.max_pose_error_h_m, r.max_pose_error_z_m, r.retries, r.n_measurements, r.mission_time_s,
      vision.found, vision.frames, static_cast<long long>(r.flow_fused),
      static_cast<long long>(r.flow_rejected), static_cast<long long>(r.flow_on_floor),
      r.terrain_resets, r.estimate_degraded_steps, r.estimate_lost_steps,
      r.estimate_reasons.c_str());
  std::printf(
      "  entering APPROACH: pose error %+.3f %+.3f %+.3f m, relative estimate error %+.3f "
      "%+.3f %+.3f m; at the touch-down %+.3f %+.3f %+.3f m\n",
      r.pose_error_at_approach_W.x(), r.pose_error_at_approach_W.y(),
      r.pose_error_at_approach_W.z(), r.estimate_error_rel_at_approach_W.x(),
      r.estimate_error_rel_at_approach_W.y(), r.estimate_error_rel_at_approach_W.z(),
      r.estimate_error_rel_at_touchdown_W.x(), r.estimate_error_rel_at_touchdown_W.y(),
      r.estimate_error_rel_at_touchdown_W.z());
  EXPECT_EQ(r.phase, Phase::kLanded) << r.reason;
  EXPECT_TRUE(r.landed) << r.reason;
  EXPECT_FALSE(r.tipped);
  EXPECT_LT(r.touchdown_error_m, 0.025);
  // The estimate the landing used: at the end of the flight the estimator has been running on
  // the ground for a while after the motors stopped, and its drift there is no landing's error.
  EXPECT_LT(std::abs(r.estimate_error_rel_at_touchdown_W.z()), 0.02)
      << "platform height at the touch-down";
  EXPECT_LT(r.max_pose_error_h_m, 0.05);
  EXPECT_LT(r.max_pose_error_z_m, 0.04);
  EXPECT_EQ(r.estimate_degraded_steps + r.estimate_lost_steps, 0) << r.estimate_reasons;
}

INSTANTIATE_TEST_SUITE_P(Seeds, RealVisionNoMocapLandingTest, ::testing::Values(1u, 2u));

TEST(RealVisionIngressTest, FliesThroughTheWindowWithoutContact) {
  RealVision vision(path("config/vehicles/pelican.yaml"), Mission::kIngress);
  const auto r = fly_closed_loop(config("ingress_wide", Mission::kIngress, 7, &vision));
  std::printf(
      "ingress_wide: %s, estimate error %.4f m, max offset in the wall %.4f m, n %d, "
      "mission %.1f s, vision found %d of %d frames\n",
      r.reason.c_str(), r.estimate_error_W.norm(), r.max_lateral_in_wall_m, r.n_measurements,
      r.mission_time_s, vision.found, vision.frames);
  EXPECT_EQ(r.phase, Phase::kDone) << r.reason;
  EXPECT_TRUE(r.crossed_wall);
  EXPECT_FALSE(r.collided);
  EXPECT_LT(r.estimate_error_W.norm(), 0.02) << "opening centre";
}

// Ingress without motion capture (issue 17): the simulator renders the forward camera for the
// vision and the downward one for the estimator's flow; vision measures the window in the
// estimator's frame, the vehicle flies through it on the estimate, the truth only scores.
class RealVisionNoMocapIngressTest : public ::testing::TestWithParam<uint64_t> {};

TEST_P(RealVisionNoMocapIngressTest, FliesThroughThe90x60cmWindowOnTheOnboardEstimate) {
  RealVision vision(path("config/vehicles/pelican.yaml"), Mission::kIngress);
  ClosedLoopConfig c = config("ingress_wide", Mission::kIngress, GetParam(), &vision);
  c.onboard_estimate = true;
  const auto r = fly_closed_loop(c);
  const Vector2d off = r.crossing_offset_m.value_or(Vector2d::Constant(NAN));
  std::printf(
      "ingress_wide seed %d without motion capture: %s, crossing offset lateral %+.4f m, "
      "vertical %+.4f m, max offset in the wall %.4f m, relative estimate error %.4f m, pose "
      "error at the crossing %+.3f %+.3f %+.3f m (largest in flight %.3f m, z %.3f m), retries "
      "%d, n %d, mission %.1f s, vision found %d of %d frames, flow fused %lld refused %lld, "
      "terrain resets %d, health not OK in %d+%d steps (%s)\n",
      static_cast<int>(GetParam()), r.reason.c_str(), off.x(), off.y(), r.max_lateral_in_wall_m,
      r.estimate_error_rel_W.norm(), r.pose_error_at_crossing_W.x(), r.pose_error_at_crossing_W.y(),
      r.pose_error_at_crossing_W.z(), r.max_pose_error_h_m, r.max_pose_error_z_m, r.retries,
      r.n_measurements, r.mission_time_s, vision.found, vision.frames,
      static_cast<long long>(r.flow_fused), static_cast<long long>(r.flow_rejected),
      r.terrain_resets, r.estimate_degraded_steps, r.estimate_lost_steps,
      r.estimate_reasons.c_str());
  EXPECT_EQ(r.phase, Phase::kDone) << r.reason;
  EXPECT_TRUE(r.crossed_wall);
  ASSERT_TRUE(r.crossing_offset_m.has_value());
  EXPECT_FALSE(r.collided);
  EXPECT_EQ(r.n_collisions, 0);
  // The pelican's 67 cm rotor span in the 90 cm window leaves 11.5 cm each side.
  EXPECT_LT(std::abs(off.x()), 0.06);
  EXPECT_LT(std::abs(off.y()), 0.06);
  EXPECT_LT(r.estimate_error_rel_W.norm(), 0.05) << "opening centre relative to the vehicle";
  EXPECT_LT(r.max_pose_error_h_m, 0.10);
  EXPECT_LT(r.max_pose_error_z_m, 0.05);
  EXPECT_EQ(r.estimate_lost_steps, 0) << r.estimate_reasons;
}

INSTANTIATE_TEST_SUITE_P(Seeds, RealVisionNoMocapIngressTest, ::testing::Values(1u, 2u));

// No false target (issue 6): whole flights with real vision over the bare floor and along the
// solid wall. The whole search path is flown once without a single detection, and autonomy, with
// no retry left, ends in HOLD with nothing measured. A retry flies the same path over the same
// scene again (autonomy_test covers the retries and the hold after the last): each pass would
// double the test's time and not its coverage.
class RealVisionNoTargetTest : public ::testing::TestWithParam<std::tuple<std::string, Mission>> {};

TEST_P(RealVisionNoTargetTest, WholeSearchWithoutASingleDetection) {
  const auto& [scenario, mission] = GetParam();
  RealVision vision(path("config/vehicles/pelican.yaml"), mission);
  ClosedLoopConfig c = config(scenario, mission, 7, &vision);
  c.detection_max_retries = 0;
  const auto r = fly_closed_loop(c);
  std::printf("%s: %s, %s after %.1f s, retries %d, vision found %d of %d frames\n",
              scenario.c_str(), phase_name(r.phase), r.reason.c_str(), r.sim_time_s, r.retries,
              vision.found, vision.frames);
  EXPECT_EQ(vision.found, 0);
  EXPECT_EQ(r.n_measurements, 0);
  EXPECT_EQ(r.phase, Phase::kHold) << r.reason;  // the search flown, nothing seen
  EXPECT_NE(r.reason.find("search path flown without a detection"), std::string::npos) << r.reason;
  EXPECT_FALSE(r.collided);
}

INSTANTIATE_TEST_SUITE_P(BareFloorAndSolidWall, RealVisionNoTargetTest,
                         ::testing::Values(std::make_tuple("landing_none", Mission::kLanding),
                                           std::make_tuple("ingress_solid", Mission::kIngress)));

// Regression, landing_none_photo 9760 (issue 15): at the search path's first turn, frames
// exposed for 10.8 ms through the turn's pitch smeared the photographed floor 13-30 px; their
// matches made a "top" 37 cm up, found, and autonomy went into refinement. Which frame of a
// flight smears into a false top is a matter of micrometres (the flight that showed it, replayed
// with its poses rounded to 10 um, shows none), so the floor (`scripts/scenes landing_none_photo
// --seed 9760`, copied here) is seen along set trajectories instead of a flown one: the vehicle
// crosses it at search speed and height while pitching back and forth as through turns, the
// simulator following them as it follows an autopilot's SITL. With landing.max_motion_blur_px
// no frame shows a top; without it some do, which is what makes this test catch the bug.
struct Swing {
  double pitch_deg, hz;
};

sim::VehicleState swinging(const Swing& swing, int64_t since_start_us) {
  constexpr double kSpeedMps = 0.5, kHeightM = 1.2;  // the search's (landing_none.yaml)
  const double t = 1e-6 * static_cast<double>(since_start_us);
  const double a = swing.pitch_deg * M_PI / 180, w = 2 * M_PI * swing.hz;
  sim::VehicleState st;
  st.armed = true;
  st.p_W_B = Vector3d(kSpeedMps * t - 1.0, 0.0, kHeightM);
  st.v_W_B = Vector3d(kSpeedMps, 0.0, 0.0);
  st.q_WB = Quaterniond(Eigen::AngleAxisd(a * std::sin(w * t), Vector3d::UnitY()));
  st.omega_B = Vector3d(0.0, a * w * std::cos(w * t), 0.0);
  return st;
}

/// Frames in which the vision found the landing target or a partial view of it, seen along
/// `state_at` (time since the start) for `duration_us`.
int tops_seen_along(const std::string& scenario_file,
                    const std::function<sim::VehicleState(int64_t)>& state_at, int64_t duration_us,
                    uint64_t seed, RealVision& vision) {
  const std::string vehicle_file = path("config/vehicles/pelican.yaml");
  sim::Simulator simulator(sim::load_scenario(scenario_file),
                           sim::load_vehicle_params(vehicle_file), seed,
                           sim::load_camera_rig(vehicle_file, "downward"));
  // The vision node's frame-to-pose policy (vision/node/frame_pose_pairing.hpp).
  vision::FramePosePairing<sim::CameraFrame> frames(PoseBufferParams{}, 100'000);
  int tops = 0;
  constexpr double kContactMarginM = 0.002;  // the trajectories stay well clear of the floor
  const int64_t t0 = simulator.now_utime();
  for (int64_t t = t0; t < t0 + duration_us; t += 5000) {
    simulator.follow([&](int64_t u) { return state_at(u - t0); }, t + 5000, kContactMarginM);
    for (const auto& m : simulator.take_mocap()) frames.add_pose(m.pose);
    if (auto f = simulator.take_camera()) {
      const int64_t exposure_utime = f->utime;
      frames.add_frame(std::move(*f), exposure_utime);
    }
    while (const auto ready = frames.poll()) {
      const auto m = vision(ready->frame, ready->pose);
      if (m && (m->found || m->partial)) ++tops;
    }
  }
  return tops;
}

TEST(RealVisionBareFloorTest, NoFalseTopFromFramesSmearedAtTheSearchPathsTurn) {
  const auto tops_seen = [](const Swing& swing, bool guarded) {
    RealVision vision(path("config/vehicles/pelican.yaml"), Mission::kLanding,
                      [&](vision::PipelineParams& p) {
                        if (!guarded) p.landing.max_motion_blur_px = 0;  // off
                      });
    const int tops = tops_seen_along(
        path("test/integration/scenarios/landing_none_photo_9760.yaml"),
        [&](int64_t u) { return swinging(swing, u); }, 6'000'000, 9760, vision);
    std::printf(
        "landing_none_photo_9760, pitching +-%g deg at %g Hz, max_motion_blur_px %s: "
        "a top in %d of %d frames\n",
        swing.pitch_deg, swing.hz, guarded ? "default" : "0 (off)", tops, vision.frames);
    EXPECT_GT(vision.frames, 150);
    return tops;
  };
  // Peak pitch rates 1.6-2.6 rad/s, as through the search path's turns.
  int unguarded = 0;
  for (const Swing swing : {Swing{10, 1.5}, Swing{10, 2}, Swing{8, 3}}) {
    EXPECT_EQ(tops_seen(swing, true), 0);
    unguarded += tops_seen(swing, false);
  }
  EXPECT_GT(unguarded, 0) << "smeared frames no longer give a false top: the test tests nothing";
}

}  // namespace
}  // namespace alight::autonomy::test
