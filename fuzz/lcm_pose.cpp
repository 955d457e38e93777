// MOCAP_POSE (pose_t): decoded as every node does, converted (outer loop, autonomy, vision),
// kept in vision's pose history and shown by the ground station.
#include "common/msg_convert.hpp"
#include "common/pose_buffer.hpp"
#include "fuzz/fuzz_support.hpp"
#include "ground_station/state.hpp"

// The station passes its own wall clock, never a time from the message.
constexpr int64_t kNow = 1'700'000'000'000'000;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  const auto msg = fuzz::decode<pose_t>(data, size);
  if (!msg) return 0;
#ifdef ALIGHT_FUZZ_HAS_POSE_FROM_MSG
  std::string why;
  auto converted = pose_from_msg(*msg, &why);
#else
  auto converted = from_msg(*msg);
#endif
  if (const auto* pose = fuzz::value_of(converted)) {
    PoseBuffer poses;
    poses.add(*pose);
    (void)poses.at(msg->utime);
    (void)poses.at(msg->utime / 2);
  }
  ground_station::StationState state{ground_station::GroundStationParams{}};
  state.on_pose(*msg, kNow);
  (void)state.to_json(kNow);
  return 0;
}
