// The autonomy: sections of the vehicle files load and validate; errors name file and key.

#include <gtest/gtest.h>

#include "autonomy/params.hpp"

namespace alight::autonomy {
namespace {

TEST(AutonomyParamsTest, VehicleFilesLoadWithThePapersThresholds) {
  for (const char* v : {"starmac", "pelican"}) {
    const std::string path = std::string(ALIGHT_SOURCE_DIR) + "/config/vehicles/" + v + ".yaml";
    const auto p = load_params(path);
    EXPECT_FALSE(p.accept_unsigned_commands) << v << ": anyone on the LAN could command it";
    EXPECT_TRUE(p.operator_key_file.empty()) << v << ": keys are made per vehicle, not shipped";
    EXPECT_DOUBLE_EQ(p.command_max_age_s, 2.0) << v;
    EXPECT_DOUBLE_EQ(p.failsafe.pose_stale_s, 0.3) << v;
    EXPECT_DOUBLE_EQ(p.failsafe.pose_lost_s, 1.0) << v;
    EXPECT_DOUBLE_EQ(p.landing.gear_footprint_m, 0.15) << v;
    EXPECT_LE(p.status_period_s, 0.1) << v;
  }
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

TEST(AutonomyParamsTest, UnsignedCommandsAreRefusedByDefault) {
  const auto p = load_params(ParamNode::from_string("autonomy: {}", "v.yaml"));
  EXPECT_FALSE(p.accept_unsigned_commands);
}

}  // namespace
}  // namespace alight::autonomy
