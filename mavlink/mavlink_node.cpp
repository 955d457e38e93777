// alight-mavlink: alight on a PX4 or ArduPilot autopilot over MAVLink. Glue only: the
// protocol, the setpoint stream, the mode and arming state machine and the conversions are the
// Bridge's (mavlink/bridge.hpp); this file owns the serial port or UDP socket, LCM, the clocks
// and the parameters.
//
//   alight-mavlink --config config/autopilot/px4.yaml --vehicle config/vehicles/pelican.yaml
//                  [--link serial:/dev/ttyACM0:921600 | udp-listen:0.0.0.0:14540 | udp:H:P[:L]]
//
// In: ATTITUDE_CMD (control: attitude), POSITION_SETPOINT (position; and KILL in both),
// MOCAP_POSE (to the autopilot's estimator). Out: IMU, AUTOPILOT_POSE, AUTOPILOT_STATUS, and
// NODE_STATUS with the link as the input "mavlink:<link>".
//
// A forced disarm needs the operator: a KILL (POSITION_SETPOINT motors KILL, ATTITUDE_CMD
// armed = false) is forced only when its kill_authority, the operator's signed CMD_KILL, verifies
// with the vehicle file's operator key (autonomy.operator_key_file, vehicle_id,
// command_max_age_s, judged on this node's wall clock: the command was stamped by the ground
// station's); otherwise it is a plain motors-off.
//
//   alight-mavlink --config FILE --setup-signing   gives the autopilot the file's signing key
//   (SETUP_SIGNING, unsigned, while it is disarmed; on a link the autopilot trusts, e.g. its USB
//   port) and exits 0 once the autopilot's HEARTBEAT comes signed with it, 1 after 10 s.
//
// A device that cannot be opened, disappears (USB unplugged) or fails is closed and reopened
// every reopen_delay_s, forever: the autopilot flies its own failsafe meanwhile, and a flight
// stack must not need a restart because a cable was reseated. Bad configuration: exit 2.

#include <poll.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <alight/attitude_cmd_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/position_setpoint_t.hpp>
#include <array>
#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>

#include "autonomy/params.hpp"
#include "common/channels.hpp"
#include "common/msg_convert.hpp"
#include "common/node.hpp"
#include "common/operator_auth.hpp"
#include "mavlink/bridge.hpp"
#include "mavlink/bridge_msgs.hpp"
#include "mavlink/link_io.hpp"
#include "outer_loop/params.hpp"

namespace {

/// Setpoints stamped further before the newest input (motion capture) are replays or strays; an
/// autopilot's offboard-loss timeout is about as long (PX4 COM_OF_LOSS_T: 1 s) [s].
constexpr double kMaxSetpointAgeS = 1.0;
/// The outer loop's clock runs ahead of the inputs' while a loaded machine delays them [s].
constexpr double kMaxSetpointAheadS = 10.0;

/// The signing key of the file's signing_key_file: 64 hex digits, or a passphrase.
std::optional<alight::mavlink::SigningConfig> load_signing(const alight::mavlink::BridgeParams& p,
                                                           const std::string& config) {
  if (p.signing_key_file.empty()) return std::nullopt;
  std::ifstream f(p.signing_key_file);
  if (!f)
    throw alight::ParamError(config, "mavlink.signing_key_file", p.signing_key_file,
                             "cannot be read");
  std::stringstream ss;
  ss << f.rdbuf();
  std::string text = ss.str();
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' '))
    text.pop_back();
  alight::mavlink::SigningConfig c;
  c.link_id = static_cast<uint8_t>(p.signing_link_id);
  if (const auto k = alight::mavlink::signing_key_from_hex(text)) {
    c.key = *k;
  } else if (!text.empty()) {
    c.key = alight::mavlink::signing_key_from_passphrase(text);
  } else {
    throw alight::ParamError(config, "mavlink.signing_key_file", p.signing_key_file, "is empty");
  }
  return c;
}

alight::ChannelStats link_stats(const alight::mavlink::AutopilotStatus& s) {
  alight::ChannelStats c;
  c.received = s.parser.frames_ok;
  c.decode_errors = s.parser.crc_errors + s.parser.bad_length + s.parser.incompat_flags +
                    s.parser.signature_failures + s.parser.replays + s.parser.unsigned_refused;
  c.rejected_values = s.stats.rejected_values;
  c.rejected_stamps = s.stats.rejected_stamps;
  c.skipped = s.stats.foreign_frames + s.parser.unknown_ids;
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  return alight::run_node_main("alight-mavlink", [&]() -> int {
    using namespace alight;
    namespace mav = alight::mavlink;
    CLI::App app{"alight-mavlink: alight's setpoints to a PX4 / ArduPilot autopilot over MAVLink"};
    NodeArgs args;
    args.add_to(app, true);
    std::string vehicle_file, link;
    bool setup_signing = false;
    app.add_option("--vehicle", vehicle_file,
                   "Vehicle file: its outer_loop.mass_kg turns ATTITUDE_CMD thrust [N] into the "
                   "autopilot's normalised thrust (needed for control: attitude)");
    app.add_option("--link", link, "instead of the file's mavlink.link");
    app.add_flag("--setup-signing", setup_signing,
                 "give the autopilot mavlink.signing_key_file's key (SETUP_SIGNING), check that "
                 "it signs with it, and exit");
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      return app.exit(e);
    }
    args.finalize();

    mav::BridgeParams params = mav::load_bridge_params(args.config);
    if (!link.empty()) {
      std::string why;
      if (!mav::parse_link_address(link, &why))
        throw ParamError("--link", "mavlink.link", link, why);
      params.link = link;
      params.validate();
    }
    const auto signing = load_signing(params, args.config);
    if (setup_signing) {
      if (!signing)
        throw ParamError(args.config, "mavlink.signing_key_file", "",
                         "--setup-signing needs a key file");
      mav::LinkIo io(*mav::parse_link_address(params.link, nullptr));
      std::string error;
      if (!io.open(&error)) {
        spdlog::error("alight-mavlink: {}", error);
        return 1;
      }
      mav::Parser parser(mav::ParserOptions{signing->key, true});
      mav::Sender plain(static_cast<uint8_t>(params.own_sysid),
                        static_cast<uint8_t>(params.own_compid));
      std::array<uint8_t, 4096> buffer;
      const int64_t start = steady_utime();
      int64_t next_send = start;
      std::optional<uint8_t> target;
      while (steady_utime() - start < 10'000'000) {
        const int64_t now = steady_utime();
        if (target && now >= next_send) {
          mav::SetupSigning m;
          m.target_system = *target;
          m.target_component = static_cast<uint8_t>(params.target_compid);
          m.secret_key = signing->key;
          m.initial_timestamp = mav::signing_timestamp_from_unix_utime(wall_utime());
          const auto f = plain.pack(m, wall_utime());
          io.write(f.bytes(), &error);
          next_send = now + 1'000'000;
        }
        const long n = io.read(buffer, &error);
        if (n < 0) {
          spdlog::error("alight-mavlink: {}", error);
          return 1;
        }
        if (n == 0) {
          std::this_thread::sleep_for(std::chrono::milliseconds(5));
          continue;
        }
        parser.observe_time(wall_utime());
        parser.push(std::span<const uint8_t>(buffer.data(), static_cast<size_t>(n)));
        mav::Frame f;
        while (parser.next(f)) {
          if (f.msgid != mav::Heartbeat::kId || f.compid != params.target_compid) continue;
          const auto hb = mav::decode<mav::Heartbeat>(f);
          if (!hb || hb->autopilot == mav::mav_autopilot::kInvalid) continue;
          if (!target) {
            target = f.sysid;
            if (hb->base_mode & mav::mav_mode_flag::kSafetyArmed) {
              spdlog::error(
                  "alight-mavlink: the autopilot is armed; both autopilots refuse "
                  "SETUP_SIGNING while armed");
              return 1;
            }
          }
          if (f.signature_verified) {
            spdlog::info("alight-mavlink: system {} signs with the key of {}", f.sysid,
                         params.signing_key_file);
            return 0;
          }
        }
      }
      spdlog::error("alight-mavlink: no HEARTBEAT signed with the key within 10 s{}",
                    target ? "" : " (no autopilot heard)");
      return 1;
    }
    // The operator's key, as autonomy reads it, for a KILL's authority.
    std::optional<KillVerifier> kill_verifier;
    if (!vehicle_file.empty()) {
      const auto ap = autonomy::load_params(vehicle_file);
      std::optional<OperatorKey> key;
      if (!ap.operator_key_file.empty()) {
        auto loaded = load_key_file(ap.operator_key_file);
        for (const auto& w : loaded.warnings) spdlog::warn("alight-mavlink: {}", w);
        key = std::move(loaded.key);
      }
      kill_verifier.emplace(std::move(key), ap.vehicle_id,
                            static_cast<int64_t>(std::llround(ap.command_max_age_s * 1e6)));
    }
    // A refused authority is logged when the reason changes and every 500th time after: the
    // carrier repeats it with every message.
    std::string last_refusal;
    uint64_t refusals = 0;
    const auto kill_authorised = [&](const operator_cmd_t& authority, const char* channel,
                                     bool is_kill) {
      std::string why;
      if (mav::kill_authorised(kill_verifier ? &*kill_verifier : nullptr, authority, wall_utime(),
                               &why))
        return true;
      const bool empty = authority.command == operator_cmd_t::CMD_NONE &&
                         authority.auth == operator_cmd_t::AUTH_NONE;
      if (!is_kill && empty) return false;  // the outer loop's motors-off on the ground
      if (why != last_refusal || ++refusals % 500 == 0)
        spdlog::warn(
            "alight-mavlink: {}: KILL without the operator's authority ({}): a plain "
            "motors-off",
            channel, why);
      last_refusal = why;
      return false;
    };
    double weight_N = 0;
    if (!vehicle_file.empty()) {
      const auto ol = outer_loop::load_params(vehicle_file);
      weight_N = ol.mass_kg * ol.gravity_mps2;
    } else if (params.control_mode() == mav::ControlMode::kAttitude) {
      throw ParamError(args.config, "mavlink.control", params.control,
                       "attitude control needs --vehicle FILE (its mass turns thrust into the "
                       "autopilot's normalised thrust)");
    } else {
      weight_N = 1.0;  // unused: position setpoints carry no thrust
    }

    const mav::LinkAddress address = *mav::parse_link_address(params.link, nullptr);
    const std::string input = "mavlink:" + address.text();
    Node node(args, "alight-mavlink");
    mav::Bridge bridge(params, weight_N, signing);
    mav::LinkIo io(address);
    int64_t imu_seq = 0, pose_seq = 0, reopens = 0;
    spdlog::info("alight-mavlink: {} over {}, {} control, engage {}, setpoints at {} Hz",
                 params.autopilot, address.text(), params.control, params.engage,
                 params.stream_rate_hz);

    const auto clock = [] { return mav::BridgeClock{steady_utime(), wall_utime()}; };
    const auto step = [&](const mav::BridgeInput& in) {
      mav::BridgeOutput out = bridge.update(in, clock());
      if (!out.link_bytes.empty() && io.is_open()) {
        std::string error;
        if (io.write(out.link_bytes, &error) < 0) {
          spdlog::warn("alight-mavlink: {}; reopening", error);
          io.close();
        }
      }
      for (const auto& s : out.imu) node.publish(channels::kImu, mav::to_msg(s, imu_seq++));
      for (const auto& p : out.autopilot_pose) {
        pose_t m = to_msg(p.pose, pose_seq++);
        if (!p.position_known) m.status = pose_t::STATUS_ATTITUDE_ONLY;
        node.publish(channels::kAutopilotPose, m);
      }
      for (const auto& e : out.events) {
        if (e.warning)
          spdlog::warn("alight-mavlink: {}", e.text);
        else
          spdlog::info("alight-mavlink: {}", e.text);
      }
    };

    node.on<attitude_cmd_t>(channels::kAttitudeCmd, [&](const attitude_cmd_t& m) {
      std::string why;
      auto t = mav::attitude_from_msg(m, &why);
      if (!t) return (void)node.reject_value(channels::kAttitudeCmd, why);
      if (!m.armed)
        t->kill_authorised = kill_authorised(m.kill_authority, channels::kAttitudeCmd, false);
      if (const auto p = mav::setpoint_stamp_problem(m.utime, node.newest_stamp(), kMaxSetpointAgeS,
                                                     kMaxSetpointAheadS))
        return (void)node.reject_value(channels::kAttitudeCmd, *p);
      mav::BridgeInput in;
      in.attitude = t;
      step(in);
    });
    node.on<position_setpoint_t>(channels::kPositionSetpoint, [&](const position_setpoint_t& m) {
      std::string why;
      auto t = mav::position_from_msg(m, &why);
      if (!t) return (void)node.reject_value(channels::kPositionSetpoint, why);
      if (t->motors == mav::Motors::kKill)
        t->kill_authorised = kill_authorised(m.kill_authority, channels::kPositionSetpoint, true);
      if (const auto p = mav::setpoint_stamp_problem(m.utime, node.newest_stamp(), kMaxSetpointAgeS,
                                                     kMaxSetpointAheadS))
        return (void)node.reject_value(channels::kPositionSetpoint, *p);
      mav::BridgeInput in;
      in.position = t;
      step(in);
    });
    node.on<pose_t>(channels::kMocapPose, [&](const pose_t& m) {
      std::string why;
      auto p = pose_from_msg(m, &why);
      if (!p) return (void)node.reject_value(channels::kMocapPose, why);
      if (!node.accept_stamp(channels::kMocapPose, m.utime)) return;
      mav::BridgeInput in;
      in.mocap = p;
      step(in);
    });
    node.every(1.0 / params.status_rate_hz, [&](int64_t wall) {
      const mav::AutopilotStatus s = bridge.status(clock());
      node.publish(channels::kAutopilotStatus, mav::to_msg(s, wall, reopens));
      node.set_input_stats(input, link_stats(s));
    });

    int64_t next_open = steady_utime();
    uint64_t open_failures = 0;
    bool opened_before = false;  // every successful open after the first is a reopen
    std::array<uint8_t, 4096> buffer;
    const int lcm_fd = node.lcm().getFileno();
    while (!node.stopping()) {
      bool reopened = false;
      if (!io.is_open() && steady_utime() >= next_open) {
        std::string error;
        if (io.open(&error)) {
          reopened = true;
          if (opened_before) ++reopens;
          opened_before = true;
          open_failures = 0;
          spdlog::info("alight-mavlink: opened {}", address.text());
        } else {
          if (++open_failures <= 3 || open_failures % 20 == 0)
            spdlog::warn("alight-mavlink: {} (attempt {}); retrying every {} s", error,
                         open_failures, params.reopen_delay_s);
          next_open = steady_utime() + static_cast<int64_t>(params.reopen_delay_s * 1e6);
        }
      }
      std::array<pollfd, 2> fds{pollfd{lcm_fd, POLLIN, 0}, pollfd{io.fd(), POLLIN, 0}};
      // 2 ms: finer than any stream period, so setpoints leave on time without a busy loop.
      poll(fds.data(), io.is_open() ? 2 : 1, 2);
      node.spin_once(0);
      // Everything that has arrived (UDP: one datagram per read), then one step for the timers.
      bool stepped = false;
      for (int reads = 0; io.is_open() && reads < 64; ++reads) {
        std::string error;
        const long n = io.read(buffer, &error);
        if (n < 0) {
          spdlog::warn("alight-mavlink: {}; reopening in {} s", error, params.reopen_delay_s);
          io.close();
          next_open = steady_utime() + static_cast<int64_t>(params.reopen_delay_s * 1e6);
          break;
        }
        if (n == 0) break;
        mav::BridgeInput in;
        in.link_reopened = reopened;
        reopened = false;
        in.link_bytes = std::span<const uint8_t>(buffer.data(), static_cast<size_t>(n));
        step(in);
        stepped = true;
      }
      if (!stepped) {
        mav::BridgeInput in;
        in.link_reopened = reopened;
        step(in);
      }
    }
    return 0;
  });
}
