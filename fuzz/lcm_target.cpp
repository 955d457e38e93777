// VISION_TARGET (target_t): decoded and converted as autonomy does, and shown by the ground
// station.
#include "autonomy/convert.hpp"
#include "fuzz/fuzz_support.hpp"
#include "ground_station/state.hpp"

// The station passes its own wall clock, never a time from the message.
constexpr int64_t kNow = 1'700'000'000'000'000;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  const auto msg = fuzz::decode<target_t>(data, size);
  if (!msg) return 0;
#ifdef ALIGHT_FUZZ_HAS_TARGET_FROM_MSG
  std::string why;
  auto converted = autonomy::target_from_msg(*msg, &why);
#else
  auto converted = autonomy::from_msg(*msg);
#endif
  if (const auto* m = fuzz::value_of(converted)) (void)autonomy::to_msg(*m, msg->seq);
  ground_station::StationState state{ground_station::GroundStationParams{}};
  state.on_target(*msg, kNow);
  (void)state.to_json(kNow);
  return 0;
}
