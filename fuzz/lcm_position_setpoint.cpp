// POSITION_SETPOINT (position_setpoint_t): decoded and converted as the outer loop does.
#include "fuzz/fuzz_support.hpp"
#include "outer_loop/convert.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  const auto msg = fuzz::decode<position_setpoint_t>(data, size);
  if (!msg) return 0;
  auto converted = outer_loop::from_msg(*msg);
  if (const auto* sp = fuzz::value_of(converted)) (void)outer_loop::to_msg(*sp);
  return 0;
}
