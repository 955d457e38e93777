// alight-vrpn-test-server: a stand-in for a motion-capture room's VRPN server on 127.0.0.1, to try
// alight-mocap without a room. Serves one object flying a horizontal circle, to one client at a
// time, in a z-up or y-up room frame, in metres or millimetres; waits for the next client when one
// goes away.
//
//   alight-vrpn-test-server --port 3883 --object Pelican --rate 100 --up-axis y --units mm
//   alight-mocap --config config/mocap/optitrack_motive.yaml --tracker Pelican@127.0.0.1:3883

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <thread>

#include "tools/vrpn_test_server.hpp"

namespace {
volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"A VRPN tracker server on 127.0.0.1 serving one object on a circle"};
  int port = 3883;
  std::string object = "Pelican", units = "m", up_axis = "z";
  double rate_hz = 100.0, radius_m = 1.0, height_m = 1.5, period_s = 10.0;
  app.add_option("--port", port, "TCP port (0: any; the port is printed)")
      ->check(CLI::Range(0, 65535));
  app.add_option("--object", object, "tracker (object) name");
  app.add_option("--rate", rate_hz, "poses per second")->check(CLI::Range(1.0, 2000.0));
  app.add_option("--units", units, "m or mm")->check(CLI::IsMember({"m", "mm"}));
  app.add_option("--up-axis", up_axis, "z or y")->check(CLI::IsMember({"z", "y"}));
  app.add_option("--radius", radius_m, "circle radius [m]");
  app.add_option("--height", height_m, "height above the floor [m]");
  app.add_option("--period", period_s, "one lap [s]")->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);

  alight::tools::VrpnServerOptions options;
  options.port = port;
  alight::tools::VrpnTestServer server(options);
  if (!server.listen()) {
    std::fprintf(stderr, "alight-vrpn-test-server: cannot listen on 127.0.0.1:%d\n", port);
    return 1;
  }
  std::printf("alight-vrpn-test-server: %s@127.0.0.1:%d, %.0f Hz, %s, %s-up\n", object.c_str(),
              server.port(), rate_hz, units.c_str(), up_axis.c_str());
  std::fflush(stdout);
  const double scale = units == "mm" ? 1000.0 : 1.0;
  const auto period = std::chrono::duration<double>(1.0 / rate_hz);
  while (!g_stop) {
    if (!server.accept(0.5, {object})) continue;
    std::printf("alight-vrpn-test-server: client connected\n");
    std::fflush(stdout);
    auto next = std::chrono::steady_clock::now();
    while (!g_stop && server.connected()) {
      const int64_t t_us = std::chrono::duration_cast<std::chrono::microseconds>(
                               std::chrono::system_clock::now().time_since_epoch())
                               .count();
      const double phase = 2 * M_PI * std::fmod(t_us * 1e-6, period_s) / period_s;
      // Position on the circle and heading along it, in a z-up frame first.
      const double x = radius_m * std::cos(phase), y = radius_m * std::sin(phase), z = height_m;
      const double yaw = phase + M_PI / 2;
      alight::tools::ServedPose pose;
      pose.object = object;
      pose.stamp_us = t_us;
      if (up_axis == "z") {
        pose.pos[0] = x * scale, pose.pos[1] = y * scale, pose.pos[2] = z * scale;
        pose.quat_xyzw[2] = std::sin(yaw / 2), pose.quat_xyzw[3] = std::cos(yaw / 2);
      } else {  // y up: room (x, y, z) = (x, z, -y); a heading is a rotation about room y
        pose.pos[0] = x * scale, pose.pos[1] = z * scale, pose.pos[2] = -y * scale;
        pose.quat_xyzw[1] = std::sin(yaw / 2), pose.quat_xyzw[3] = std::cos(yaw / 2);
      }
      server.send_pose(pose);
      next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
      std::this_thread::sleep_until(next);
    }
    std::printf("alight-vrpn-test-server: client gone\n");
    std::fflush(stdout);
  }
  return 0;
}
