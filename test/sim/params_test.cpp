#include "common/params.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <utility>
#include <vector>

#include "common/build_paths.hpp"
#include "sim/params.hpp"
#include "sim_test_util.hpp"

namespace alight::sim {
namespace {

using test::config_path;

std::string write_temp(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::path(alight::build::binary_dir()) / "test_tmp" / "sim";
  std::filesystem::create_directories(dir);
  const auto path = dir / name;
  std::ofstream(path) << text;
  return path.string();
}

TEST(SimParamsTest, EveryScenarioAndVehicleInTheRepositoryLoads) {
  for (const char* name :
       {"landing_a", "landing_b", "landing_c", "landing_none", "ingress", "ingress_solid"}) {
    SCOPED_TRACE(name);
    const Scenario s = test::scenario(name);
    EXPECT_EQ(s.name, name);
  }
  for (const char* v : {"starmac", "pelican"}) {
    const VehicleParams p =
        load_vehicle_params(config_path(std::string("vehicles/") + v + ".yaml"));
    EXPECT_EQ(p.name, v);
    EXPECT_NEAR(p.gear_footprint_m, 0.15, 1e-9);  // paper 4.1
    EXPECT_NO_THROW(
        load_camera_rig(config_path(std::string("vehicles/") + v + ".yaml"), "downward"));
  }
}

TEST(SimParamsTest, ThePapersPlatformsAndOpening) {
  EXPECT_TRUE(test::scenario("landing_a").platform->size_m.isApprox(Vector3d(0.432, 0.279, 0.109)));
  EXPECT_TRUE(test::scenario("landing_b").platform->size_m.isApprox(Vector3d(0.432, 0.279, 0.219)));
  EXPECT_TRUE(test::scenario("landing_c").platform->size_m.isApprox(Vector3d(0.216, 0.279, 0.219)));
  EXPECT_FALSE(test::scenario("landing_none").platform.has_value());
  const Scenario ingress = test::scenario("ingress");
  ASSERT_TRUE(ingress.wall && ingress.wall->has_opening);
  EXPECT_TRUE(ingress.wall->opening_size_m.isApprox(Vector2d(0.6, 0.6)));
  EXPECT_FALSE(test::scenario("ingress_solid").wall->has_opening);
}

TEST(SimParamsTest, ABadValueNamesFileKeyAndValue) {
  const std::string path = write_temp("bad_value.yaml", "name: bad\nmocap:\n  rate_hz: -5\n");
  try {
    load_scenario(path);
    FAIL() << "no error";
  } catch (const ParamError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.key(), "mocap.rate_hz");
    EXPECT_EQ(e.value(), "-5");
    EXPECT_NE(std::string(e.what()).find("mocap.rate_hz"), std::string::npos) << e.what();
  }
}

TEST(SimParamsTest, AMisspelledKeyIsRejected) {
  const std::string path =
      write_temp("typo.yaml", "name: typo\nplatform:\n  size_m: [0.4, 0.3, 0.1]\n  yaw_dge: 3\n");
  try {
    load_scenario(path);
    FAIL() << "no error";
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("yaw_dge"), std::string::npos) << e.what();
  }
}

TEST(SimParamsTest, AWrongTypeAndAnOpeningOutsideTheWallAreRejected) {
  EXPECT_THROW(load_scenario(write_temp("type.yaml", "name: t\ncamera: {rate_hz: fast}\n")),
               ParamError);
  EXPECT_THROW(load_scenario(write_temp("opening.yaml",
                                        "name: t\nwall:\n  height_m: 1.0\n  opening: {center_yz_m: "
                                        "[0, 0.9], size_m: [0.6, 0.6]}\n")),
               ParamError);
  EXPECT_THROW(load_scenario(write_temp("nodt.yaml", "name: t\nsim: {physics_dt_s: 0.01}\n")),
               ParamError);
}

TEST(SimParamsTest, AnImageTextureIsLoadedRelativeToTheScenario) {
  cv::Mat img(100, 150, CV_8U);
  cv::randu(img, 0, 255);
  const auto dir = std::filesystem::path(alight::build::binary_dir()) / "test_tmp" / "sim";
  std::filesystem::create_directories(dir);
  cv::imwrite((dir / "photo.png").string(), img);
  const std::string path = write_temp(
      "image_texture.yaml",
      "name: photo\narea:\n  floor_texture: {kind: image, path: photo.png, texel_m: 0.01}\n");
  const Scenario s = load_scenario(path);
  ASSERT_FALSE(s.floor_texture.image.empty());
  EXPECT_EQ(s.floor_texture.image.size(), img.size());
  const std::string missing = write_temp(
      "missing_texture.yaml",
      "name: photo\narea:\n  floor_texture: {kind: image, path: nothere.png, texel_m: 0.01}\n");
  try {
    load_scenario(missing);
    FAIL();
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("nothere.png"), std::string::npos) << e.what();
  }
}

TEST(SimParamsTest, AVehicleWithTooLittleThrustIsRejected) {
  const std::string path =
      write_temp("weak.yaml", "vehicle:\n  mass_kg: 3.0\n  max_thrust_N: 20\n");
  EXPECT_THROW(load_vehicle_params(path), ParamError);
}

TEST(SimParamsTest, SensorSwitchesAndBadSensorValuesNameTheirFullKey) {
  const Scenario s = load_scenario(write_temp(
      "sensors_off.yaml",
      "name: off\nmocap: {enabled: false}\nimu: {enabled: false}\n"
      "rangefinder: {enabled: false}\nbaro: {enabled: false, ground_altitude_m: 1000}\n"));
  EXPECT_FALSE(s.mocap.enabled);
  EXPECT_FALSE(s.imu.enabled);
  EXPECT_FALSE(s.rangefinder.enabled);
  EXPECT_FALSE(s.baro.enabled);
  EXPECT_EQ(s.baro.ground_altitude_m, 1000.0);
  // Absent sections: every sensor on, at its defaults.
  const Scenario d = load_scenario(write_temp("sensors_default.yaml", "name: d\n"));
  EXPECT_TRUE(d.mocap.enabled && d.imu.enabled && d.rangefinder.enabled && d.baro.enabled);
  // ... but the second, downward camera for the estimator's flow (issue 17) is off.
  EXPECT_FALSE(d.flow_camera.enabled);
  EXPECT_EQ(d.flow_camera.mount, "downward");

  const std::vector<std::pair<std::string, std::string>> cases = {
      {"rangefinder: {min_range_m: 0.5, max_range_m: 0.4}", "rangefinder.max_range_m"},
      {"rangefinder: {rate_hz: 0}", "rangefinder.rate_hz"},
      {"rangefinder: {sigma_frac: -0.01}", "rangefinder.sigma_frac"},
      {"rangefinder: {dropout_prob: 0.7}", "rangefinder.dropout_prob"},
      {"rangefinder: {direction_B: [0, 0, 0]}", "rangefinder.direction_B"},
      {"rangefinder: {offset_B_m: [0, 0, .nan]}", "rangefinder.offset_B_m"},
      {"rangefinder: {enabled: maybe}", "rangefinder.enabled"},
      {"baro: {rate_hz: -50}", "baro.rate_hz"},
      {"baro: {drift_tau_s: 0}", "baro.drift_tau_s"},
      {"baro: {sea_level_pressure_pa: 50000}", "baro.sea_level_pressure_pa"},
      {"baro: {ground_altitude_m: 12000}", "baro.ground_altitude_m"},
      {"mocap: {enabled: 3}", "mocap.enabled"},
      {"imu: {gyro_bias_walk_radps_per_sqrt_s: -1}", "imu.gyro_bias_walk_radps_per_sqrt_s"},
      {"flow_camera: {enabled: true, mount: forward}", "flow_camera.mount"},
      {"flow_camera: {rate_hz: 0}", "flow_camera.rate_hz"},
  };
  for (const auto& [text, key] : cases) {
    SCOPED_TRACE(text);
    const std::string path = write_temp("bad_sensor.yaml", "name: bad\n" + text + "\n");
    try {
      load_scenario(path);
      ADD_FAILURE() << "no error";
    } catch (const ParamError& e) {
      EXPECT_EQ(e.key(), key) << e.what();
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(load_scenario(write_temp("typo_sensor.yaml", "name: t\nbaro: {sigma_p: 1}\n")),
               ParamError);
}

}  // namespace
}  // namespace alight::sim
