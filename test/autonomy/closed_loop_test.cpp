// Closed loop in-process: alight_sim + outer loop + autonomy + oracle vision (test fixture).
// A few seeds per case to keep ctest short; bench/autonomy runs 20 seeds per platform and
// prints the touchdown error distribution and mission times.

#include "closed_loop.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "common/build_paths.hpp"

namespace alight::autonomy::test {
namespace {

std::string path(const std::string& rel) {
  return std::string(alight::build::source_dir()) + "/" + rel;
}

ClosedLoopConfig landing(const std::string& vehicle, const std::string& platform, uint64_t seed) {
  ClosedLoopConfig c;
  c.vehicle_file = path("config/vehicles/" + vehicle + ".yaml");
  c.scenario_file = path("config/scenarios/landing_" + platform + ".yaml");
  c.mission = Mission::kLanding;
  c.seed = seed;
  return c;
}

void expect_landed(const ClosedLoopResult& r, const std::string& what) {
  EXPECT_EQ(r.phase, Phase::kLanded) << what << ": " << r.reason;
  EXPECT_TRUE(r.landed) << what << ": " << r.reason;
  EXPECT_FALSE(r.tipped) << what;
  EXPECT_FALSE(r.armed) << what;
  EXPECT_LT(r.touchdown_error_m, 0.05) << what;
}

class ClosedLoopLandingTest
    : public ::testing::TestWithParam<std::tuple<std::string, std::string>> {};

TEST_P(ClosedLoopLandingTest, LandsOnThePlatformWithinCentimetres) {
  const auto& [vehicle, platform] = GetParam();
  std::vector<double> errors;
  for (uint64_t seed : {1, 2, 3}) {
    const auto r = fly_closed_loop(landing(vehicle, platform, seed));
    expect_landed(r, vehicle + "/" + platform + " seed " + std::to_string(seed));
    errors.push_back(r.touchdown_error_m);
  }
  std::sort(errors.begin(), errors.end());
  EXPECT_LE(errors[1], 0.03) << "median touchdown lateral error";
}

INSTANTIATE_TEST_SUITE_P(PapersPlatforms, ClosedLoopLandingTest,
                         ::testing::Combine(::testing::Values("starmac", "pelican"),
                                            ::testing::Values("a", "b", "c")));

}  // namespace
}  // namespace alight::autonomy::test

namespace alight::autonomy::test {
namespace {

ClosedLoopConfig ingress(const std::string& vehicle, uint64_t seed) {
  ClosedLoopConfig c;
  c.vehicle_file = path("config/vehicles/" + vehicle + ".yaml");
  c.scenario_file = path("config/scenarios/ingress.yaml");
  c.mission = Mission::kIngress;
  c.seed = seed;
  return c;
}

OperatorCommand operator_command(Command command) {
  OperatorCommand c;
  c.command = command;
  c.sender = "gs";
  // As the node passes it on once CommandVerifier accepted the ground station's signature.
  c.auth = CommandAuth::kVerified;
  return c;
}

// Issue 15 (landing_lowtex 9926, 9937; landing_photo 9968): at the impact in a wind the gear
// levelled the tilted body and, the thrust still near hover until the land detector's verdict,
// the wind slid the near-weightless vehicle 1-1.3 cm across the top. With the outer loop's
// land_contact_cut the thrust goes as the ground holds the vehicle up, and the friction of its
// weight holds it. Flown on platform a) in a 0.9 m/s wind with gusts, four seeds; the slide is
// the body's travel from the detected touch-down to rest (the impact's own kick included).
std::vector<double> slides_m(const std::string& vehicle_file) {
  std::vector<double> slides;
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    ClosedLoopConfig c = landing("pelican", "a", seed);
    c.vehicle_file = vehicle_file;
    c.scenario_file = path("test/integration/scenarios/landing_a_gusts.yaml");
    const auto r = fly_closed_loop(c);
    expect_landed(r, "seed " + std::to_string(seed));
    slides.push_back((r.final_p_W - r.p_W_at_touchdown).head<2>().norm());
  }
  return slides;
}

TEST(ClosedLoopGustTest, TheVehicleDoesNotSlideAfterATouchDownInTheWind) {
  const auto with = slides_m(path("config/vehicles/pelican.yaml"));
  // The same flights with the thrust left to the land detector.
  std::ifstream in(path("config/vehicles/pelican.yaml"));
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string on = "land_contact_cut: true";
  ASSERT_NE(text.find(on), std::string::npos);
  text.replace(text.find(on), on.size(), "land_contact_cut: false");
  // In a temporary folder (never beside the shipped files, which other tests list), its camera
  // files named by their full path.
  for (size_t at; (at = text.find("../cameras/")) != std::string::npos;)
    text.replace(at, 11, path("config/cameras/"));
  const std::string off_file =
      (std::filesystem::temp_directory_path() /
       ("alight_closed_loop_gust_test_" + std::to_string(::getpid()) + ".yaml"))
          .string();
  std::ofstream(off_file) << text;
  const auto without = slides_m(off_file);
  std::remove(off_file.c_str());
  ASSERT_EQ(with.size(), without.size());
  // How far one flight slides without the cut depends on the gust's phase at the impact: per
  // flight the cut never slides further, and over the four it takes millimetres off the mean.
  double sum_with = 0, sum_without = 0;
  for (size_t i = 0; i < with.size(); ++i) {
    EXPECT_LT(with[i], without[i]) << "seed " << i + 1 << ": the cut stops the slide";
    sum_with += with[i], sum_without += without[i];
  }
  EXPECT_LT(sum_with / 4 + 0.003, sum_without / 4) << "the mean slide";
  EXPECT_LT(*std::max_element(with.begin(), with.end()), 0.012) << "the impact's kick alone";
}

TEST(ClosedLoopIngressTest, FliesThroughAnOpeningThatFitsWithoutContact) {
  // Both simulated vehicles span more than 60 cm rotor tip to rotor tip (STARMAC 0.75 m,
  // Pelican 0.67 m), so the paper's 60 x 60 cm opening is refused (next test); a 1.0 x 0.6 m
  // window fits with 5 cm clearance per side for the STARMAC.
  for (uint64_t seed : {1, 2, 3}) {
    auto c = ingress("starmac", seed);
    c.opening_size_m = Vector2d(1.0, 0.6);
    const auto r = fly_closed_loop(c);
    const std::string what = "seed " + std::to_string(seed);
    EXPECT_EQ(r.phase, Phase::kDone) << what << ": " << r.reason;
    EXPECT_TRUE(r.crossed_wall) << what;
    EXPECT_FALSE(r.collided) << what << ": " << r.n_collisions << " contacts";
    EXPECT_GT(r.final_p_W.x(), 3.5) << what;
    EXPECT_LT(r.max_lateral_in_wall_m, 0.06) << what;
  }
}

TEST(ClosedLoopIngressTest, FliesThroughThePapers60cmOpeningWithASmallerVehicle) {
  // The STARMAC model with its rotor span cut to 0.45 m (7.5 cm clearance per side).
  for (uint64_t seed : {1, 2, 3}) {
    auto c = ingress("starmac", seed);
    c.rotor_span_m = 0.45;
    const auto r = fly_closed_loop(c);
    const std::string what = "seed " + std::to_string(seed);
    EXPECT_EQ(r.phase, Phase::kDone) << what << ": " << r.reason;
    EXPECT_TRUE(r.crossed_wall) << what;
    EXPECT_FALSE(r.collided) << what << ": " << r.n_collisions << " contacts";
    EXPECT_LT(r.max_lateral_in_wall_m, 0.05) << what;
  }
}

TEST(ClosedLoopIngressTest, RefusesThePapers60cmOpeningForAVehicleThatDoesNotFit) {
  const auto r = fly_closed_loop(ingress("pelican", 1));
  EXPECT_EQ(r.phase, Phase::kHold) << r.reason;
  EXPECT_NE(r.reason.find("refused ingress"), std::string::npos) << r.reason;
  EXPECT_FALSE(r.collided);
  EXPECT_FALSE(r.crossed_wall);
}

TEST(ClosedLoopFailsafeTest, MocapDropoutMidDescentDescendsAndDisarmsOnTouchdown) {
  auto c = landing("starmac", "b", 4);
  bool dropped = false;
  c.script = [&](const Autonomy& a, double, ScriptActions& act) {
    if (!dropped && a.phase() == Phase::kApproach && act.p_W_true.z() < 0.9) {  // mid-descent
      act.drop_mocap_for_s = 1000.0;
      dropped = true;
    }
  };
  const auto r = fly_closed_loop(c);
  EXPECT_TRUE(dropped);
  EXPECT_EQ(r.phase, Phase::kFailsafe) << r.reason;
  EXPECT_NE(r.reason.find("touch-down"), std::string::npos) << r.reason;
  EXPECT_FALSE(r.armed) << "disarmed on touch-down";
  EXPECT_FALSE(r.tipped);
  EXPECT_LT(r.final_z_m, 0.5) << "on the platform or the floor";
}

TEST(ClosedLoopFailsafeTest, AbortMidDescentClimbsToTheSafeHeightAndHovers) {
  auto c = landing("pelican", "a", 5);
  bool sent = false;
  c.script = [&](const Autonomy& a, double, ScriptActions& act) {
    if (!sent && a.phase() == Phase::kApproach && act.p_W_true.z() < 0.9) {  // mid-descent
      act.command = operator_command(Command::kAbort);
      sent = true;
    }
  };
  const auto r = fly_closed_loop(c);
  EXPECT_TRUE(sent);
  EXPECT_EQ(r.phase, Phase::kHold) << r.reason;
  EXPECT_TRUE(r.armed);
  EXPECT_LT(r.min_z_after_event_m, 0.9) << "it was descending";
  EXPECT_NEAR(r.final_z_m, 1.5, 0.1) << "abort_height_m";
}

TEST(ClosedLoopFailsafeTest, VisionSilenceInRefinementRetriesThenHolds) {
  auto c = landing("starmac", "c", 6);
  c.script = [&](const Autonomy& a, double, ScriptActions& act) {
    if (a.phase() == Phase::kRefinement) act.vision_silent = true;
  };
  const auto r = fly_closed_loop(c);
  EXPECT_EQ(r.phase, Phase::kHold) << r.reason;
  // The target is lost in refinement and detection retried; with no VISION_TARGET at all for
  // failsafe.vision_silent_s it holds and names the cause (it used to fly the whole search path
  // once per retry until "retries exhausted").
  EXPECT_NE(r.reason.find("no VISION_TARGET"), std::string::npos) << r.reason;
  EXPECT_TRUE(r.armed);
  EXPECT_GT(r.final_z_m, 1.0);
}

TEST(ClosedLoopFailsafeTest, KillStopsTheMotorsAtOnce) {
  auto c = landing("pelican", "b", 7);
  bool sent = false;
  c.script = [&](const Autonomy& a, double, ScriptActions& act) {
    if (!sent && a.phase() == Phase::kRefinement) {
      act.command = operator_command(Command::kKill);
      sent = true;
    }
  };
  const auto r = fly_closed_loop(c);
  EXPECT_EQ(r.phase, Phase::kKilled);
  EXPECT_FALSE(r.armed);
  EXPECT_LT(r.final_z_m, 0.3) << "fell";
}

// Issue 17: the onboard estimate's health with the simulator and the real outer loop. The
// pose is motion capture's here, standing in for the one the estimator dead-reckons.
EstimateHealth estimate_health(EstimateHealth::Level level, uint32_t reasons, const char* text) {
  EstimateHealth e;
  e.level = level;
  e.reasons = reasons;
  e.text = text;
  return e;
}

TEST(ClosedLoopEstimateTest, LostMidDescentDescendsAndDisarmsOnTouchdown) {
  auto c = landing("pelican", "a", 8);
  bool lost = false;
  c.script = [&](const Autonomy& a, double, ScriptActions& act) {
    if (!act.estimate) act.estimate = estimate_health(EstimateHealth::Level::kOk, 0, "");
    if (!lost && a.phase() == Phase::kApproach && act.p_W_true.z() < 0.9) {  // mid-descent
      act.estimate = estimate_health(EstimateHealth::Level::kLost, 16, "position_uncertain");
      lost = true;
    }
  };
  const auto r = fly_closed_loop(c);
  EXPECT_TRUE(lost);
  EXPECT_EQ(r.phase, Phase::kFailsafe) << r.reason;
  EXPECT_NE(r.reason.find("touch-down"), std::string::npos) << r.reason;
  EXPECT_FALSE(r.armed) << "disarmed on touch-down";
  EXPECT_FALSE(r.tipped);
  EXPECT_LT(r.final_z_m, 0.5) << "on the platform or the floor";
}

TEST(ClosedLoopEstimateTest, DegradedInRefinementHoldsInTheAir) {
  auto c = landing("starmac", "b", 9);
  c.script = [&](const Autonomy& a, double, ScriptActions& act) {
    if (!act.estimate) act.estimate = estimate_health(EstimateHealth::Level::kOk, 0, "");
    if (a.phase() == Phase::kRefinement)
      act.estimate = estimate_health(EstimateHealth::Level::kDegraded, 2, "no_flow");
  };
  const auto r = fly_closed_loop(c);
  EXPECT_EQ(r.phase, Phase::kHold) << r.reason;
  EXPECT_NE(r.reason.find("state estimate degraded (no_flow): holding"), std::string::npos)
      << r.reason;
  EXPECT_TRUE(r.armed);
  EXPECT_GT(r.final_z_m, 1.0);
  EXPECT_FALSE(r.collided);
}

}  // namespace
}  // namespace alight::autonomy::test
