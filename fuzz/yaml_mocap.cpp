// alight-mocap's configuration file: mocap::load_params may only throw ParamError (exit 2 naming
// file, key and value), and what it accepts builds the room frame and the client.
#include "fuzz/fuzz_support.hpp"
#include "mocap/params.hpp"
#include "mocap/tracker.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  static fuzz::InputFile file("mocap");
  const std::string& path = file.write(data, size);
  fuzz::expect_param_errors_only("mocap::load_params", [&] {
    const mocap::MocapParams p = mocap::load_params(path);
    if (!mocap::parse_tracker(p.server.tracker)) fuzz::fail("accepted an unparsable tracker");
    mocap::TrackerClient client(p);
    (void)client.greeting(0);
  });
  return 0;
}
