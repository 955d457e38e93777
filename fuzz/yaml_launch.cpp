// A launch file (config/launch/*.yaml) through the launcher's parser, and the ${VAR}
// substitution it applies to each command.
#include "fuzz/fuzz_support.hpp"
#include "launcher/launch_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  const std::string text(reinterpret_cast<const char*>(data), size);
  fuzz::expect_param_errors_only("launcher::parse_launch_file", [&] {
    const launcher::LaunchFile lf = launcher::parse_launch_file(text, "fuzz.yaml");
    const std::map<std::string, std::string> vars{{"ALIGHT_SEED", "1"}, {"X", "${X}"}};
    for (const auto& p : lf.processes)
      for (const auto& arg : p.command) (void)launcher::substitute(arg, vars);
  });
  (void)launcher::substitute(text, {{"A", "${A}"}, {"", "x"}});
  return 0;
}
