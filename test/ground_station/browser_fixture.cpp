// Stand-in vehicle for the ground station's browser test (and for trying the page by hand):
// publishes changing CAMERA and VISION_DIAG frames, MOCAP_POSE on a circle, AUTONOMY_STATUS with
// the phase given on stdin ("phase N"), VISION_TARGET and PROCESS_STATUS, and checks every
// OPERATOR_CMD with CommandVerifier, printing one JSON line per command on stdout.

#include <CLI/CLI.hpp>
#include <alight/autonomy_status_t.hpp>
#include <alight/operator_cmd_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/process_status_t.hpp>
#include <alight/target_t.hpp>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "common/image_msg.hpp"
#include "common/node.hpp"
#include "common/operator_auth.hpp"

int main(int argc, char** argv) {
  namespace ch = alight::channels;
  CLI::App app{"ground station browser-test fixture"};
  std::string lcm_url, key_file;
  double fps = 15.0;
  app.add_option("--lcm-url", lcm_url)->required();
  app.add_option("--key-file", key_file)->required();
  app.add_option("--fps", fps);
  CLI11_PARSE(app, argc, argv);

  // As autonomy runs it: vehicle id, a session per start, announced on AUTONOMY_STATUS, and the
  // last accepted / rejected seq echoed there (the page shows acknowledgements from them).
  const int64_t session = alight::draw_session_nonce();
  alight::CommandVerifier verifier(alight::load_key_file(key_file).key, "alight", session);
  std::atomic<int64_t> last_accepted_seq{-1};
  std::atomic<bool> acknowledge{true};
  alight::Node node(lcm_url, "gs-fixture");
  std::atomic<int> phase{alight::autonomy_status_t::PHASE_IDLE};
  std::atomic<bool> quit{false};
  std::thread input([&] {
    std::string line;
    while (std::getline(std::cin, line)) {
      if (line.rfind("phase ", 0) == 0) phase = std::stoi(line.substr(6));
      if (line == "ack off" || line == "ack on") {
        acknowledge = line == "ack on";  // off: a vehicle that no longer answers
        // Said back, so that the test presses a key only once the switch is in force.
        std::printf("{\"event\":\"ack\",\"on\":%s}\n", acknowledge ? "true" : "false");
        std::fflush(stdout);
      }
      if (line == "quit") break;
    }
    quit = true;
  });
  input.detach();

  node.on<alight::operator_cmd_t>(ch::kOperatorCmd, [&](const alight::operator_cmd_t& cmd) {
    const auto verdict = verifier.check(cmd, alight::wall_utime());
    if (verdict.accepted() && acknowledge) last_accepted_seq = cmd.seq;
    std::printf(
        "{\"event\":\"cmd\",\"verdict\":\"%s\",\"command\":%d,\"mission\":%d,\"seq\":%lld,"
        "\"sender\":\"%s\",\"nudge\":[%.3f,%.3f,%.3f]}\n",
        verdict.accepted() ? "accepted" : alight::command_reject_name(verdict.reason), cmd.command,
        cmd.mission, static_cast<long long>(cmd.seq), cmd.sender.c_str(), cmd.nudge_W[0],
        cmd.nudge_W[1], cmd.nudge_W[2]);
    std::fflush(stdout);
  });

  int64_t frame = 0;
  const int64_t t_start = alight::wall_utime();
  node.every(1.0 / fps, [&](int64_t now) {
    cv::Mat img(240, 320, CV_8UC1, cv::Scalar(40));
    const int x = static_cast<int>((frame * 7) % 320);
    cv::rectangle(img, {x, 0}, {x + 20, 239}, cv::Scalar(220), cv::FILLED);
    cv::putText(img, "frame " + std::to_string(frame), {10, 30}, cv::FONT_HERSHEY_SIMPLEX, 0.8,
                cv::Scalar(255), 2);
    node.publish(ch::kCamera, alight::image_to_msg(img, now, frame));
    if (frame % 3 == 0) {
      cv::Mat diag;
      cv::cvtColor(img, diag, cv::COLOR_GRAY2BGR);
      cv::circle(diag, {160, 120}, 40 + static_cast<int>(frame % 20), {0, 200, 0}, 2);
      node.publish(ch::kVisionDiag, alight::jpeg_image_to_msg(diag, now));
    }
    ++frame;
  });
  node.every(0.02, [&](int64_t now) {
    const double t = (now - t_start) * 1e-6;
    alight::pose_t p{};
    p.utime = now;
    p.pos[0] = 2.0 * std::cos(0.3 * t);
    p.pos[1] = 2.0 * std::sin(0.3 * t);
    p.pos[2] = 2.0 - 0.02 * t;
    p.orientation[0] = 1;
    node.publish(ch::kMocapPose, p);
  });
  node.every(0.1, [&](int64_t now) {
    alight::autonomy_status_t s{};
    s.utime = now;
    s.mission = 1;
    s.phase = static_cast<int8_t>(phase.load());
    s.phase_name = "";  // the page names it from the phase number
    s.reason = "fixture";
    s.n_measurements = static_cast<int32_t>((now - t_start) / 500'000);
    s.has_estimate = s.n_measurements > 2;
    s.estimate_W[0] = 0.5;
    s.estimate_W[1] = -0.3;
    s.estimate_W[2] = 0.6;
    s.covariance[0] = 0.04;
    s.covariance[1] = s.covariance[3] = 0.01;
    s.covariance[4] = 0.02;
    s.covariance[8] = 0.0025;
    s.setpoint_W[2] = 1.5;
    s.vehicle_id = "alight";
    s.cmd_session = session;
    s.last_cmd_seq = last_accepted_seq;
    s.cmds_rejected = static_cast<int32_t>(verifier.n_rejected());
    s.last_rejected_seq = verifier.last_rejected_seq();
    s.last_reject_reason = static_cast<int8_t>(verifier.last_reject_reason());
    s.wall_utime = alight::wall_utime();
    node.publish(ch::kAutonomyStatus, s);
  });
  node.every(0.2, [&](int64_t now) {
    alight::target_t t{};
    t.utime = now;
    t.mission = 1;
    t.found = true;
    t.p_W_target[0] = 0.5 + 0.1 * std::sin(now * 1e-5);
    t.p_W_target[1] = -0.3 + 0.1 * std::cos(now * 1.3e-5);
    t.p_W_target[2] = 0.6;
    t.n_features = 300;
    t.n_matches = 120;
    node.publish(ch::kVisionTarget, t);
  });
  node.every(1.0, [&](int64_t now) {
    alight::process_status_t ps{};
    ps.utime = now;
    ps.launch_name = "fixture";
    for (const char* name : {"vision", "autonomy", "outer_loop"}) {
      alight::process_info_t p{};
      p.name = name;
      p.pid = 1000;
      p.state = alight::process_info_t::STATE_RUNNING;
      ps.processes.push_back(p);
    }
    ps.n = static_cast<int32_t>(ps.processes.size());
    node.publish(ch::kProcessStatus, ps);
  });
  std::printf("{\"event\":\"ready\"}\n");
  std::fflush(stdout);
  while (!quit && !node.stopping()) node.spin_once(50);
  return 0;
}
