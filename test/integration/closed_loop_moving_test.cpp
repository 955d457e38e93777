// Closed loop in-process with real vision onto a MOVING platform: the shipped cart
// (config/scenarios/landing_moving_cart.yaml, 1 m/s round a stadium) and deck (landing_deck.yaml,
// 0.5 m/s, heave, roll and pitch). The vision measures the moving top (VISION_PLATFORM, through
// the node's and autonomy's conversions), autonomy's platform filter and moving approach follow
// it and time the last drop to the deck's heave. Lockstep and deterministic, as
// closed_loop_vision_test.
#include <gtest/gtest.h>

#include "closed_loop.hpp"
#include "real_vision.hpp"

namespace alight::autonomy::test {
namespace {

std::string path(const std::string& rel) { return std::string(ALIGHT_SOURCE_DIR) + "/" + rel; }

struct Case {
  std::string scenario;
  uint64_t seed;
};

class MovingPlatformLandingTest : public ::testing::TestWithParam<Case> {};

TEST_P(MovingPlatformLandingTest, LandsOnThePlatformWhileItMoves) {
  RealVision vision(path("config/vehicles/pelican.yaml"), Mission::kLanding);
  ClosedLoopConfig c;
  c.vehicle_file = path("config/vehicles/pelican.yaml");
  c.scenario_file = path("config/scenarios/" + GetParam().scenario + ".yaml");
  c.mission = Mission::kLanding;
  c.seed = GetParam().seed;
  c.time_limit_s = 150;
  c.camera_vision = [&vision](const sim::CameraFrame& f, const std::optional<PoseSample>& p) {
    return vision(f, p);
  };
  c.camera_platform = [&vision] { return vision.take_platform(); };
  const auto r = fly_closed_loop(c);
  std::printf(
      "%s seed %llu: %s, touchdown error %.4f m relative to the platform (at the detected "
      "touch-down %.4f), heading error %.1f deg, contact relative vz %+.2f m/s, mission %.1f s, "
      "platform measured in %d of %d frames\n",
      GetParam().scenario.c_str(), static_cast<unsigned long long>(GetParam().seed),
      r.reason.c_str(), r.touchdown_error_m, r.error_at_touchdown_m,
      r.heading_error_at_touchdown_deg, r.contact_rel_vz_mps, r.mission_time_s,
      vision.platform_found, vision.frames);
  EXPECT_EQ(r.phase, Phase::kLanded) << r.reason;
  EXPECT_TRUE(r.landed) << r.reason;
  EXPECT_FALSE(r.tipped);
  EXPECT_TRUE(r.on_platform_top);
  EXPECT_GT(vision.platform_found, 0);
  // On the top, well inside its half width (0.14 m for the shipped platform).
  EXPECT_LT(r.touchdown_error_m, 0.10);
}

INSTANTIATE_TEST_SUITE_P(CartAndDeck, MovingPlatformLandingTest,
                         ::testing::Values(Case{"landing_moving_cart", 7}, Case{"landing_deck", 7}),
                         [](const auto& info) { return info.param.scenario; });

}  // namespace
}  // namespace alight::autonomy::test
