// IMU (imu_t): decoded and converted as autonomy does.
#include "autonomy/convert.hpp"
#include "fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  const auto msg = fuzz::decode<imu_t>(data, size);
  if (!msg) return 0;
#ifdef ALIGHT_FUZZ_HAS_IMU_FROM_MSG
  std::string why;
  auto converted = autonomy::imu_from_msg(*msg, &why);
#else
  auto converted = autonomy::from_msg(*msg);
#endif
  if (const auto* imu = fuzz::value_of(converted)) (void)autonomy::to_msg(*imu, msg->seq);
  return 0;
}
