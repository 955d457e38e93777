// POSITION_SETPOINT (position_setpoint_t): decoded and converted as the outer loop does.
#include "fuzz/fuzz_support.hpp"
#include "outer_loop/convert.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  const auto msg = fuzz::decode<position_setpoint_t>(data, size);
  if (!msg) return 0;
#ifdef ALIGHT_FUZZ_HAS_SETPOINT_FROM_MSG
  std::string why;
  auto converted = outer_loop::setpoint_from_msg(*msg, &why);
#else
  auto converted = outer_loop::from_msg(*msg);
#endif
  if (const auto* sp = fuzz::value_of(converted)) (void)outer_loop::to_msg(*sp);
  return 0;
}
