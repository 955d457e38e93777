// alight-inject: the fault injector of the fault campaign (scripts/faults). Waits for
// a mission phase (AUTONOMY_STATUS), then does one or more of:
//   --fault KIND:CHANNELS  hostile messages (tools/fault_gen.hpp: garbage, truncated,
//                          bad_lengths, nan, inf, future, zero_stamp; `all` for every kind) on
//                          the channels (comma-separated, or ALL), built from the newest live
//                          message of each channel; --repeat N times, every --period-s
//   --kill NAME            SIGKILL the launcher's process NAME (its pid from PROCESS_STATUS)
//   --sim-control K=S,...  the simulator's test hook (SIM_CONTROL): mocap_off_s, camera_off_s,
//                          imu_off_s (1e6: for good)
//   --replay LOG           plays an old session log onto the live URL with lcm-logplayer
//                          (every channel but SIM_TRUTH), for --replay-s at most
// It acts as a faulty part of the vehicle, not an intruder: each message goes out as the channel's
// own publisher (its id from the newest live message's origin trailer, a counter just above
// it), signed with the bus key when the session has one (--bus-key, $ALIGHT_BUS_KEY_FILE), so
// the faults reach the nodes' value and stamp checks instead of being refused for their origin.
// (scripts/attacks is the intruder.)
// Exit status: 0 when done, 3 when the phase never came (--wait-timeout-s), 2 on bad arguments.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <alight/autonomy_status_t.hpp>
#include <alight/process_status_t.hpp>
#include <alight/sim_control_t.hpp>
#include <chrono>
#include <cstdio>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string_view>
#include <thread>

#include "common/decode.hpp"
#include "common/node.hpp"
#include "common/params.hpp"
#include "tools/fault_gen.hpp"

namespace faults = alight::tools::faults;

namespace {

struct Live {
  std::map<std::string, faults::Bytes> newest;
  std::set<size_t> sent;  // hashes of what we injected: never taken as a live message  // raw bytes
                          // of the newest message per channel
  std::optional<alight::autonomy_status_t> status;
  std::optional<alight::process_status_t> processes;
};

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, sep);)
    if (!item.empty()) out.push_back(item);
  return out;
}

void say(const std::string& text) {
  std::printf("alight-inject: %s\n", text.c_str());
  std::fflush(stdout);
}

// Spins LCM for `seconds` of steady time.
void spin_for(lcm::LCM& lcm, double seconds) {
  const int64_t end = alight::steady_utime() + static_cast<int64_t>(seconds * 1e6);
  for (int64_t now = alight::steady_utime(); now < end; now = alight::steady_utime())
    lcm.handleTimeout(
        static_cast<int>(std::max<int64_t>(1, std::min<int64_t>(50, (end - now) / 1000))));
}

int run_replay(const std::string& url, const std::string& log, double max_s) {
  const pid_t pid = fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    const std::string url_arg = "--lcm-url=" + url;
    execlp("lcm-logplayer", "lcm-logplayer", url_arg.c_str(), "--regexp=^(?!SIM_TRUTH$).*$",
           log.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  const int64_t end = alight::steady_utime() + static_cast<int64_t>(max_s * 1e6);
  int status = 0;
  while (waitpid(pid, &status, WNOHANG) == 0) {
    if (alight::steady_utime() > end) {
      kill(pid, SIGINT);
      waitpid(pid, &status, 0);
      return 0;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"alight-inject: inject faults into a live alight session (fault campaign)"};
  alight::NodeArgs args;
  args.add_to(app, false);
  std::string when_phase, kill_name, sim_control, replay_log;
  std::vector<std::string> fault_specs;
  double delay_s = 0, wait_timeout_s = 120, period_s = 1.0, replay_s = 20, base_wait_s = 1.0;
  int repeat = 1;
  uint64_t seed = 1;
  app.add_option("--when-phase", when_phase,
                 "Wait for an AUTONOMY_STATUS phase name matching this regex (e.g. TAKEOFF)");
  app.add_option("--delay-s", delay_s, "Then wait this long [s]")->check(CLI::Range(0.0, 3600.0));
  app.add_option("--wait-timeout-s", wait_timeout_s, "Give up waiting for the phase after [s]")
      ->check(CLI::Range(0.0, 3600.0));
  app.add_option("--fault", fault_specs, "KIND:CHANNELS, e.g. nan:MOCAP_POSE,IMU or all:ALL");
  app.add_option("--repeat", repeat, "Send the message faults this many times")
      ->check(CLI::Range(1, 10000));
  app.add_option("--period-s", period_s, "... every this long [s]")->check(CLI::Range(0.0, 60.0));
  app.add_option("--base-wait-s", base_wait_s,
                 "Listen this long for live messages to mutate before the first injection [s]")
      ->check(CLI::Range(0.0, 60.0));
  app.add_option("--seed", seed, "Seed of the garbage bytes");
  app.add_option("--kill", kill_name, "SIGKILL this launcher process (name in the launch file)");
  app.add_option("--sim-control", sim_control, "e.g. mocap_off_s=2 or camera_off_s=1e6");
  app.add_option("--replay", replay_log, "Old session log to play onto the live URL")
      ->check(CLI::ExistingFile);
  app.add_option("--replay-s", replay_s, "Stop the replay after this long [s]")
      ->check(CLI::Range(0.0, 3600.0));
  CLI11_PARSE(app, argc, argv);
  try {
    args.finalize();
  } catch (const alight::RemapError& e) {
    std::fprintf(stderr, "alight-inject: %s\n", e.what());
    return 2;
  } catch (const alight::ParamError& e) {
    std::fprintf(stderr, "alight-inject: %s\n", e.what());
    return 2;
  }
  // Channels are named as in common/channels.hpp and --fault; on LCM they go by their remapped
  // names, as the session's processes were started with.
  const alight::ChannelRemap& lcm_name = args.remap;

  // Parse everything before touching the session.
  std::vector<std::pair<std::vector<faults::Kind>, std::vector<std::string>>> message_faults;
  for (const auto& spec : fault_specs) {
    const auto colon = spec.find(':');
    const std::string kind_text = spec.substr(0, colon);
    const std::string chans = colon == std::string::npos ? "ALL" : spec.substr(colon + 1);
    std::vector<faults::Kind> kinds;
    if (kind_text == "all") {
      kinds = faults::all_kinds();
    } else if (const auto k = faults::parse_kind(kind_text)) {
      kinds = {*k};
    } else {
      std::fprintf(stderr, "alight-inject: --fault %s: unknown kind '%s'\n", spec.c_str(),
                   kind_text.c_str());
      return 2;
    }
    std::vector<std::string> channels =
        chans == "ALL" ? faults::injectable_channels() : split(chans, ',');
    for (const auto& c : channels) {
      if (!faults::type_of_channel(c)) {
        std::fprintf(stderr, "alight-inject: --fault %s: unknown channel '%s'\n", spec.c_str(),
                     c.c_str());
        return 2;
      }
    }
    message_faults.emplace_back(kinds, channels);
  }
  alight::sim_control_t control{};
  control.mocap_off_s = control.camera_off_s = control.imu_off_s = -1;
  if (!sim_control.empty()) {
    for (const auto& kv : split(sim_control, ',')) {
      const auto eq = kv.find('=');
      double v = 0;
      try {
        v = std::stod(kv.substr(eq == std::string::npos ? kv.size() : eq + 1));
      } catch (const std::exception&) {
        std::fprintf(stderr, "alight-inject: --sim-control %s: not KEY=SECONDS\n", kv.c_str());
        return 2;
      }
      const std::string key = kv.substr(0, eq);
      if (key == "mocap_off_s") {
        control.mocap_off_s = v;
      } else if (key == "camera_off_s") {
        control.camera_off_s = v;
      } else if (key == "imu_off_s") {
        control.imu_off_s = v;
      } else {
        std::fprintf(stderr, "alight-inject: --sim-control: unknown key '%s'\n", key.c_str());
        return 2;
      }
    }
  }
  std::optional<std::regex> phase_re;
  try {
    if (!when_phase.empty()) phase_re = std::regex(when_phase);
  } catch (const std::regex_error&) {
    std::fprintf(stderr, "alight-inject: --when-phase '%s': not a regular expression\n",
                 when_phase.c_str());
    return 2;
  }

  lcm::LCM lcm(alight::with_receive_buffer(args.lcm_url));
  if (!lcm.good()) {
    std::fprintf(stderr, "alight-inject: cannot open LCM at %s\n", args.lcm_url.c_str());
    return 1;
  }
  Live live;
  struct Handler {
    Live* live;
    std::string status_channel, process_channel;
    void on(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
      const auto* p = static_cast<const uint8_t*>(rbuf->data);
      const auto* c = static_cast<const char*>(rbuf->data);
      if (live->sent.count(std::hash<std::string_view>{}(std::string_view(c, rbuf->data_size))))
        return;
      if (channel == status_channel) {
        alight::autonomy_status_t m;
        if (alight::decode_message(m, rbuf->data, rbuf->data_size) &&
            (!live->status || m.utime > live->status->utime))
          live->status = m;
      } else if (channel == process_channel) {
        alight::process_status_t m;
        if (alight::decode_message(m, rbuf->data, rbuf->data_size) &&
            (!live->processes || m.utime > live->processes->utime))
          live->processes = m;
      }
      live->newest[channel].assign(p, p + rbuf->data_size);
    }
  } handler{&live, lcm_name(alight::channels::kAutonomyStatus),
            lcm_name(alight::channels::kProcessStatus)};
  lcm.subscribe(".*", &Handler::on, &handler);
  const uint64_t own_source = alight::bus::draw_source_id();
  // Publishes `bytes` (an encoded message, no trailer) on `lcm_channel` as its live publisher.
  const auto publish = [&](const std::string& lcm_channel, faults::Bytes bytes) {
    uint64_t source = own_source, counter = 0;
    const auto it = live.newest.find(lcm_channel);
    if (it != live.newest.end()) {
      const auto r = alight::bus::split(it->second.data(), it->second.size());
      if (r.trailer) {
        source = r.trailer->source;
        counter = r.trailer->counter;
      }
    }
    alight::bus::Sealer sealer(source, args.bus_key);
    sealer.seal(bytes, lcm_channel,
                std::max<int64_t>(static_cast<int64_t>(counter) + 1, alight::wall_utime()));
    live.sent.insert(std::hash<std::string_view>{}(
        std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size())));
    return lcm.publish(lcm_channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  };

  if (phase_re) {
    const int64_t give_up = alight::steady_utime() + static_cast<int64_t>(wait_timeout_s * 1e6);
    while (!(live.status && std::regex_search(live.status->phase_name, *phase_re))) {
      if (alight::steady_utime() > give_up) {
        say("phase /" + when_phase + "/ not reached within " + std::to_string(wait_timeout_s) +
            " s; no fault injected");
        return 3;
      }
      lcm.handleTimeout(100);
    }
    say("phase " + live.status->phase_name + " reached");
  }
  spin_for(lcm, delay_s);

  if (!kill_name.empty()) {
    const int64_t give_up = alight::steady_utime() + 10000000;
    pid_t pid = 0;
    while (pid <= 0 && alight::steady_utime() < give_up) {
      if (live.processes)
        for (const auto& p : live.processes->processes)
          if (p.name == kill_name && p.state == alight::process_info_t::STATE_RUNNING) pid = p.pid;
      if (pid <= 0) lcm.handleTimeout(100);
    }
    if (pid <= 0) {
      say("no running process '" + kill_name + "' in PROCESS_STATUS");
      return 3;
    }
    const int rc = kill(pid, SIGKILL);
    say("SIGKILL " + kill_name + " (pid " + std::to_string(pid) + ")" +
        (rc == 0 ? "" : ": failed"));
  }
  if (!sim_control.empty()) {
    control.utime = alight::wall_utime();
    faults::Bytes bytes(static_cast<size_t>(control.getEncodedSize()));
    control.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    publish(lcm_name(alight::channels::kSimControl), std::move(bytes));
    say("SIM_CONTROL " + sim_control);
  }
  if (!message_faults.empty()) {
    spin_for(lcm, base_wait_s);
    std::mt19937_64 rng(seed);
    for (int i = 0; i < repeat; ++i) {
      int sent = 0;
      for (const auto& [kinds, channels] : message_faults)
        for (const auto& channel : channels) {
          const std::string type = *faults::type_of_channel(channel);
          const auto it = live.newest.find(lcm_name(channel));
          const faults::Bytes base = it == live.newest.end() ? faults::Bytes{} : it->second;
          for (const auto kind : kinds)
            for (const auto& bytes :
                 faults::generate(kind, type, base, alight::wall_utime(), rng)) {
              publish(lcm_name(channel), bytes);
              ++sent;
            }
        }
      say("round " + std::to_string(i + 1) + ": " + std::to_string(sent) + " hostile messages");
      if (i + 1 < repeat) spin_for(lcm, period_s);
    }
  }
  if (!replay_log.empty()) {
    say("replaying " + replay_log);
    const int rc = run_replay(args.lcm_url, replay_log, replay_s);
    say("replay ended (" + std::to_string(rc) + ")");
  }
  return 0;
}
