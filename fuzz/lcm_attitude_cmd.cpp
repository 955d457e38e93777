// ATTITUDE_CMD (attitude_cmd_t): decoded and converted as the simulated vehicle (alight-sim)
// does, and by the outer loop's own inverse conversion (tools, tests).
#include "fuzz/fuzz_support.hpp"
#include "outer_loop/convert.hpp"
#include "sim/sim_msgs.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  const auto msg = fuzz::decode<attitude_cmd_t>(data, size);
  if (!msg) return 0;
#ifdef ALIGHT_FUZZ_HAS_SIM_COMMAND_FROM_MSG
  std::string why;
  auto sim_cmd = sim::command_from_msg(*msg, &why);
#else
  auto sim_cmd = sim::from_msg(*msg);
#endif
  (void)fuzz::value_of(sim_cmd);
  auto ol_cmd = outer_loop::from_msg(*msg);
  if (const auto* cmd = fuzz::value_of(ol_cmd)) (void)outer_loop::to_msg(*cmd);
  return 0;
}
