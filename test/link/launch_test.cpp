// The launch files' alight-link commands (config/launch/vehicle_link.yaml and
// ground_station_link.yaml) are valid options for alight-link, mirror each other (what the
// vehicle sends the ground receives, and the other way), and carry every channel the ground
// station reads and the one it publishes.

#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <set>

#include "common/build_paths.hpp"
#include "ground_station/params.hpp"
#include "launcher/launch_file.hpp"
#include "link/cli.hpp"

namespace alight::link {
namespace {

const std::string kLaunchDir = std::string(alight::build::source_dir()) + "/config/launch/";

// The alight-link process of a launch file, its command parsed as the node parses it.
Options link_options(const std::string& file) {
  const launcher::LaunchFile lf = launcher::load_launch_file(kLaunchDir + file);
  const auto it = std::find_if(lf.processes.begin(), lf.processes.end(), [](const auto& p) {
    return !p.command.empty() && p.command[0] == "alight-link";
  });
  if (it == lf.processes.end()) throw std::runtime_error(file + " runs no alight-link");
  const std::map<std::string, std::string> vars = {{"ALIGHT_VEHICLE_HOST", "192.168.1.20"},
                                                   {"ALIGHT_LINK_KEY", "/keys/link.key"}};
  std::vector<std::string> args;
  for (const auto& a : it->command) args.push_back(launcher::substitute(a, vars));
  CLI::App app;
  RawOptions raw;
  std::string key;
  add_options(app, raw, key);
  std::reverse(args.begin(), args.end());
  args.pop_back();  // the program
  app.parse(args);
  EXPECT_EQ(key, "/keys/link.key") << file;
  return parse_options(raw);
}

std::set<std::string> as_set(const std::vector<std::string>& v) { return {v.begin(), v.end()}; }

TEST(LinkLaunchFiles, VehicleAndGroundMirrorEachOtherAndCarryWhatTheStationUses) {
  const Options vehicle = link_options("vehicle_link.yaml");
  const Options ground = link_options("ground_station_link.yaml");
  EXPECT_EQ(vehicle.role, Role::kVehicle);
  EXPECT_EQ(ground.role, Role::kGround);
  EXPECT_EQ(vehicle.endpoint.port, ground.endpoint.port);
  EXPECT_EQ(ground.endpoint.host, "192.168.1.20");
  EXPECT_EQ(as_set(vehicle.send), as_set(ground.receive));
  EXPECT_EQ(as_set(ground.send), as_set(vehicle.receive));
  EXPECT_EQ(vehicle.receive, std::vector<std::string>{channels::kOperatorCmd})
      << "nothing but operator commands goes up";
  const ground_station::GroundStationParams station;
  for (const std::string& ch :
       {station.camera_channel, station.diag_channel, station.status_channel,
        station.target_channel, station.process_channel, station.autopilot_channel,
        station.pose_channel, station.node_status_channel})
    EXPECT_TRUE(as_set(ground.receive).count(ch)) << ch << " is read by the ground station";
  EXPECT_TRUE(as_set(ground.send).count(station.command_channel));
  // Images over Wi-Fi at a low rate.
  for (const char* ch : {channels::kCamera, channels::kVisionDiag}) {
    ASSERT_TRUE(vehicle.max_rate_hz.count(ch)) << ch;
    EXPECT_LE(vehicle.max_rate_hz.at(ch), 5.0) << ch;
  }
}

TEST(LinkLaunchFiles, TheirLaunchersStatusStaysOffTheVehiclesChannel) {
  // On the operator's bus PROCESS_STATUS is the vehicle's, relayed by the link; on the vehicle's,
  // the flight launch's. A second publisher there would be refused.
  for (const char* file : {"ground_station_link.yaml", "vehicle_link.yaml"}) {
    const launcher::LaunchFile lf = launcher::load_launch_file(kLaunchDir + file);
    EXPECT_NE(lf.status_channel, channels::kProcessStatus) << file;
    EXPECT_NE(lf.lcm_url.find("ttl=0"), std::string::npos) << file;
  }
}

}  // namespace
}  // namespace alight::link
