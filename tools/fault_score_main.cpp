// alight-fault-score LOG [--expected-exit NAME] [--disarm-max-height-m H]: the outcome of one
// fault-campaign run (tools/fault_score.hpp) as one JSON object. Exit status: 0 when the
// campaign's goal held, 1 when it did not, 2 when the log cannot be read.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <lcm/lcm-cpp.hpp>

#include "common/bus_auth.hpp"
#include "common/channels.hpp"
#include "common/decode.hpp"
#include "tools/fault_score.hpp"

namespace {

// lcm-gen's decode_message() dies of SIGSEGV on a string length of INT32_MIN (lcm-gen's
// `len - 1` wraps): the referee walks the strings of the types it reads itself first, so the log
// of a campaign that injected exactly that can still be judged.
bool strings_ok(const std::string& channel, const void* data, size_t size) {
  alight::wire::Reader r(data, size);
  int32_t n = 0;
  if (channel == alight::channels::kAutonomyStatus)
    return r.skip(8 + 8 + 1 + 1) && r.string() && r.string();
  if (channel == alight::channels::kSimTruth) return r.skip(8 + 8) && r.string();
  if (channel == alight::channels::kProcessStatus) {
    if (!r.skip(8 + 8) || !r.string() || !r.string() || !r.int32(n) || n < 0) return false;
    for (int32_t i = 0; i < n; ++i)  // name, then pid .. backoff_s
      if (!r.string() || !r.skip(4 + 1 + 4 + 4 + 4 + 8 + 8)) return false;
    return true;
  }
  if (channel == alight::channels::kNodeStatus) {
    // pid, uptime_s, source, signed_bus, clock_from_inputs, wall_clock_steps
    if (!r.skip(8 + 8) || !r.string() || !r.skip(4 + 8 + 8 + 1 + 1 + 4) || !r.int32(n) || n < 0)
      return false;
    for (int32_t i = 0; i < n; ++i)  // channel, then 9 int64 counters
      if (!r.string() || !r.skip(9 * 8)) return false;
    return true;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"alight-fault-score: outcome of a fault-campaign run from its session log"};
  std::string log_path;
  alight::tools::FaultScoreParams params;
  app.add_option("log", log_path, "Session log (.lcmlog)")->required()->check(CLI::ExistingFile);
  app.add_option("--expected-exit", params.expected_exit,
                 "Launcher process the campaign killed (its one SIGKILL is not a failure)");
  app.add_option("--disarm-max-height-m", params.disarm_max_height_m,
                 "Highest acceptable disarm above the surface [m]")
      ->check(CLI::Range(0.0, 10.0));
  std::string key_file;
  app.add_option("--bus-key", key_file,
                 "The session's bus key: only messages signed with it are the vehicle's");
  CLI11_PARSE(app, argc, argv);
  std::optional<alight::bus::BusKey> key;
  if (!key_file.empty()) {
    try {
      key = alight::bus::load_bus_key(key_file);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "alight-fault-score: --bus-key: %s\n", e.what());
      return 2;
    }
  }

  lcm::LogFile log(log_path, "r");
  if (!log.good()) {
    std::fprintf(stderr, "alight-fault-score: cannot read %s\n", log_path.c_str());
    return 2;
  }
  alight::tools::FaultScorer scorer(params);
  // Injected garbage fails to decode here too: skipped without a word. What the vehicle's own
  // processes published carries their origin trailer (signed with the bus key, when given); an
  // outsider's message (the attack campaign's) does not, and is not the vehicle's.
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev; ev = log.readNextEvent()) {
    const auto feed = [&](auto msg) {
      const auto size = static_cast<size_t>(ev->datalen);
      const auto r = alight::bus::split(ev->data, size);
      if (!r.trailer) return;
      if (key &&
          (r.trailer->key_id != key->id ||
           alight::bus::compute_tag(*key, ev->channel, r.payload, *r.trailer) != r.trailer->tag))
        return;
      if (strings_ok(ev->channel, ev->data, size) && alight::decode_message(msg, ev->data, size))
        scorer.add(msg, ev->timestamp);
    };
    if (ev->channel == alight::channels::kSimTruth) {
      feed(alight::sim_truth_t{});
    } else if (ev->channel == alight::channels::kAttitudeCmd) {
      feed(alight::attitude_cmd_t{});
    } else if (ev->channel == alight::channels::kAutonomyStatus) {
      feed(alight::autonomy_status_t{});
    } else if (ev->channel == alight::channels::kProcessStatus) {
      feed(alight::process_status_t{});
    } else if (ev->channel == alight::channels::kNodeStatus) {
      feed(alight::node_status_t{});
    }
  }
  const auto r = scorer.result();
  std::cout << r.to_json();
  return r.ok ? 0 : 1;
}
