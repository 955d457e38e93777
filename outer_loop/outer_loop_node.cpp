// alight-outer-loop: POSITION_SETPOINT + MOCAP_POSE -> ATTITUDE_CMD (paper 3.4, 4.1).
// Steps on the utime of its inputs: every pose and every setpoint advances the controller to the
// newest input time seen, so a replayed log gives the same commands as the live flight, and the
// pose-lost failsafe still runs when motion capture stops (autonomy keeps publishing setpoints
// stepped on the IMU).

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <optional>

#include "common/msg_convert.hpp"
#include "common/node.hpp"
#include "outer_loop/convert.hpp"
#include "outer_loop/params.hpp"
#include "outer_loop/position_controller.hpp"

int main(int argc, char** argv) {
  return alight::run_node_main("alight-outer-loop", [&]() -> int {
    CLI::App app{"alight outer loop: linear position controller (POSITION_SETPOINT, MOCAP_POSE -> "
                 "ATTITUDE_CMD)"};
    alight::NodeArgs args;
    args.add_to(app, true);
    std::string pose_channel = "MOCAP_POSE", setpoint_channel = "POSITION_SETPOINT",
                cmd_channel = "ATTITUDE_CMD";
    app.add_option("--pose-channel", pose_channel, "pose_t input");
    app.add_option("--setpoint-channel", setpoint_channel, "position_setpoint_t input");
    app.add_option("--cmd-channel", cmd_channel, "attitude_cmd_t output");
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      return app.exit(e);
    }
    args.finalize();

    namespace ol = alight::outer_loop;
    const ol::OuterLoopParams params = ol::load_params(args.config);
    ol::PositionController controller(params);
    alight::Node node(args.lcm_url, "alight-outer-loop");

    std::optional<alight::PoseSample> pose;
    std::optional<ol::PositionSetpoint> setpoint;
    int64_t now_utime = 0;
    ol::Mode last_mode = ol::Mode::kDisarmed;

    const auto step = [&](int64_t input_utime) {
      now_utime = std::max(now_utime, input_utime);
      const ol::AttitudeCommand cmd = controller.update(setpoint, pose, now_utime);
      if (cmd.mode != last_mode) {
        spdlog::info("outer loop: {} -> {} ({})", ol::mode_name(last_mode), ol::mode_name(cmd.mode),
                     cmd.reason);
        last_mode = cmd.mode;
      }
      node.publish(cmd_channel, ol::to_msg(cmd));
    };
    node.on<alight::pose_t>(pose_channel, [&](const alight::pose_t& m) {
      pose = alight::from_msg(m);
      step(m.utime);
    });
    node.on<alight::position_setpoint_t>(setpoint_channel,
                                         [&](const alight::position_setpoint_t& m) {
                                           setpoint = ol::from_msg(m);
                                           step(m.utime);
                                         });
    spdlog::info("alight-outer-loop: {} + {} -> {} (mass {} kg)", setpoint_channel, pose_channel,
                 cmd_channel, params.mass_kg);
    return node.run();
  });
}
