// CAMERA / VISION_DIAG (image_t), raw and JPEG: decoded, converted to mono as vision does and to
// colour as the ground station does, then re-encoded to JPEG as the station's video stream does.
#include "common/channels.hpp"
#include "common/image_msg.hpp"
#include "fuzz/fuzz_support.hpp"
#include "ground_station/frame_store.hpp"
#include "ground_station/state.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  const auto msg = fuzz::decode<image_t>(data, size);
  if (!msg) return 0;
  std::string error;
  (void)image_from_msg(*msg, true, &error);
  (void)ground_station::frame_to_jpeg(*msg, 80, &error);
  ground_station::StationState state{ground_station::GroundStationParams{}};
  const int64_t now = 1'700'000'000'000'000;  // the station's own clock
  state.on_frame(channels::kCamera, msg->utime, now, now);
  (void)state.to_json(now);
  (void)metadata_int(*msg, "seq");
  (void)metadata_string(*msg, "exposure_us");
  return 0;
}
