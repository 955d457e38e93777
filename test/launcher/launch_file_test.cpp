#include "launcher/launch_file.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "common/build_paths.hpp"

namespace alight::launcher {
namespace {

constexpr const char* kGood = R"(
name: test
lcm_url: udpm://239.255.76.67:7800?ttl=0
record: false
backoff: {initial_s: 0.02, max_s: 0.5}
processes:
  - name: sim
    command: [alight-sim, --scenario, "${ALIGHT_ROOT}/config/scenarios/landing_a.yaml"]
  - name: vision
    command: [alight-vision]
    restart: always
    max_restarts: 5
    start_delay_s: 0.5
    on_exit: shutdown
    env: {ALIGHT_SEED: "7"}
)";

std::string error_of(const std::string& yaml) {
  try {
    parse_launch_file(yaml, "bad.yaml");
  } catch (const ParamError& e) {
    return e.what();
  }
  return "no error";
}

TEST(LaunchFileTest, ParsesEveryField) {
  const LaunchFile lf = parse_launch_file(kGood, "good.yaml");
  EXPECT_EQ(lf.name, "test");
  EXPECT_FALSE(lf.record);
  EXPECT_DOUBLE_EQ(lf.backoff.initial_s, 0.02);
  EXPECT_DOUBLE_EQ(lf.backoff.max_s, 0.5);
  ASSERT_EQ(lf.processes.size(), 2u);
  EXPECT_EQ(lf.processes[0].restart, RestartPolicy::kOnFailure);
  EXPECT_EQ(lf.processes[0].max_restarts, -1);
  EXPECT_EQ(lf.processes[1].restart, RestartPolicy::kAlways);
  EXPECT_EQ(lf.processes[1].max_restarts, 5);
  EXPECT_TRUE(lf.processes[1].shutdown_on_exit);
  EXPECT_EQ(lf.processes[1].env.at("ALIGHT_SEED"), "7");
}

TEST(LaunchFileTest, BadValuesNameFileKeyAndValue) {
  EXPECT_EQ(error_of("name: x\nprocesses:\n  - {name: a, command: [a], restart: sometimes}\n"),
            "bad.yaml: processes[0].restart = sometimes: must be never, on-failure or always");
  EXPECT_EQ(error_of("name: x\nprocesses:\n  - {name: a, command: []}\n"),
            "bad.yaml: processes[0].command = []: must name a program");
  EXPECT_EQ(error_of("name: x\nprocesses: []\n"),
            "bad.yaml: processes = []: must list at least one process");
  EXPECT_EQ(error_of("name: x\nstop_timeout_s: 0\nprocesses:\n  - {name: a, command: [a]}\n"),
            "bad.yaml: stop_timeout_s = 0: must be > 0");
  EXPECT_NE(
      error_of("name: x\nprocesses:\n  - {name: a, command: [a]}\n  - {name: a, command: [b]}\n")
          .find("two processes have this name"),
      std::string::npos);
  EXPECT_NE(error_of("name: x\nprocesess: []\n").find("processes = <missing>"), std::string::npos);
  EXPECT_NE(error_of("name: x\nprocesses:\n  - {name: a, command: [a], restrat: never}\n")
                .find("processes[0].restrat = never: unknown key"),
            std::string::npos);
  EXPECT_NE(
      error_of(
          "name: x\nbackoff: {initial_s: 1, max_s: 0.5}\nprocesses:\n  - {name: a, command: [a]}\n")
          .find("backoff.max_s = 0.5"),
      std::string::npos);
}

// Issue 14: every timeout finite and bounded, named with its full key.
TEST(LaunchFileTest, TimeoutsAreFiniteAndBounded) {
  const std::string procs = "processes:\n  - {name: a, command: [a]}\n";
  EXPECT_EQ(error_of("name: x\nstop_timeout_s: .inf\n" + procs),
            "bad.yaml: stop_timeout_s = .inf: expected a finite number");
  EXPECT_EQ(error_of("name: x\nstop_timeout_s: 100\n" + procs),
            "bad.yaml: stop_timeout_s = 100: must be <= 60");
  EXPECT_EQ(error_of("name: x\nbackoff: {initial_s: 0.1, max_s: 7200}\n" + procs),
            "bad.yaml: backoff.max_s = 7200: must be <= 3600");
  EXPECT_EQ(error_of("name: x\nprocesses:\n  - {name: a, command: [a], start_delay_s: 601}\n"),
            "bad.yaml: processes[0].start_delay_s = 601: must be <= 600");
  EXPECT_EQ(
      error_of("name: x\nname: y\n" + procs),
      "bad.yaml: name = y: duplicate key (line 2): the key appears twice in the same mapping");
}

TEST(LaunchFileTest, SubstitutesKnownVariablesOnly) {
  const std::map<std::string, std::string> vars{{"A", "x"}, {"SESSION_DIR", "/s"}};
  EXPECT_EQ(substitute("${A}/b/${SESSION_DIR}", vars), "x/b//s");
  EXPECT_EQ(substitute("${UNKNOWN}-${A}", vars), "${UNKNOWN}-x");
  EXPECT_EQ(substitute("plain", vars), "plain");
  EXPECT_EQ(substitute("${unterminated", vars), "${unterminated");
}

// The vehicle file's geofences are the vehicle's (the shipped ones reach the ingress room behind
// its wall); the room flown in is the site's. Every shipped launch file that runs the outer loop
// or the autonomy hands them one (docs/configuration.md, "Sites").
TEST(ShippedLaunchFiles, TheOuterLoopAndTheAutonomyFlyInASite) {
  const std::filesystem::path dir = std::string(build::source_dir()) + "/config/launch";
  int checked = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const LaunchFile lf = load_launch_file(entry.path().string());
    for (const auto& p : lf.processes) {
      if (p.command.empty() ||
          (p.command[0] != "alight-autonomy" && p.command[0] != "alight-outer-loop"))
        continue;
      const auto site = std::find(p.command.begin(), p.command.end(), "--site");
      ASSERT_NE(site, p.command.end()) << entry.path() << ": " << p.name << " has no --site";
      ASSERT_NE(site + 1, p.command.end()) << entry.path();
      const bool simulated = entry.path().filename().string().rfind("sim_", 0) == 0;
      EXPECT_EQ(*(site + 1), simulated ? "${ALIGHT_SCENARIO}" : "${ALIGHT_SITE}")
          << entry.path() << ": " << p.name;
      ++checked;
    }
  }
  EXPECT_GE(checked, 15);
}

}  // namespace
}  // namespace alight::launcher
