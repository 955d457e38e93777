// A scenario file (config/scenarios/*.yaml) through the simulator's loader.
#include "fuzz/fuzz_support.hpp"
#include "sim/params.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  static fuzz::InputFile file("scenarios");
  const std::string& path = file.write(data, size);
  fuzz::expect_param_errors_only("sim::load_scenario", [&] { sim::load_scenario(path); });
  return 0;
}
