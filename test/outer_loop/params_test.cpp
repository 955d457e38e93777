// The outer_loop: sections of the vehicle files load and validate; errors name file and key.

#include "outer_loop/params.hpp"

#include <gtest/gtest.h>

#include "common/build_paths.hpp"

namespace alight::outer_loop {
namespace {

// Every outer_loop section states its flying area (the fence is required).
#define FENCE "geofence_min_W_m: [-3, -3, -0.5], geofence_max_W_m: [4.7, 3, 2.6], "

TEST(OuterLoopParamsTest, VehicleFilesLoad) {
  for (const char* v : {"starmac", "pelican"}) {
    const std::string path =
        std::string(alight::build::source_dir()) + "/config/vehicles/" + v + ".yaml";
    const auto p = load_params(path);
    EXPECT_GT(p.mass_kg, 0.0) << v;
    EXPECT_DOUBLE_EQ(p.pose_stale_s, 0.3) << v;
    EXPECT_DOUBLE_EQ(p.pose_lost_s, 1.0) << v;
  }
}

TEST(OuterLoopParamsTest, BadValueAndUnknownKeyNameTheKey) {
  try {
    load_params(
        ParamNode::from_string("outer_loop: {" FENCE "mass_kg: 1.0, max_tilt_deg: 70}", "v.yaml"));
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_EQ(e.key(), "outer_loop.max_tilt_deg");
    EXPECT_EQ(e.file(), "v.yaml");
  }
  try {
    load_params(ParamNode::from_string("outer_loop: {" FENCE "mass_kg: 1.0, kp_xy: 3}", "v.yaml"));
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("kp_xy"), std::string::npos);
  }
  EXPECT_THROW(
      load_params(ParamNode::from_string("outer_loop: {" FENCE "kp_xy_per_s2: 3}", "v.yaml")),
      ParamError);  // mass_kg is required
}

// A vehicle file without its flying area is refused, naming the key.
TEST(OuterLoopParamsTest, TheGeofenceIsRequired) {
  try {
    load_params(ParamNode::from_string("outer_loop: {mass_kg: 1.0}", "v.yaml"));
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_EQ(e.file(), "v.yaml");
    EXPECT_EQ(e.key(), "outer_loop.geofence_min_W_m");
  }
  try {
    load_params(ParamNode::from_string(
        "outer_loop: {mass_kg: 1.0, geofence_min_W_m: [0, 0, 0], geofence_max_W_m: [3, 3, 0.3]}",
        "v.yaml"));
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_EQ(e.key(), "outer_loop.geofence_max_W_m");
  }
}

TEST(OuterLoopRegression, InfiniteTimeoutInAFileIsAParamErrorNamingFileKeyAndValue) {
  // `.inf` loaded and switched the failsafe it bounds off.
  for (const char* key : {"pose_lost_s", "failsafe_disarm_after_s", "setpoint_lost_s",
                          "pose_stale_s", "setpoint_stale_s", "landed_still_s"}) {
    const std::string yaml = std::string("outer_loop: {" FENCE "mass_kg: 1.0, ") + key + ": .inf}";
    try {
      load_params(ParamNode::from_string(yaml, "v.yaml"));
      ADD_FAILURE() << key << ": .inf accepted";
    } catch (const ParamError& e) {
      EXPECT_EQ(e.file(), "v.yaml") << key;
      EXPECT_EQ(e.key(), std::string("outer_loop.") + key);
      EXPECT_EQ(e.value(), ".inf") << key;  // as written in the file
    }
  }
  try {
    load_params(
        ParamNode::from_string("outer_loop: {" FENCE "mass_kg: 1.0, kp_z_per_s2: .nan}", "v.yaml"));
    ADD_FAILURE() << ".nan accepted";
  } catch (const ParamError& e) {
    EXPECT_EQ(e.key(), "outer_loop.kp_z_per_s2");
  }
}

TEST(OuterLoopParamsTest, EveryTimeoutHasAnUpperBound) {
  for (const char* kv :
       {"pose_stale_s: 2.5", "pose_lost_s: 6", "failsafe_disarm_after_s: 121",
        "setpoint_stale_s: 6", "setpoint_lost_s: 31", "landed_still_s: 11", "land_detect_s: 6"}) {
    const std::string yaml = std::string("outer_loop: {" FENCE "mass_kg: 1.0, ") + kv + "}";
    const std::string key = std::string(kv).substr(0, std::string(kv).find(':'));
    try {
      load_params(ParamNode::from_string(yaml, "v.yaml"));
      ADD_FAILURE() << kv << " accepted";
    } catch (const ParamError& e) {
      EXPECT_EQ(e.key(), "outer_loop." + key);
    }
  }
}

}  // namespace
}  // namespace alight::outer_loop
