// alight-autonomy: MOCAP_POSE, IMU, VISION_TARGET, OPERATOR_CMD, STATE_ESTIMATE ->
// POSITION_SETPOINT, AUTONOMY_STATUS (paper 3.4). Time comes from the sensors: pose and IMU
// messages advance the autonomy's clock to their utime; vision measurements (stamped at
// exposure, in the past), the onboard estimate's health (stamped with the estimator's newest IMU
// sample) and operator commands (stamped by the ground station's clock) are handled at the
// current sensor time and never move it, so a replayed log gives the same setpoints.
//
// Input boundary: every message goes through a validating conversion (non-finite or
// absurd values are counted with reject_value and dropped; the autonomy keeps the last good
// one), and pose, IMU and vision stamps through the node's StampGuard: only an accepted stamp
// advances the clock, so one IMU sample stamped an hour ahead no longer ages every pose past
// pose_lost_s (FAILSAFE for good). Operator commands are stamped by the ground station's clock
// and judged by the verifier on the wall clock, not here.
//
// Restart: the latches (KILL, failsafe) and whether the motors were on are kept in a
// state file (autonomy/restart_state.hpp says why a file), rewritten on every change and once a
// second. A restarted autonomy gets them as RestartState; it publishes no setpoint before the
// first pose, and one that finds the vehicle flying holds there and never runs --auto-go.

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <optional>

#include "autonomy/autonomy.hpp"
#include "autonomy/convert.hpp"
#include "autonomy/params.hpp"
#include "autonomy/restart_state.hpp"
#include "autonomy/text.hpp"
#include "common/msg_convert.hpp"
#include "common/node.hpp"
#include "common/operator_auth.hpp"
#include "common/pose_gate.hpp"
#include "outer_loop/convert.hpp"
#include "outer_loop/params.hpp"
#include "outer_loop/runner.hpp"

// The verifier and the gate share alight::CommandReject; AUTONOMY_STATUS has a slot for each.
static_assert(alight::kCommandRejectCount <= alight::autonomy::kCommandRejectSlots);

int main(int argc, char** argv) {
  return alight::run_node_main("alight-autonomy", [&]() -> int {
    namespace au = alight::autonomy;
    namespace ch = alight::channels;
    CLI::App app{"alight autonomy loop: detection, refinement and approach for landing / ingress"};
    alight::NodeArgs args;
    args.add_to(app, true);
    std::string auto_go;
    app.add_option("--auto-go", auto_go,
                   "simulation only: issue TAKEOFF, then GO with this mission, once a pose "
                   "arrives (landing | ingress)")
        ->check(CLI::IsMember({"landing", "ingress"}));
    std::string key_file;
    app.add_option(
        "--key-file", key_file,
        "HMAC key shared with the ground station (overrides autonomy.operator_key_file)");
    std::string state_file, site_file;
    app.add_option("--site", site_file,
                   "the room flown in (a file's area: section; a simulator scenario is one): "
                   "narrows autonomy.geofence to its walls and ceiling");
    app.add_option("--state-file", state_file,
                   "where the KILL / failsafe latches survive a restart (default: "
                   "$XDG_RUNTIME_DIR/alight/ or /tmp/alight-<uid>/, one file per LCM URL)");
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      return app.exit(e);
    }
    args.finalize();

    const au::AutonomyParams params = [&] {
      au::AutonomyParams p = au::load_params(args.config);
      if (!site_file.empty()) au::fit_to_site(p, alight::load_site(site_file), site_file);
      spdlog::info("geofence {}",
                   alight::fence_text(p.geofence.min_W_m, p.geofence.max_W_m, site_file));
      return p;
    }();
    if (state_file.empty()) state_file = au::default_state_path(args.lcm_url);
    const std::string boot_id = au::read_boot_id();
    const int64_t session = static_cast<int64_t>(::getppid());
    au::RestartState restored;
    {
      std::string why;
      std::optional<au::RestartRecord> record;
      if (auto text = au::read_state_file(state_file, &why)) {
        record = au::parse_record(*text, &why);
        if (!record) spdlog::warn("{}: {}: ignored", state_file, why);
      }
      restored = au::restore_state(record, boot_id, session, alight::steady_utime(),
                                   params.restart.state_max_age_s, &why);
      spdlog::log(restored != au::RestartState{} ? spdlog::level::warn : spdlog::level::info,
                  "{}: {}", state_file, why);
    }
    au::Autonomy autonomy(params, restored);
    au::RestartState saved_state;
    bool state_file_ok = true;
    const auto save_state = [&]() {
      saved_state = autonomy.restart_state();
      au::RestartRecord r{boot_id, session, alight::steady_utime(), saved_state};
      std::string why;
      const bool ok = au::write_state_file(state_file, au::format_record(r), &why);
      if (!ok && state_file_ok)
        spdlog::error("state file not written, latches will not survive a restart: {}", why);
      state_file_ok = ok;
    };
    save_state();
    // Signed operator commands are verified here, at the link: the pure autonomy only
    // sees commands the verifier accepted. Freshness is judged on the wall clock because the
    // command's utime comes from the ground station's clock, not from the sensors.
    if (key_file.empty()) key_file = params.operator_key_file;
    std::optional<alight::CommandVerifier> verifier;
    if (!key_file.empty()) {
      auto loaded = alight::load_key_file(key_file);
      for (const auto& w : loaded.warnings) spdlog::warn("{}", w);
      // A new session per start: commands signed for an earlier run are refused.
      verifier.emplace(std::move(loaded.key), params.vehicle_id, alight::draw_session_nonce(),
                       static_cast<int64_t>(std::llround(params.command_max_age_s * 1e6)));
    }
    // What the station needs to sign for this run; the acknowledgements and the
    // counters of refused commands are the autonomy's CommandGate's (in the converted status).
    const auto fill_link_status = [&](alight::autonomy_status_t& st) {
      st.vehicle_id = params.vehicle_id;
      st.cmd_session = verifier ? verifier->session() : 0;
      st.wall_utime = alight::wall_utime();
    };
    alight::Node node(args, "alight-autonomy");

    int64_t now_utime = 0;
    int64_t last_status_utime = 0;
    int64_t last_status_wall = 0;
    std::string last_phase_reason, last_phase_kind;
    int64_t last_reason_log_utime = 0;
    alight::autonomy_status_t last_status{};
    int64_t internal_seq = 0;
    std::optional<alight::operator_cmd_t> kill_authority;  // the signed KILL, once verified
    // --auto-go tries TAKEOFF in IDLE and GO in HOVER once a second of sensor time until obeyed:
    // the autonomy refuses them while the onboard estimate is not OK (the estimator aligns on
    // the ground for a while after it starts).
    std::optional<int64_t> takeoff_tried_utime, go_tried_utime;
    bool took_off = false, went = false;
    const auto retry_due = [&](const std::optional<int64_t>& tried_utime) {
      return !tried_utime || now_utime - *tried_utime >= 1'000'000;
    };

    std::optional<au::EstimateHealth> pending_estimate;  // the newest STATE_ESTIMATE's health

    const auto step = [&](au::Inputs in) {
      if (now_utime == 0) return;  // no sensor time yet
      in.estimate = std::move(pending_estimate);
      pending_estimate.reset();
      // --auto-go only for an autonomy that started on the ground: never after a restart in
      // flight or a latched KILL (the first pose decides, so TAKEOFF waits for the second).
      const bool auto_go_now = !auto_go.empty() && autonomy.started() && !autonomy.resumed();
      if (auto_go_now && in.pose && !took_off && autonomy.phase() == au::Phase::kIdle &&
          retry_due(takeoff_tried_utime)) {
        in.command = au::OperatorCommand{now_utime,
                                         ++internal_seq,
                                         "auto-go",
                                         au::Command::kTakeoff,
                                         au::Mission::kNone,
                                         alight::Vector3d::Zero(),
                                         au::CommandAuth::kInternal};
        takeoff_tried_utime = now_utime;
      } else if (auto_go_now && !went && autonomy.phase() == au::Phase::kHover && !in.command &&
                 retry_due(go_tried_utime)) {
        in.command = au::OperatorCommand{
            now_utime,
            ++internal_seq,
            "auto-go",
            au::Command::kGo,
            auto_go == "landing" ? au::Mission::kLanding : au::Mission::kIngress,
            alight::Vector3d::Zero(),
            au::CommandAuth::kInternal};
        go_tried_utime = now_utime;
      }
      const au::Output out = autonomy.update(in, now_utime);
      // Obeyed (or overtaken: a hold, a KILL): never again.
      if (takeoff_tried_utime && autonomy.phase() != au::Phase::kIdle) took_off = true;
      if (go_tried_utime && autonomy.phase() != au::Phase::kHover) went = true;
      if (autonomy.restart_state() != saved_state) save_state();
      // Nothing before the first pose: a motors-off setpoint would disarm a flying vehicle.
      if (out.has_setpoint) {
        alight::position_setpoint_t sp = alight::outer_loop::to_msg(out.setpoint);
        // The outer loop and alight-mavlink stop the motors in the air only for the operator's
        // own signed KILL, which they check themselves: it goes with the verdict.
        if (out.setpoint.kill && kill_authority) sp.kill_authority = *kill_authority;
        node.publish(ch::kPositionSetpoint, sp);
      }
      // Logged, and published at once, when what the reason says changes; its numbers alone
      // (a follow's offset changes every step) at most once a second of sensor time, and
      // AUTONOMY_STATUS carries them every status_period_s.
      const std::string phase_reason =
          std::string(au::phase_name(out.status.phase)) + ": " + out.status.reason;
      const std::string phase_kind = au::reason_kind(phase_reason);
      const bool changed = phase_kind != last_phase_kind;
      if (changed ||
          (phase_reason != last_phase_reason && now_utime - last_reason_log_utime >= 1'000'000)) {
        spdlog::info("{}", phase_reason);
        last_phase_reason = phase_reason;
        last_phase_kind = phase_kind;
        last_reason_log_utime = now_utime;
      }
      if (changed || (now_utime - last_status_utime) * 1e-6 >= params.status_period_s * 0.5) {
        last_status = au::to_msg(out.status);
        fill_link_status(last_status);
        node.publish(ch::kAutonomyStatus, last_status);
        last_status_utime = now_utime;
        last_status_wall = alight::wall_utime();
      }
    };

    // The same innovation gate as the outer loop's: a pose off its prediction is refused, and a
    // sustained disagreement refuses every later pose, so the pose-lost failsafe follows.
    alight::PoseGate pose_gate(
        alight::outer_loop::pose_gate_params(alight::outer_loop::load_params(args.config)));
    node.on<alight::pose_t>(ch::kMocapPose, [&](const alight::pose_t& m) {
      std::string why;
      au::Inputs in;
      in.pose = alight::pose_from_msg(m, &why);
      if (!in.pose) return (void)node.reject_value(ch::kMocapPose, why);
      if (!node.accept_stamp(ch::kMocapPose, m.utime)) return;
      // On the ground a new flight starts with a fresh gate.
      const au::Phase ph = autonomy.phase();
      if (ph == au::Phase::kIdle || ph == au::Phase::kLanded || ph == au::Phase::kKilled)
        pose_gate.reset();
      const bool was_latched = pose_gate.latched();
      if (!alight::pose_gate_ok(pose_gate.check(*in.pose))) {
        if (pose_gate.latched() && !was_latched)
          spdlog::error(
              "pose disagrees with its prediction for {} s: refused from now on, the "
              "pose-lost failsafe follows",
              alight::PoseGateParams{}.sustained_s);
        return (void)node.reject_value(ch::kMocapPose, "innovation gate: " + pose_gate.last_why());
      }
      now_utime = std::max(now_utime, m.utime);
      step(in);
    });
    node.on<alight::imu_t>(ch::kImu, [&](const alight::imu_t& m) {
      std::string why;
      au::Inputs in;
      in.imu = au::imu_from_msg(m, &why);
      if (!in.imu) return (void)node.reject_value(ch::kImu, why);
      if (!node.accept_stamp(ch::kImu, m.utime)) return;
      // The clock starts with the first pose. The first stamp of all is judged against the wall
      // clock only, and sensor time (a simulator's) may lie far behind it: an IMU sample an hour
      // ahead as the very first message would otherwise set the clock for good.
      if (now_utime != 0) now_utime = std::max(now_utime, m.utime);
      step(in);
    });
    node.on<alight::target_t>(ch::kVisionTarget, [&](const alight::target_t& m) {
      std::string why;
      au::Inputs in;
      in.target = au::target_from_msg(m, &why);
      if (!in.target) return (void)node.reject_value(ch::kVisionTarget, why);
      if (!node.accept_stamp(ch::kVisionTarget, m.utime)) return;
      step(in);
    });
    // A moving platform's measurements (landing): one per landing frame; those not found carry
    // nothing to fuse and make no step.
    node.on<alight::platform_motion_t>(ch::kVisionPlatform,
                                       [&](const alight::platform_motion_t& m) {
                                         std::string why;
                                         au::Inputs in;
                                         in.platform = au::platform_from_msg(m, &why);
                                         if (!in.platform) {
                                           if (!why.empty())
                                             node.reject_value(ch::kVisionPlatform, why);
                                           return;
                                         }
                                         if (!node.accept_stamp(ch::kVisionPlatform, m.utime))
                                           return;
                                         step(in);
                                       });
    // The onboard estimate's health (its pose arrives as the pose, remapped). It comes
    // at the IMU rate and goes with the next step rather than making one: a step per estimate
    // would add 200 setpoints a second, and as many attitude commands from the outer loop,
    // without new information for either (the IMU steps the autonomy as often).
    node.on<alight::state_estimate_t>(ch::kStateEstimate, [&](const alight::state_estimate_t& m) {
      std::string why;
      auto estimate = au::estimate_from_msg(m, &why);
      if (!estimate) return (void)node.reject_value(ch::kStateEstimate, why);
      if (!node.accept_stamp(ch::kStateEstimate, m.utime)) return;
      pending_estimate = std::move(estimate);
    });
    node.on<alight::operator_cmd_t>(ch::kOperatorCmd, [&](const alight::operator_cmd_t& m) {
      au::Inputs in;
      std::string why;
      in.command = au::command_from_msg(m, &why);
      if (!in.command) return (void)node.reject_value(ch::kOperatorCmd, why);
      // The signature is checked here, where the wire message is (the HMAC covers its
      // encoding); the autonomy's CommandGate takes the verdict, decides, counts and acks.
      if (m.auth != alight::operator_cmd_t::AUTH_NONE && verifier) {
        const auto verdict = verifier->check(m, alight::wall_utime());
        if (!verdict.accepted()) {
          spdlog::warn("OPERATOR_CMD from '{}' for '{}' seq {} rejected: {}", m.sender,
                       m.vehicle_id, m.seq, alight::command_reject_name(verdict.reason));
          in.command->link_reject = verdict.reason;
          return autonomy.refused_at_link(*in.command);
        }
        in.command->auth = au::CommandAuth::kVerified;
        if (m.command == alight::operator_cmd_t::CMD_KILL) kill_authority = m;
      }
      if (now_utime == 0) {
        spdlog::warn("operator command before any sensor time: ignored");
        return;
      }
      step(in);
    });
    // The heartbeat that tells a restarted instance the record is from this session.
    node.every(1.0, [&](int64_t) { save_state(); });
    // Without sensor input the autonomy cannot step; keep the ground station informed anyway.
    node.every(params.status_period_s, [&](int64_t wall) {
      if (last_status_utime != 0 && (wall - last_status_wall) * 1e-6 >= params.status_period_s) {
        alight::autonomy_status_t st = last_status;
        st.reason = "no sensor input: " + st.reason;
        fill_link_status(st);
        node.publish(ch::kAutonomyStatus, st);
        last_status_wall = wall;
      }
    });
    spdlog::info(
        "alight-autonomy: seed {}, vehicle '{}', signed commands {}, unsigned commands {}{}",
        params.seed, params.vehicle_id,
        verifier ? "verified with " + key_file + ", session " + std::to_string(verifier->session())
                 : std::string("refused (no key)"),
        params.accept_unsigned_commands ? "accepted" : "refused",
        auto_go.empty() ? "" : ", auto-go " + auto_go);
    return node.run();
  });
}
