// The autonomy: sections of the vehicle files load and validate; errors name file and key.

#include "autonomy/params.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "common/build_paths.hpp"
#include "outer_loop/params.hpp"
#include "test/common/expect_param_error.hpp"

namespace alight::autonomy {
namespace {

// The value in an error is as written for a non-finite one (refused at the read), as the number
// it is otherwise (refused by validate(): 1e-7 reads back as 1e-07).
void expect_value(const ParamError& e, const std::string& written) {
  const double want = YAML::Load(written).as<double>();
  if (std::isfinite(want)) {
    EXPECT_DOUBLE_EQ(std::stod(e.value()), want) << e.what();
  } else {
    EXPECT_EQ(e.value(), written) << e.what();
  }
}

TEST(AutonomyParamsTest, VehicleFilesLoadWithThePapersThresholds) {
  for (const char* v : {"starmac", "pelican"}) {
    const std::string path =
        std::string(alight::build::source_dir()) + "/config/vehicles/" + v + ".yaml";
    const auto p = load_params(path);
    EXPECT_FALSE(p.accept_unsigned_commands) << v << ": anyone on the LAN could command it";
    EXPECT_TRUE(p.operator_key_file.empty()) << v << ": keys are made per vehicle, not shipped";
    EXPECT_DOUBLE_EQ(p.command_max_age_s, 2.0) << v;
    EXPECT_DOUBLE_EQ(p.failsafe.pose_stale_s, 0.3) << v;
    EXPECT_DOUBLE_EQ(p.failsafe.pose_lost_s, 1.0) << v;
    EXPECT_DOUBLE_EQ(p.landing.gear_footprint_m, 0.15) << v;
    EXPECT_LE(p.status_period_s, 0.1) << v;
    // The downward camera's view, derived from cameras.downward (the Firefly's 640 x 480).
    ASSERT_TRUE(p.downward_view) << v;
    EXPECT_NEAR(p.downward_view->tan_long, (320 - kViewBorderPx) / 666.667, 1e-6) << v;
    EXPECT_NEAR(p.downward_view->tan_short, (240 - kViewBorderPx) / 666.667, 1e-6) << v;
  }
  EXPECT_FALSE(load_params(ParamNode::from_string("autonomy: {}", "v.yaml")).downward_view);
}

TEST(AutonomyParamsTest, ErrorsNameTheNestedKey) {
  try {
    load_params(ParamNode::from_string("autonomy: {refinement: {n_min: -3}}", "v.yaml"));
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_EQ(e.key(), "autonomy.refinement.n_min");
    EXPECT_EQ(e.value(), "-3");
    EXPECT_EQ(e.file(), "v.yaml");
  }
  EXPECT_THROW(load_params(ParamNode::from_string("autonomy: {landing: {v_des: 1}}", "v.yaml")),
               ParamError);
  EXPECT_THROW(load_params(ParamNode::from_string("autonomy: {status_period_s: 0.5}", "v.yaml")),
               ParamError);
}

TEST(AutonomyParamsTest, TheFinalHoldAndPauseAreCheckedAtTheirFullKeys) {
  const auto expect_refused = [](const std::string& landing, const std::string& key) {
    try {
      load_params(ParamNode::from_string("autonomy: {landing: {" + landing + "}}", "v.yaml"));
      ADD_FAILURE() << landing;
    } catch (const ParamError& e) {
      EXPECT_EQ(e.key(), key) << e.what();
      EXPECT_EQ(e.file(), "v.yaml");
    }
  };
  // A pause waits for the hold's calm moment: without the hold there is none to wait for.
  expect_refused("final_pause_radial_m: 0.012", "autonomy.landing.final_pause_radial_m");
  // Within the calm radius the pause would end as it began.
  expect_refused(
      "final_hold_speed_mps: 0.02, final_hold_radial_m: 0.01, final_pause_radial_m: 0.008",
      "autonomy.landing.final_pause_radial_m");
  expect_refused("final_pause_min_height_m: 0.3", "autonomy.landing.final_pause_min_height_m");
  // The hold's speed bound grows, never shrinks.
  expect_refused("final_hold_speed_mps: 0.05, final_hold_speed_max_mps: 0.02",
                 "autonomy.landing.final_hold_speed_max_mps");
  const auto p = load_params(ParamNode::from_string(
      "autonomy: {landing: {final_hold_speed_mps: 0.02, final_pause_radial_m: 0.012, "
      "final_pause_min_height_m: 0.1}}",
      "v.yaml"));
  EXPECT_DOUBLE_EQ(p.landing.final_pause_radial_m, 0.012);
  EXPECT_DOUBLE_EQ(p.landing.final_pause_min_height_m, 0.1);
}

TEST(AutonomyParamsTest, UnsignedCommandsAreRefusedByDefault) {
  const auto p = load_params(ParamNode::from_string("autonomy: {}", "v.yaml"));
  EXPECT_FALSE(p.accept_unsigned_commands);
}

// Bug: command_max_age_s: 1e-7 reached the verifier's assert (SIGABRT, exit 134, restarted by
// the launcher forever). Now a ParamError (exit 2) naming file, key and value.
TEST(AutonomyParamsRegression, TinyCommandMaxAgeIsAParamErrorNotAnAssert) {
  for (const char* v : {"1e-7", "0", "-1", "1e9", ".inf", ".nan"}) {
    try {
      load_params(ParamNode::from_string(std::string("autonomy: {command_max_age_s: ") + v + "}",
                                         "v.yaml"));
      ADD_FAILURE() << v << " accepted";
    } catch (const ParamError& e) {
      EXPECT_EQ(e.file(), "v.yaml") << v;
      EXPECT_EQ(e.key(), "autonomy.command_max_age_s") << v;
      expect_value(e, v);
    }
  }
}

// Bug: `.inf` loaded for pose_lost_s (and every other timeout): the failsafe never fired.
TEST(AutonomyParamsRegression, InfiniteOrHugeTimeoutsAreRefusedNamingTheKey) {
  const std::vector<std::pair<std::string, std::string>> timeouts = {
      {"failsafe", "pose_stale_s"},      {"failsafe", "pose_lost_s"},
      {"refinement", "vantage_dwell_s"}, {"refinement", "vantage_timeout_s"},
      {"refinement", "lost_timeout_s"},  {"refinement", "max_time_s"},
      {"landing", "touchdown_still_s"},  {"landing", "lost_timeout_s"},
      {"ingress", "align_settle_s"},     {"ingress", "lost_timeout_s"},
      {"restart", "state_max_age_s"},    {"", "status_period_s"},
      {"", "command_max_age_s"},         {"failsafe", "estimate_silent_s"}};
  for (const auto& [section, key] : timeouts) {
    const std::string full = "autonomy." + (section.empty() ? key : section + "." + key);
    for (const char* v : {".inf", ".nan", "1e7"}) {
      const std::string yaml = section.empty()
                                   ? "autonomy: {" + key + ": " + v + "}"
                                   : "autonomy: {" + section + ": {" + key + ": " + v + "}}";
      try {
        load_params(ParamNode::from_string(yaml, "v.yaml"));
        ADD_FAILURE() << full << " = " << v << " accepted";
      } catch (const ParamError& e) {
        EXPECT_EQ(e.key(), full) << v << ": " << e.what();
        expect_value(e, v);
        EXPECT_EQ(e.file(), "v.yaml");
      }
    }
  }
}

// Every number must be finite, not only the timeouts (an infinite geofence clamps nothing).
TEST(AutonomyParamsRegression, NonFiniteNumbersAreRefusedNamingTheKey) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"autonomy: {geofence: {max_W_m: [3, .inf, 2.5]}}", "autonomy.geofence.max_W_m"},
      {"autonomy: {detection: {landing_area_max_W_m: [.nan, 1]}}",
       "autonomy.detection.landing_area_max_W_m"},
      {"autonomy: {takeoff: {reached_tol_m: .inf}}", "autonomy.takeoff.reached_tol_m"},
      {"autonomy: {refinement: {gate_chi2: .inf}}", "autonomy.refinement.gate_chi2"},
      {"autonomy: {hover_tol_m: .nan}", "autonomy.hover_tol_m"},
      {"autonomy: {failsafe: {max_nudge_m: .inf}}", "autonomy.failsafe.max_nudge_m"},
      {"autonomy: {restart: {airborne_height_m: .inf}}", "autonomy.restart.airborne_height_m"}};
  for (const auto& [yaml, key] : cases) {
    try {
      load_params(ParamNode::from_string(yaml, "v.yaml"));
      ADD_FAILURE() << yaml << " accepted";
    } catch (const ParamError& e) {
      EXPECT_EQ(e.key(), key) << e.what();
    }
  }
}

// Issue 17: the onboard estimate's parameters, at their full keys.
TEST(AutonomyParamsTest, EstimateHealthParametersLoadAndAreCheckedAtTheirFullKeys) {
  const auto defaults = load_params(ParamNode::from_string("autonomy: {}", "v.yaml"));
  EXPECT_DOUBLE_EQ(defaults.failsafe.estimate_silent_s, 0.5);
  EXPECT_FALSE(defaults.failsafe.require_estimate) << "flights on motion capture need none";
  const auto set = load_params(ParamNode::from_string(
      "autonomy: {failsafe: {estimate_silent_s: 0.2, require_estimate: true}}", "v.yaml"));
  EXPECT_DOUBLE_EQ(set.failsafe.estimate_silent_s, 0.2);
  EXPECT_TRUE(set.failsafe.require_estimate);
  for (const auto& [yaml, key] : std::vector<std::pair<std::string, std::string>>{
           {"autonomy: {failsafe: {estimate_silent_s: 0}}", "autonomy.failsafe.estimate_silent_s"},
           {"autonomy: {failsafe: {estimate_silent_s: -1}}", "autonomy.failsafe.estimate_silent_s"},
           {"autonomy: {failsafe: {estimate_silent_s: 6}}", "autonomy.failsafe.estimate_silent_s"},
           {"autonomy: {failsafe: {require_estimate: maybe}}",
            "autonomy.failsafe.require_estimate"},
           {"autonomy: {failsafe: {require_estimate: 0.5}}",
            "autonomy.failsafe.require_estimate"}}) {
    try {
      load_params(ParamNode::from_string(yaml, "v.yaml"));
      ADD_FAILURE() << yaml << " accepted";
    } catch (const ParamError& e) {
      EXPECT_EQ(e.key(), key) << e.what();
      EXPECT_EQ(e.file(), "v.yaml");
    }
  }
  // The shipped vehicles fly on motion capture: no estimate required.
  for (const char* v : {"starmac", "pelican"}) {
    const auto p =
        load_params(std::string(alight::build::source_dir()) + "/config/vehicles/" + v + ".yaml");
    EXPECT_FALSE(p.failsafe.require_estimate) << v;
    EXPECT_DOUBLE_EQ(p.failsafe.estimate_silent_s, 0.5) << v;
  }
}

TEST(AutonomyParamsTest, TheFollowedPlatformSpeedDerivesFromTheOuterLoopsLimit) {
  // The shipped vehicles follow a setpoint's velocity up to 2 m/s: a platform up to 1.6 m/s.
  for (const char* v : {"starmac", "pelican"}) {
    const auto p =
        load_params(std::string(alight::build::source_dir()) + "/config/vehicles/" + v + ".yaml");
    EXPECT_DOUBLE_EQ(p.moving_platform.max_speed_mps, 1.6) << v;
  }
  const auto slow = load_params(
      ParamNode::from_string("autonomy: {}\nouter_loop: {max_feedforward_xy_mps: 1.0}", "v.yaml"));
  EXPECT_DOUBLE_EQ(slow.moving_platform.max_speed_mps, followed_speed_mps(1.0));
  EXPECT_LT(slow.moving_platform.max_speed_mps, 1.0);
  // Without the key: the outer loop's default (2 m/s). Declared once: the outer loop's key, not
  // one of autonomy's own.
  EXPECT_DOUBLE_EQ(
      load_params(ParamNode::from_string("autonomy: {}", "v.yaml")).moving_platform.max_speed_mps,
      followed_speed_mps(outer_loop::OuterLoopParams{}.max_feedforward_xy_mps));
  EXPECT_THROW(load_params(ParamNode::from_string("autonomy: {moving_platform: {max_speed_mps: 3}}",
                                                  "v.yaml")),
               ParamError);
  try {
    load_params(
        ParamNode::from_string("autonomy: {}\nouter_loop: {max_feedforward_xy_mps: -1}", "v.yaml"));
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_EQ(e.key(), "outer_loop.max_feedforward_xy_mps");
    EXPECT_EQ(e.file(), "v.yaml");
  }
}

// A site narrows both geofences to the room flown in: the shipped vehicle's reaches x = 4.5 m
// for the ingress room behind its wall, the landing room's wall stands at x = 3 m.
TEST(SiteTest, TheLandingRoomNarrowsTheVehiclesGeofencesTheIngressRoomLeavesThem) {
  const std::string root = alight::build::source_dir();
  const std::string vehicle = root + "/config/vehicles/pelican.yaml";
  const std::string landing = root + "/config/scenarios/landing_moving_cart.yaml";
  const std::string ingress = root + "/config/scenarios/ingress.yaml";
  AutonomyParams au = load_params(vehicle);
  outer_loop::OuterLoopParams ol = outer_loop::load_params(vehicle);
  const AutonomyParams au_vehicle = au;
  const outer_loop::OuterLoopParams ol_vehicle = ol;
  ASSERT_GT(au.geofence.max_W_m.x(), 4.0);

  fit_to_site(au, load_site(landing), landing);
  outer_loop::fit_to_site(ol, load_site(landing), landing);
  EXPECT_DOUBLE_EQ(au.geofence.max_W_m.x(), 3.0 - kSiteWallClearanceM);
  EXPECT_DOUBLE_EQ(ol.geofence_max_W_m.x(), 3.0);
  // The outer loop keeps its setpoints as far inside its fence as the autonomy keeps its own
  // inside the walls: both stop at the same place.
  EXPECT_DOUBLE_EQ(ol.geofence_max_W_m.x() - outer_loop::kFenceInsetM, au.geofence.max_W_m.x());
  EXPECT_EQ(au.geofence.min_W_m, au_vehicle.geofence.min_W_m);
  EXPECT_EQ(au.geofence.max_W_m.z(), au_vehicle.geofence.max_W_m.z());

  AutonomyParams au_in = au_vehicle;
  outer_loop::OuterLoopParams ol_in = ol_vehicle;
  fit_to_site(au_in, load_site(ingress), ingress);
  outer_loop::fit_to_site(ol_in, load_site(ingress), ingress);
  EXPECT_EQ(au_in.geofence.min_W_m, au_vehicle.geofence.min_W_m);
  EXPECT_EQ(au_in.geofence.max_W_m, au_vehicle.geofence.max_W_m);
  EXPECT_EQ(ol_in.geofence_max_W_m, ol_vehicle.geofence_max_W_m);
}

TEST(SiteTest, ASiteWithNoRoomForTheFlightIsAnErrorNamingTheSiteFile) {
  const std::string vehicle =
      std::string(alight::build::source_dir()) + "/config/vehicles/pelican.yaml";
  AutonomyParams au = load_params(vehicle);
  SiteArea beside;
  beside.center_xy_m = Vector2d(20.0, 0.0);
  const ParamError far =
      alight::test::expect_param_error([&] { fit_to_site(au, beside, "sites/far.yaml"); });
  EXPECT_EQ(far.file(), "sites/far.yaml");
  EXPECT_EQ(far.key(), "area");
  EXPECT_EQ(far.value(), site_text(beside));
  SiteArea low;
  low.height_m = au.takeoff.height_m;  // the ceiling at the take-off height
  const ParamError ceiling =
      alight::test::expect_param_error([&] { fit_to_site(au, low, "sites/low.yaml"); });
  EXPECT_EQ(ceiling.file(), "sites/low.yaml");
  EXPECT_EQ(ceiling.key(), "area.height_m");
  outer_loop::OuterLoopParams ol = outer_loop::load_params(vehicle);
  EXPECT_EQ(alight::test::expect_param_error([&] {
              outer_loop::fit_to_site(ol, beside, "sites/far.yaml");
            }).file(),
            "sites/far.yaml");
}

}  // namespace
}  // namespace alight::autonomy
