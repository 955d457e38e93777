// The ground station's parameter file through its loader.
#include "fuzz/fuzz_support.hpp"
#include "ground_station/params.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  static fuzz::InputFile file("station");
  const std::string& path = file.write(data, size);
  fuzz::expect_param_errors_only("ground_station::load_params",
                                 [&] { ground_station::load_params(path); });
  return 0;
}
