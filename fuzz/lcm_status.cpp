// Status messages the ground station and the mission monitor consume: AUTONOMY_STATUS
// (autonomy_status_t), PROCESS_STATUS (process_status_t), SIM_TRUTH (sim_truth_t), NODE_STATUS
// (node_status_t). The first byte picks the type; the rest is the message.
#include <alight/node_status_t.hpp>
#include <alight/sim_truth_t.hpp>

#include "fuzz/fuzz_support.hpp"
#include "ground_station/commands.hpp"
#include "ground_station/state.hpp"
#include "tools/monitor.hpp"

// The station passes its own wall clock, never a time from the message.
constexpr int64_t kNow = 1'700'000'000'000'000;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  if (size < 1) return 0;
  const uint8_t kind = data[0] % 4;
  ++data;
  --size;
  ground_station::StationState state{ground_station::GroundStationParams{}};
  switch (kind) {
    case 0:
      if (const auto msg = fuzz::decode<autonomy_status_t>(data, size)) {
        state.on_status(*msg, kNow);
        (void)state.to_json(kNow);
        ground_station::CommandTracker tracker(1.0);
        tracker.sent("go", 1, 1, kNow);
        tracker.on_status(*msg, kNow + 100'000);
        (void)tracker.alarm(kNow + 2'000'000);
        tools::MissionMonitor monitor;
        (void)monitor.add(*msg);
        (void)monitor.add(*msg);
      }
      break;
    case 1:
      if (const auto msg = fuzz::decode<process_status_t>(data, size)) {
        (void)state.to_json(kNow);
      }
      break;
    case 2:
      if (const auto msg = fuzz::decode<sim_truth_t>(data, size)) {
        tools::MissionMonitor monitor;
        (void)monitor.add(*msg);
        (void)monitor.add(*msg);
      }
      break;
    case 3:
      (void)fuzz::decode<node_status_t>(data, size);
      break;
  }
  return 0;
}
