#include <gtest/gtest.h>
#include <sys/wait.h>

#include <alight/attitude_cmd_t.hpp>
#include <alight/baro_t.hpp>
#include <alight/image_t.hpp>
#include <alight/imu_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/range_t.hpp>
#include <alight/sim_truth_t.hpp>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <sstream>
#include <thread>

#include "common/build_paths.hpp"
#include "common/channels.hpp"
#include "common/image_msg.hpp"

namespace alight {
namespace {

const std::string kUrl = "udpm://239.255.76.67:7893?ttl=0";

std::string bin() { return std::string(alight::build::binary_dir()) + "/bin/alight-sim"; }
std::string scenario(const std::string& name) {
  return std::string(alight::build::source_dir()) + "/config/scenarios/" + name + ".yaml";
}

int run(const std::string& args, std::string* stderr_text = nullptr) {
  // One file per test: CTest runs this file's cases in parallel.
  const auto err = std::filesystem::path(alight::build::binary_dir()) / "test_tmp" /
                   (std::string("sim_node_output_") +
                    ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".txt");
  std::filesystem::create_directories(err.parent_path());
  const int status = std::system((bin() + " " + args + " > " + err.string() + " 2>&1").c_str());
  if (stderr_text) {
    std::stringstream ss;
    ss << std::ifstream(err).rdbuf();
    *stderr_text = ss.str();
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

struct Counter {
  std::atomic<int> mocap{0}, imu{0}, camera{0}, truth{0}, range{0}, range_ok{0}, baro{0};
  std::atomic<int64_t> pose_utime{0};
  sim_truth_t last_truth{};
  image_t last_image{};
  range_t last_range{}, last_range_ok{};
  baro_t last_baro{};
  void on_range(const lcm::ReceiveBuffer*, const std::string&, const range_t* m) {
    last_range = *m;
    ++range;
    if (m->status != range_t::STATUS_OK) return;
    last_range_ok = *m;
    ++range_ok;
  }
  void on_baro(const lcm::ReceiveBuffer*, const std::string&, const baro_t* m) {
    last_baro = *m;
    ++baro;
  }
  void on_pose(const lcm::ReceiveBuffer*, const std::string&, const pose_t* m) {
    pose_utime = m->utime;
    ++mocap;
  }
  void on_imu(const lcm::ReceiveBuffer*, const std::string&, const imu_t*) { ++imu; }
  void on_image(const lcm::ReceiveBuffer*, const std::string&, const image_t* m) {
    last_image = *m;
    ++camera;
  }
  void on_truth(const lcm::ReceiveBuffer*, const std::string&, const sim_truth_t* m) {
    last_truth = *m;
    ++truth;
  }
};

TEST(SimNodeTest, PublishesEveryChannelAndFollowsAttitudeCommands) {
  lcm::LCM lcm(kUrl + "&recv_buf_size=8388608");
  ASSERT_TRUE(lcm.good());
  Counter c;
  lcm.subscribe(channels::kMocapPose, &Counter::on_pose, &c);
  lcm.subscribe(channels::kImu, &Counter::on_imu, &c);
  lcm.subscribe(channels::kCamera, &Counter::on_image, &c)->setQueueCapacity(100);
  lcm.subscribe(channels::kSimTruth, &Counter::on_truth, &c);
  lcm.subscribe(channels::kRange, &Counter::on_range, &c);
  lcm.subscribe(channels::kBaro, &Counter::on_baro, &c);
  std::atomic<int> code{-1};
  std::thread node([&] {
    code = run("--scenario " + scenario("landing_a") + " --seed 3 --duration 1.5 --lcm-url '" +
               kUrl + "'");
  });
  // Full thrust, armed, until the node exits (however loaded the machine): it must climb.
  // Stamped like the outer loop's, with the newest pose: the simulated autopilot refuses
  // commands stamped far from its clock.
  while (code == -1) {
    attitude_cmd_t cmd{};
    cmd.utime = c.pose_utime;
    cmd.thrust_N = 1.5 * 1.2 * 9.81;
    cmd.armed = true;
    lcm.publish(channels::kAttitudeCmd, &cmd);
    lcm.handleTimeout(5);
  }
  node.join();
  while (lcm.handleTimeout(50) > 0) {
  }
  EXPECT_EQ(code, 0);
  EXPECT_GE(c.mocap, 130);  // 100 Hz
  EXPECT_GE(c.imu, 270);    // 200 Hz
  EXPECT_GE(c.camera, 35);  // 30 Hz
  EXPECT_GE(c.truth, 65);   // 50 Hz
  EXPECT_GE(c.range, 130);  // 100 Hz
  EXPECT_GE(c.baro, 65);    // 50 Hz
  // On the ground the rangefinder, 5 cm above the floor, is too near; flying, it measures.
  EXPECT_GE(c.range_ok, 20);
  // (a sample or two behind the last truth, climbing at a few m/s)
  EXPECT_NEAR(c.last_range_ok.distance_m, c.last_truth.pos[2] - 0.05, 0.5);
  EXPECT_EQ(c.last_range.max_range_m, 8.0);
  EXPECT_EQ(c.last_range.beam_B[2], -1.0);
  EXPECT_NEAR(c.last_baro.pressure_pa, 101325.0 - 12.0 * c.last_truth.pos[2], 600.0);
  EXPECT_EQ(c.last_truth.scenario, "landing_a");
  EXPECT_TRUE(c.last_truth.has_platform);
  EXPECT_TRUE(c.last_truth.armed);
  EXPECT_GT(c.last_truth.pos[2], 0.5);
  EXPECT_EQ(c.last_image.width, 640);
  EXPECT_EQ(c.last_image.height, 480);
  EXPECT_EQ(c.last_image.pixelformat, image_t::PIXEL_FORMAT_GRAY);
  EXPECT_TRUE(metadata_int(c.last_image, "seq").has_value());
}

TEST(SimNodeTest, RemappedChannelsAreUsedUnderTheirNewNames) {
  lcm::LCM lcm(kUrl + "&recv_buf_size=8388608");
  ASSERT_TRUE(lcm.good());
  Counter renamed, original;
  lcm.subscribe("SIM_NODE_TEST_TRUTH", &Counter::on_truth, &renamed);
  lcm.subscribe("SIM_NODE_TEST_POSE", &Counter::on_pose, &renamed);
  lcm.subscribe(channels::kSimTruth, &Counter::on_truth, &original);
  lcm.subscribe(channels::kMocapPose, &Counter::on_pose, &original);
  std::atomic<int> code{-1};
  std::thread node([&] {
    code =
        run("--scenario " + scenario("landing_a") + " --seed 3 --duration 1.5 --lcm-url '" + kUrl +
            "' --remap SIM_TRUTH=SIM_NODE_TEST_TRUTH --remap MOCAP_POSE=SIM_NODE_TEST_POSE "
            "--remap ATTITUDE_CMD=SIM_NODE_TEST_CMD");
  });
  // Full thrust on the renamed command channel only: the vehicle arms and climbs iff the sim
  // subscribed to the new name.
  while (code == -1) {
    attitude_cmd_t cmd{};
    cmd.utime = renamed.pose_utime;
    cmd.thrust_N = 1.5 * 1.2 * 9.81;
    cmd.armed = true;
    lcm.publish("SIM_NODE_TEST_CMD", &cmd);
    lcm.handleTimeout(5);
  }
  node.join();
  while (lcm.handleTimeout(50) > 0) {
  }
  EXPECT_EQ(code, 0);
  EXPECT_GE(renamed.truth, 10);
  EXPECT_GE(renamed.mocap, 20);
  EXPECT_TRUE(renamed.last_truth.armed);
  EXPECT_GT(renamed.last_truth.pos[2], 0.5);
  EXPECT_EQ(original.truth, 0);  // nothing on the old names
  EXPECT_EQ(original.mocap, 0);
}

TEST(SimNodeTest, SensorsSwitchedOffPublishNothingWhileTheTruthGoesOn) {
  const auto path =
      std::filesystem::path(alight::build::binary_dir()) / "test_tmp" / "sim_sensors_off.yaml";
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << "name: sensors_off\nmocap: {enabled: false}\nimu: {enabled: false}\n"
                         "rangefinder: {enabled: false}\nbaro: {enabled: false}\n"
                         "camera: {enabled: false}\n";
  lcm::LCM lcm(kUrl + "&recv_buf_size=8388608");
  ASSERT_TRUE(lcm.good());
  Counter c;
  lcm.subscribe(channels::kMocapPose, &Counter::on_pose, &c);
  lcm.subscribe(channels::kImu, &Counter::on_imu, &c);
  lcm.subscribe(channels::kCamera, &Counter::on_image, &c);
  lcm.subscribe(channels::kSimTruth, &Counter::on_truth, &c);
  lcm.subscribe(channels::kRange, &Counter::on_range, &c);
  lcm.subscribe(channels::kBaro, &Counter::on_baro, &c);
  std::atomic<int> code{-1};
  std::thread node([&] {
    code = run("--scenario " + path.string() + " --vehicle " +
               std::string(alight::build::source_dir()) +
               "/config/vehicles/starmac.yaml --duration 1.0 --lcm-url '" + kUrl + "'");
  });
  while (code == -1) lcm.handleTimeout(5);
  node.join();
  while (lcm.handleTimeout(50) > 0) {
  }
  EXPECT_EQ(code, 0);
  EXPECT_GE(c.truth, 40);
  EXPECT_EQ(c.last_truth.scenario, "sensors_off");
  EXPECT_EQ(c.mocap, 0);
  EXPECT_EQ(c.imu, 0);
  EXPECT_EQ(c.camera, 0);
  EXPECT_EQ(c.range, 0);
  EXPECT_EQ(c.baro, 0);
}

// Ingress without motion capture (issue 17): the forward camera on CAMERA for the vision, the
// downward one on FLOW_CAMERA for the estimator, no MOCAP_POSE.
TEST(SimNodeTest, FlowCameraPublishesTheDownwardCameraBesidesTheForwardOne) {
  lcm::LCM lcm(kUrl + "&recv_buf_size=8388608");
  ASSERT_TRUE(lcm.good());
  Counter c, flow;
  lcm.subscribe(channels::kMocapPose, &Counter::on_pose, &c);
  lcm.subscribe(channels::kCamera, &Counter::on_image, &c)->setQueueCapacity(100);
  lcm.subscribe(channels::kFlowCamera, &Counter::on_image, &flow)->setQueueCapacity(100);
  std::atomic<int> code{-1};
  std::thread node([&] {
    code = run("--scenario " + scenario("ingress_wide") + " --vehicle " +
               std::string(alight::build::source_dir()) +
               "/config/vehicles/pelican.yaml --no-mocap --flow-camera --duration 1.0 --lcm-url '" +
               kUrl + "'");
  });
  while (code == -1) lcm.handleTimeout(5);
  node.join();
  while (lcm.handleTimeout(50) > 0) {
  }
  EXPECT_EQ(code, 0);
  EXPECT_EQ(c.mocap, 0);
  EXPECT_GE(c.camera, 25);  // 30 Hz each
  EXPECT_GE(flow.camera, 25);
  EXPECT_EQ(flow.last_image.width, 640);
  EXPECT_EQ(flow.last_image.pixelformat, image_t::PIXEL_FORMAT_GRAY);
}

TEST(SimNodeTest, ABadRemapExitsWithCode2NamingTheKnownChannels) {
  std::string err;
  EXPECT_EQ(
      run("--scenario " + scenario("landing_a") + " --lcm-url '" + kUrl + "' --remap SIM_TRUTH",
          &err),
      2);
  EXPECT_NE(err.find("FROM=TO"), std::string::npos) << err;
  EXPECT_EQ(run("--scenario " + scenario("landing_a") + " --lcm-url '" + kUrl + "' --remap TRUTH=X",
                &err),
            2);
  EXPECT_NE(err.find("unknown channel 'TRUTH'"), std::string::npos) << err;
  EXPECT_NE(err.find(channels::kSimTruth), std::string::npos) << err;
}

TEST(SimNodeTest, ABadScenarioExitsWithCode2NamingFileKeyAndValue) {
  const auto path =
      std::filesystem::path(alight::build::binary_dir()) / "test_tmp" / "sim_bad_scenario.yaml";
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << "name: bad\ncamera:\n  rate_hz: 500\n";
  std::string err;
  EXPECT_EQ(run("--scenario " + path.string() + " --lcm-url '" + kUrl + "'", &err), 2);
  EXPECT_NE(err.find(path.string()), std::string::npos) << err;
  EXPECT_NE(err.find("camera.rate_hz"), std::string::npos) << err;
  EXPECT_NE(err.find("500"), std::string::npos) << err;
}

}  // namespace
}  // namespace alight
