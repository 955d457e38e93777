// alight-outer-loop: POSITION_SETPOINT + MOCAP_POSE -> ATTITUDE_CMD (paper 3.4, 4.1).
// Glue only: the input boundary, controller time and the failsafe timer are the Runner's
// (outer_loop/runner.hpp); this file owns LCM, the clocks, the parameters and the state file.
//
// Steps on the utime of its inputs, so a replayed log gives the same commands as the live
// flight; its own steady-clock timer keeps the failsafe sequence running when motion capture and
// setpoints have both stopped. A (re)started outer loop publishes nothing until a pose and a
// setpoint are both fresh, and restores a latched failsafe disarm (and whether the vehicle was
// flying) from its state file.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <optional>

#include "autonomy/operator_identity.hpp"
#include "common/boot_id.hpp"
#include "common/node.hpp"
#include "outer_loop/convert.hpp"
#include "outer_loop/params.hpp"
#include "outer_loop/runner.hpp"
#include "outer_loop/state_file.hpp"

int main(int argc, char** argv) {
  return alight::run_node_main("alight-outer-loop", [&]() -> int {
    CLI::App app{
        "alight outer loop: linear position controller (POSITION_SETPOINT, MOCAP_POSE -> "
        "ATTITUDE_CMD)"};
    alight::NodeArgs args;
    args.add_to(app, true);
    namespace ol = alight::outer_loop;
    ol::RunnerOptions options;
    std::string cmd_channel = alight::channels::kAttitudeCmd, state_file;
    double state_max_age_s = 10.0;
    std::string site_file;
    app.add_option("--site", site_file,
                   "the room flown in (a file's area: section; a simulator scenario is one): "
                   "narrows outer_loop.geofence to its walls and ceiling");
    app.add_option("--pose-channel", options.pose_channel, "pose_t input");
    app.add_option("--setpoint-channel", options.setpoint_channel, "position_setpoint_t input");
    app.add_option("--cmd-channel", cmd_channel, "attitude_cmd_t output");
    app.add_option("--state-file", state_file,
                   "What survives a restart (failsafe latch, armed); default "
                   "/tmp/alight-<uid>/outer_loop-<LCM URL>.state");
    app.add_option("--state-max-age", state_max_age_s,
                   "A restart trusts the file's 'armed' only when it is this recent [s]")
        ->check(CLI::Range(0.5, 600.0));
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      return app.exit(e);
    }
    args.finalize();
    if (state_file.empty()) state_file = ol::default_state_path(args.lcm_url);

    const ol::OuterLoopParams params = [&] {
      ol::OuterLoopParams p = ol::load_params(args.config);
      if (!site_file.empty()) ol::fit_to_site(p, alight::load_site(site_file), site_file);
      spdlog::info("outer loop: geofence {}",
                   alight::fence_text(p.geofence_min_W_m, p.geofence_max_W_m, site_file));
      return p;
    }();
    std::string error;
    const auto record = ol::load_state(state_file, &error);
    if (!error.empty()) spdlog::warn("outer loop: {}: starting from the ground state", error);
    const std::string boot_id = alight::read_boot_id();
    const ol::PersistentState restored = ol::restored_state(
        record, {alight::wall_utime(), boot_id, alight::steady_utime()}, state_max_age_s);
    if (restored.disarm_latched || restored.armed)
      spdlog::warn("outer loop: restored from {}: failsafe latched {}, armed {}", state_file,
                   restored.disarm_latched, restored.armed);

    std::vector<std::string> key_warnings;
    alight::KillVerifier kill_verifier =
        alight::autonomy::load_kill_verifier(args.config, &key_warnings);
    for (const auto& w : key_warnings) spdlog::warn("outer loop: {}", w);

    alight::Node node(args, "alight-outer-loop");
    ol::InputGate gate;
    // A KILL is checked on the wall clock, as autonomy checks the operator's commands: its
    // stamp is the ground station's clock, not the sensors'.
    gate.authorise_kill = [&](const alight::operator_cmd_t& cmd) -> std::string {
      const alight::KillCheck c = kill_verifier.check(cmd, alight::wall_utime());
      return c == alight::KillCheck::kAuthorised ? "" : alight::kill_check_name(c);
    };
    gate.reject_value = [&](const std::string& ch, const std::string& why) {
      return node.reject_value(ch, why);
    };
    gate.accept_stamp = [&](const std::string& ch, int64_t utime) {
      return node.accept_stamp(ch, utime);
    };
    ol::Runner runner(params, restored, gate, options);

    ol::Mode last_mode = ol::Mode::kDisarmed;
    uint64_t kills_refused = 0;
    ol::PersistentState saved = restored;
    int64_t saved_steady_us = 0;
    const auto save = [&](const ol::PersistentState& s) {
      std::string err;
      if (!ol::save_state(state_file, {s, alight::wall_utime(), boot_id, alight::steady_utime()},
                          &err))
        spdlog::error("outer loop: state file: {}", err);
      saved = s;
      saved_steady_us = alight::steady_utime();
    };
    const auto publish = [&](const std::optional<ol::AttitudeCommand>& cmd) {
      if (!cmd) return;
      if (cmd->mode != last_mode) {
        spdlog::info("outer loop: {} -> {} ({})", ol::mode_name(last_mode),
                     ol::mode_name(cmd->mode), cmd->reason);
        last_mode = cmd->mode;
      }
      alight::attitude_cmd_t msg = ol::to_msg(*cmd);
      if (!cmd->armed && runner.kill_authority()) msg.kill_authority = *runner.kill_authority();
      node.publish(cmd_channel, msg);
      if (runner.kills_refused() != kills_refused) {
        kills_refused = runner.kills_refused();
        spdlog::error(
            "outer loop: {} KILL setpoint(s) without the operator's signed KILL ({}): "
            "flown as a motors-off (landing)",
            kills_refused, runner.last_kill_refusal());
      }
      const ol::PersistentState s = runner.controller().persistent_state();
      if (s.disarm_latched != saved.disarm_latched || s.armed != saved.armed) save(s);
    };
    node.on<alight::pose_t>(options.pose_channel, [&](const alight::pose_t& m) {
      publish(runner.on_pose(m, alight::steady_utime()));
    });
    node.on<alight::position_setpoint_t>(options.setpoint_channel,
                                         [&](const alight::position_setpoint_t& m) {
                                           publish(runner.on_setpoint(m, alight::steady_utime()));
                                         });
    node.every(0.01, [&](int64_t) {
      publish(runner.tick(alight::steady_utime()));
      // While flying, keep the record fresh: a restart trusts "armed" only from a recent one.
      if (saved.armed && alight::steady_utime() - saved_steady_us > 1'000'000) save(saved);
    });
    spdlog::info("alight-outer-loop: {} + {} -> {} (mass {} kg, state {})",
                 options.setpoint_channel, options.pose_channel, cmd_channel, params.mass_kg,
                 state_file);
    return node.run();
  });
}
