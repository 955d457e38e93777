// alight-sim: the simulated vehicle, motion-capture room, IMU, rangefinder, barometer and camera
// on LCM. The only file of sim/ that knows LCM, files or the wall clock; the simulation itself
// is the Simulator. Each sensor is switched in the scenario (`enabled:`); one switched off
// publishes nothing (SIM_TRUTH is always published).
//
//   alight-sim --scenario config/scenarios/landing_a.yaml [--vehicle FILE] [--seed N]
//              [--rate X] [--duration S] [--lcm-url URL] [--mavlink ADDRESS]
//
// --mavlink: the vehicle's autopilot is a MAVLink peer that behaves like PX4's offboard interface
// (sim/offboard_endpoint.hpp) on that link (e.g. udp:127.0.0.1:14540:14580, where alight-mavlink
// listens, as PX4 SITL's onboard link does): commands come as SET_ATTITUDE_TARGET instead of
// ATTITUDE_CMD, and IMU goes out as HIGHRES_IMU (alight-mavlink publishes it) instead of on LCM.
// RANGE and BARO are published on LCM either way (alight-mavlink does not bridge them).
//
// --truth-from ardupilot|px4 --truth-link ADDRESS: the vehicle is a real autopilot's SITL
// (ArduCopter's own physics, PX4's SIH), flown by it; alight-sim only renders the
// sensors from its true state (SIM_STATE / HIL_STATE_QUATERNION over MAVLink on ADDRESS,
// sim/autopilot_truth.hpp) and judges contact with the scene. The SITL's ground is flat: it is
// the platform's top in a landing scenario (the top's height above the floor: 11 to 22 cm),
// the floor otherwise, so that a touch-down on the top is the autopilot's own ground contact.
// No IMU (the autopilot's comes through alight-mavlink), no ATTITUDE_CMD; nothing is published
// while the truth is older than 0.5 s. Implies --start-now.
//
// --flow-camera (or the scenario's flow_camera.enabled): the downward camera is rendered besides
// the scenario's camera and published on FLOW_CAMERA for alight-estimator, at flow_camera.rate_hz
// (ingress without motion capture: the vision flies the forward camera, the estimator's flow
// needs the floor). SIM_CONTROL's camera dropouts silence CAMERA only.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <alight/attitude_cmd_t.hpp>
#include <alight/sim_control_t.hpp>
#include <chrono>
#include <filesystem>
#include <thread>

#include "autonomy/operator_identity.hpp"
#include "common/node.hpp"
#include "common/params.hpp"
#include "mavlink/link_io.hpp"
#include "sim/autopilot_truth.hpp"
#include "sim/offboard_endpoint.hpp"
#ifdef ALIGHT_SIM_POSITION_CONTROL
#include "outer_loop/params.hpp"
#include "outer_loop/position_controller.hpp"
#endif
#include "sim/params.hpp"
#include "sim/sensor_gate.hpp"
#include "sim/sim_msgs.hpp"
#include "sim/simulator.hpp"

namespace {
constexpr int64_t kChunkUs = 1000;         // commands are picked up at this sim-time granularity
constexpr int64_t kTruthPeriodUs = 20000;  // SIM_TRUTH at 50 Hz
}  // namespace

int main(int argc, char** argv) {
  return alight::run_node_main("alight-sim", [&]() -> int {
    using namespace alight;
    CLI::App app(
        "alight-sim: quadrotor, motion capture, IMU, rangefinder, barometer and camera, "
        "simulated");
    std::string scenario_file, vehicle_file;
    uint64_t seed = 0;
    double rate = 1.0, duration_s = 0.0;
    bool start_now = false;
    int threads = 1;
    NodeArgs args;
    std::string mavlink_link, truth_from, truth_link;
    double truth_rate_hz = 100.0, contact_margin_m = 0.01;
    app.add_option("--mavlink", mavlink_link,
                   "The autopilot speaks MAVLink (PX4 offboard) on this link instead of taking "
                   "ATTITUDE_CMD: udp:HOST:PORT[:LOCAL_PORT], udp-listen:HOST:PORT or "
                   "serial:DEVICE:BAUD");
    app.add_option("--truth-from", truth_from,
                   "The vehicle is this autopilot's SITL (its own physics): render the sensors "
                   "from its true state instead of simulating it")
        ->check(CLI::IsMember({"ardupilot", "px4"}));
    app.add_option("--truth-link", truth_link,
                   "MAVLink link to the SITL for --truth-from (ArduPilot: a serial port as "
                   "udp-listen:127.0.0.1:PORT; PX4 SIH: udp:127.0.0.1:19450:19410)");
    app.add_option("--truth-rate", truth_rate_hz, "Truth messages asked of the SITL [Hz]")
        ->check(CLI::Range(10.0, 400.0));
    app.add_option("--contact-margin", contact_margin_m,
                   "--truth-from: a point this close above a surface touches it [m]")
        ->check(CLI::Range(0.0, 0.05));
    app.add_option("--scenario", scenario_file, "Scenario file (config/scenarios/*.yaml)")
        ->required();
    app.add_option("--vehicle", vehicle_file,
                   "Vehicle file (default: ../vehicles/starmac.yaml beside the scenario)");
    app.add_option("--seed", seed, "Randomises platform pose, textures, lighting and noise");
    app.add_option("--rate", rate, "Real-time factor (0: as fast as possible)")
        ->check(CLI::Range(0.0, 1000.0));
    app.add_option("--duration", duration_s, "Stop after this much sim time [s] (0: never)")
        ->check(CLI::NonNegativeNumber);
    app.add_flag("--start-now", start_now,
                 "Start the sim clock at the wall clock, not the scenario's start_utime");
    app.add_option("--render-threads", threads, "Threads for the camera renderer")
        ->check(CLI::Range(1, 16));
    bool no_mocap = false;
    app.add_flag("--no-mocap", no_mocap,
                 "No MOCAP_POSE whatever the scenario says (mocap.enabled: false): the vehicle "
                 "flies on its onboard estimate; SIM_TRUTH still scores it");
    bool flow_camera = false;
    app.add_flag("--flow-camera", flow_camera,
                 "Also render the downward camera on FLOW_CAMERA for the onboard estimator's flow "
                 "(flow_camera.enabled: true), when CAMERA carries another camera (ingress "
                 "without motion capture)");
    args.add_to(app, false);
    try {
      app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
      return app.exit(e);
    }
    args.finalize();

    if (truth_from.empty() != truth_link.empty())
      throw ParamError("--truth-from", "truth-link", truth_link,
                       "--truth-from and --truth-link go together");
    if (!truth_from.empty() && !mavlink_link.empty())
      throw ParamError("--truth-from", "mavlink", mavlink_link,
                       "the SITL is the autopilot: no --mavlink endpoint with --truth-from");
    if (!truth_from.empty()) start_now = true;
    sim::Scenario scenario = sim::load_scenario(scenario_file);
    if (vehicle_file.empty())
      vehicle_file = resolve_relative(scenario_file, "../vehicles/starmac.yaml");
    const sim::VehicleParams vehicle = sim::load_vehicle_params(vehicle_file);
    std::optional<sim::CameraRig> rig;
    if (scenario.camera.enabled) rig = sim::load_camera_rig(vehicle_file, scenario.camera.mount);
    if (start_now) scenario.start_utime = wall_utime();
    if (no_mocap) scenario.mocap.enabled = false;
    if (flow_camera) scenario.flow_camera.enabled = true;
    std::optional<sim::CameraRig> flow_rig;
    if (scenario.flow_camera.enabled)
      flow_rig = sim::load_camera_rig(vehicle_file, scenario.flow_camera.mount);

    std::optional<mavlink::LinkAddress> mavlink_address;
    if (!mavlink_link.empty()) {
      std::string why;
      mavlink_address = mavlink::parse_link_address(mavlink_link, &why);
      if (!mavlink_address) throw ParamError("--mavlink", "mavlink", mavlink_link, why);
    }

    sim::Simulator simulator(scenario, vehicle, seed, rig, flow_rig);
    simulator.set_render_threads(threads);
    // The autopilot stops the motors in the air only for the operator's own signed KILL.
    std::vector<std::string> key_warnings;
    KillVerifier kill_verifier = autonomy::load_kill_verifier(vehicle_file, &key_warnings);
    for (const auto& w : key_warnings) spdlog::info("alight-sim: {}", w);
    // The vision undistorts with the vehicle file's camera_info: a scenario's lens it does not
    // name is a mismatch the vision cannot see (sim/README.md, "A real camera's effects").
    if (rig && scenario.camera.effects.lens) {
      const CameraModel rendered = sim::with_lens(rig->model, scenario.camera.effects);
      if (rendered.distortion != rig->model.distortion || rendered.D != rig->model.D)
        spdlog::warn(
            "alight-sim: camera.effects.lens renders a {} lens that {} does not name; give "
            "alight-vision a vehicle file whose camera_info has the same lens",
            scenario.camera.effects.lens_model, vehicle_file);
    }
    uint64_t disarms_refused = 0;
    Node node(args, "alight-sim");
    // Disarmed until the outer loop says otherwise; its silence is the autopilot's command-loss
    // failsafe's business (Simulator::advance_to).
    node.on<attitude_cmd_t>(channels::kAttitudeCmd, [&](const attitude_cmd_t& m) {
      if (mavlink_address) return;  // the autopilot takes its commands over MAVLink
      std::string why;
      if (auto cmd =
              sim::command_from_msg(m, simulator.now_utime(), vehicle.cmd_loss_timeout_s, &why)) {
        cmd->forced = !m.armed &&
                      kill_verifier.check(m.kill_authority, wall_utime()) == KillCheck::kAuthorised;
        simulator.command(*cmd);
        if (simulator.disarms_refused() != disarms_refused) {
          disarms_refused = simulator.disarms_refused();
          spdlog::error(
              "alight-sim: {} disarm(s) in the air refused: not forced by the operator's signed "
              "KILL (as an autopilot refuses a disarm in flight)",
              disarms_refused);
        }
      } else {
        node.reject_value(channels::kAttitudeCmd, why);
      }
    });
    bool command_lost = false;
    // Test hook of the fault campaign: sensor dropouts on request (sim/sensor_gate.hpp).
    sim::SensorGates gates;
    node.on<sim_control_t>(channels::kSimControl, [&](const sim_control_t& m) {
      if (const auto why = gates.apply(m, simulator.now_utime())) {
        node.reject_value(channels::kSimControl, *why);
      } else {
        spdlog::info("alight-sim: SIM_CONTROL: mocap off {} s, camera off {} s, imu off {} s",
                     m.mocap_off_s, m.camera_off_s, m.imu_off_s);
      }
    });

    spdlog::info("alight-sim: scenario {} ({}), vehicle {} ({}), seed {}, rate {}", scenario.name,
                 scenario_file, vehicle.name, vehicle_file, seed, rate);
    if (flow_rig)
      spdlog::info("alight-sim: the {} camera on {} at {} Hz besides {} on {}",
                   scenario.flow_camera.mount, channels::kFlowCamera, scenario.flow_camera.rate_hz,
                   scenario.camera.mount, channels::kCamera);
    const int64_t sim0 = simulator.now_utime();
    // The MAVLink autopilot: its link, reopened when it fails (a bridge that is not up yet).
    std::optional<mavlink::LinkIo> link;
    std::optional<sim::OffboardEndpoint> autopilot;
    if (mavlink_address) {
      link.emplace(*mavlink_address);
      autopilot.emplace(sim::OffboardEndpointParams{}, vehicle.hover_thrust_N(), sim0);
      spdlog::info("alight-sim: the autopilot speaks MAVLink (PX4 offboard) on {}",
                   mavlink_address->text());
    }
    // The SITL whose true state the sensors render (--truth-from).
    std::optional<mavlink::LinkIo> truth_io;
    std::optional<sim::AutopilotTruth> truth;
    if (!truth_from.empty()) {
      std::string why;
      const auto address = mavlink::parse_link_address(truth_link, &why);
      if (!address) throw ParamError("--truth-link", "truth-link", truth_link, why);
      truth_io.emplace(*address);
      sim::AutopilotTruthParams tp;
      tp.flavour = truth_from == "px4" ? mavlink::Flavour::kPx4 : mavlink::Flavour::kArdupilot;
      tp.rate_hz = truth_rate_hz;
      // At rest on the SITL's flat ground: the platform's top in a landing scenario.
      const double ground_z =
          simulator.scene().platform ? simulator.scene().platform->top_center_W.z() : 0.0;
      tp.start_W = Vector3d(scenario.start_position_m.x(), scenario.start_position_m.y(),
                            simulator.dynamics().resting_height(ground_z));
      tp.start_yaw_rad = scenario.start_yaw_deg * M_PI / 180.0;
      truth.emplace(tp);
      spdlog::info(
          "alight-sim: the vehicle is {}'s SITL, its true state on {}; its ground at "
          "z = {:.3f} m",
          truth_from, address->text(), ground_z);
    }
    std::vector<uint8_t> truth_rx(65536);
    int64_t truth_next_open = 0;
    const auto serve_truth = [&]() {
      if (!truth_io->is_open() && wall_utime() >= truth_next_open) {
        std::string error;
        if (!truth_io->open(&error)) {
          spdlog::warn("alight-sim: {}", error);
          truth_next_open = wall_utime() + 1'000'000;
        }
      }
      // One update per datagram, at the kernel's time of its arrival.
      std::vector<uint8_t> reply;
      const auto handle = [&](std::span<const uint8_t> bytes, int64_t at) {
        auto out = truth->update(bytes, at);
        for (const auto& e : out.events) spdlog::info("alight-sim: truth: {}", e);
        reply.insert(reply.end(), out.bytes.begin(), out.bytes.end());
      };
      for (int i = 0; truth_io->is_open() && i < 256; ++i) {
        std::string error;
        const long n = truth_io->read(truth_rx, &error);
        if (n < 0) {
          spdlog::warn("alight-sim: {}", error);
          truth_io->close();
        }
        if (n <= 0) break;
        const int64_t at = truth_io->last_receipt_wall_us();
        handle(std::span<const uint8_t>(truth_rx.data(), static_cast<size_t>(n)),
               at > 0 ? at : wall_utime());
      }
      handle({}, wall_utime());
      const auto& out_bytes = reply;
      if (truth_io->is_open() && !out_bytes.empty()) {
        std::string error;
        if (truth_io->write(out_bytes, &error) < 0) {
          spdlog::warn("alight-sim: {}", error);
          truth_io->close();
        }
      }
    };
#ifdef ALIGHT_SIM_POSITION_CONTROL
    // The autopilot's own position controller for SET_POSITION_TARGET_LOCAL_NED: alight's outer
    // loop with the vehicle file's gains, on the true state (the autopilot's estimate).
    std::optional<outer_loop::PositionController> position_controller;
    std::optional<sim::EndpointPositionTarget> position_target;
#endif
    std::vector<uint8_t> link_rx(65536);
    int64_t link_next_open = 0;
    const auto serve_autopilot = [&](std::vector<sim::ImuSample> imu) {
      if (link && !link->is_open() && wall_utime() >= link_next_open) {
        std::string error;
        if (!link->open(&error)) {
          spdlog::warn("alight-sim: {}", error);
          link_next_open = wall_utime() + 1'000'000;
        }
      }
      std::vector<uint8_t> bytes;
      for (int i = 0; link->is_open() && i < 64; ++i) {
        std::string error;
        const long n = link->read(link_rx, &error);
        if (n < 0) {
          spdlog::warn("alight-sim: {}", error);
          link->close();
        }
        if (n <= 0) break;
        bytes.insert(bytes.end(), link_rx.begin(), link_rx.begin() + n);
      }
      const sim::Truth t = simulator.truth();
      sim::EndpointInput in;
      in.bytes = bytes;
      in.now_utime = simulator.now_utime();
      in.state = simulator.state();
      in.on_ground = t.contact == sim::Contact::kFloor || t.contact == sim::Contact::kPlatformTop;
      in.imu = std::move(imu);
      sim::EndpointOutput out = autopilot->update(in);
      for (const auto& e : out.events) spdlog::info("alight-sim: autopilot: {}", e);
      if (out.command) simulator.command(*out.command);
      if (out.disarm) {
        sim::AttitudeCommand off;
        off.utime = simulator.now_utime();
        simulator.command(off);
      }
#ifdef ALIGHT_SIM_POSITION_CONTROL
      if (out.position) {
        if (!position_controller)
          position_controller.emplace(outer_loop::load_params(vehicle_file));
        position_target = out.position;
      }
      // Flown while fresh, armed and in OFFBOARD; otherwise the commands stop and the simulated
      // autopilot's command-loss descent takes over, as PX4's failsafe would.
      if (position_target && !out.disarm && autopilot->armed() && autopilot->offboard() &&
          simulator.now_utime() - position_target->utime < 500'000) {
        const sim::VehicleState& s = simulator.state();
        PoseSample pose;
        pose.utime = simulator.now_utime();
        pose.p_W_B = s.p_W_B;
        pose.v_W_B = s.v_W_B;
        pose.q_WB = s.q_WB;
        pose.omega_B = s.omega_B;
        outer_loop::PositionSetpoint sp;
        sp.utime = position_target->utime;
        sp.p_W = position_target->p_W;
        sp.v_W = position_target->v_W;
        sp.a_W = position_target->a_W;
        sp.yaw_rad = position_target->yaw_rad;
        sp.motors_on = true;
        const auto c = position_controller->update(sp, pose, simulator.now_utime());
        sim::AttitudeCommand cmd;
        cmd.utime = simulator.now_utime();
        cmd.roll_rad = c.roll_rad;
        cmd.pitch_rad = c.pitch_rad;
        cmd.yaw_rate_radps = c.yaw_rate_radps;
        cmd.thrust_N = c.thrust_N;
        cmd.armed = true;
        simulator.command(cmd);
      }
#else
      if (out.position)
        spdlog::warn("alight-sim: built without the outer loop: position targets are not flown");
#endif
      if (link->is_open() && !out.bytes.empty()) {
        std::string error;
        if (link->write(out.bytes, &error) < 0) {
          spdlog::warn("alight-sim: {}", error);
          link->close();
        }
      }
    };
    const int64_t end_utime =
        duration_s > 0 ? sim0 + static_cast<int64_t>(duration_s * 1e6) : INT64_MAX;
    // Started now, simulated time is the wall clock: the time spent building the scene and the
    // renderer is caught up at once (on the ground), so a frame's exposure stamp is the wall time
    // it was taken and the end-to-end latency alight-score measures from it is a latency, not
    // the start-up delay. Following a SITL it must be: the truth is stamped on the wall clock.
    const int64_t wall0 = truth || (start_now && rate == 1.0) ? sim0 : wall_utime();
    int64_t next_truth = sim0;
    int64_t late_warned_at = wall0;
    while (!node.stopping() && simulator.now_utime() < end_utime) {
      node.spin_once(0);
      const int64_t wall = wall_utime();
      const int64_t target =
          rate > 0 ? sim0 + static_cast<int64_t>(static_cast<double>(wall - wall0) * rate)
                   : INT64_MAX;
      if (simulator.now_utime() + kChunkUs > target) {
        node.spin_once(1);  // ahead of the wall clock: wait for commands
        continue;
      }
      if (rate > 0 && target - simulator.now_utime() > 200000 && wall - late_warned_at > 5000000) {
        spdlog::warn("alight-sim: running {:.0f} ms behind real time x {}",
                     (target - simulator.now_utime()) / 1e3, rate);
        late_warned_at = wall;
      }
      const int64_t chunk_end = std::min(end_utime, simulator.now_utime() + kChunkUs);
      if (truth) {
        serve_truth();
        simulator.follow([&](int64_t t) { return truth->advance(t); }, chunk_end, contact_margin_m);
        // A vehicle whose truth stopped is not seen: nothing is published for it.
        if (!truth->has_sample() || simulator.now_utime() - truth->last_sample_utime() > 500'000) {
          simulator.take_mocap();
          simulator.take_camera();
          simulator.take_flow_camera();
          simulator.take_range();
          simulator.take_baro();
          simulator.take_imu();
          continue;
        }
      } else {
        simulator.advance_to(chunk_end);
      }
      if (simulator.command_lost() != command_lost) {
        command_lost = !command_lost;
        if (command_lost)
          spdlog::warn("alight-sim: no ATTITUDE_CMD for {} s: autopilot failsafe (level, descend)",
                       vehicle.cmd_loss_timeout_s);
        else
          spdlog::info("alight-sim: ATTITUDE_CMD back: autopilot failsafe ended");
      }
      const int64_t now = simulator.now_utime();
      for (const auto& m : simulator.take_mocap())
        if (gates.mocap.on(now)) node.publish(channels::kMocapPose, sim::to_msg(m));
      std::vector<sim::ImuSample> imu;
      for (const auto& m : simulator.take_imu())
        if (gates.imu.on(now)) imu.push_back(m);
      if (truth) {
        // The autopilot's own IMU comes through alight-mavlink.
      } else if (autopilot) {
        serve_autopilot(std::move(imu));
      } else {
        for (const auto& m : imu) node.publish(channels::kImu, sim::to_msg(m));
      }
      for (const auto& m : simulator.take_range()) node.publish(channels::kRange, sim::to_msg(m));
      for (const auto& m : simulator.take_baro()) node.publish(channels::kBaro, sim::to_msg(m));
      if (auto frame = simulator.take_camera())
        if (gates.camera.on(now)) node.publish(channels::kCamera, sim::to_msg(*frame));
      if (auto frame = simulator.take_flow_camera())
        node.publish(channels::kFlowCamera, sim::to_msg(*frame));
      if (simulator.now_utime() >= next_truth) {
        const sim::Truth truth = simulator.truth();
        // The platform's first: a reader of SIM_TRUTH has the platform of the same time.
        if (auto platform = sim::platform_msg(truth))
          node.publish(channels::kSimPlatform, *platform);
        node.publish(channels::kSimTruth, sim::to_msg(truth));
        next_truth += kTruthPeriodUs;
      }
    }
    const sim::Truth t = simulator.truth();
    spdlog::info("alight-sim: stopped at {:.3f} s sim time; landed {}, tipped {}, collided {}",
                 (t.utime - sim0) * 1e-6, t.landed, t.tipped, t.collided);
    return 0;
  });
}
