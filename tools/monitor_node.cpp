// alight-monitor: prints a mission's progress (phase changes, measurement count, estimate vs
// truth) and exits when it is over: 0 on success, 1 on failure, so a launch file can end the
// session with it (on_exit: shutdown).
#include <CLI/CLI.hpp>
#include <alight/autonomy_status_t.hpp>
#include <alight/sim_truth_t.hpp>
#include <iostream>

#include "common/node.hpp"
#include "tools/monitor.hpp"

int main(int argc, char** argv) {
  CLI::App app{"alight-monitor: follow a mission on LCM and exit when it is over"};
  alight::NodeArgs args;
  args.add_to(app, false);
  alight::tools::MonitorParams params;
  double wall_timeout_s = 0;
  app.add_option("--timeout-s", params.timeout_s, "Mission time limit (message time) [s]");
  app.add_option("--wall-timeout-s", wall_timeout_s,
                 "Also give up after this much wall time [s] (0: never)");
  CLI11_PARSE(app, argc, argv);
  return alight::run_node_main("alight-monitor", [&]() -> int {
    args.finalize();
    alight::Node node(args, "alight-monitor");
    alight::tools::MissionMonitor monitor(params);
    auto print = [](const std::vector<std::string>& lines) {
      for (const auto& l : lines) std::cout << l << std::endl;
    };
    node.on<alight::autonomy_status_t>(alight::channels::kAutonomyStatus,
                                       [&](const auto& m) { print(monitor.add(m)); });
    node.on<alight::sim_truth_t>(alight::channels::kSimTruth,
                                 [&](const auto& m) { print(monitor.add(m)); });
    const int64_t start = alight::wall_utime();
    while (!node.stopping() && monitor.end() == alight::tools::MissionMonitor::End::kNone) {
      node.spin_once(100);
      if (wall_timeout_s > 0 && alight::wall_utime() - start > wall_timeout_s * 1e6) {
        std::cout << "mission failed: no result within " << wall_timeout_s << " s of wall time"
                  << std::endl;
        return 1;
      }
    }
    return monitor.end() == alight::tools::MissionMonitor::End::kSuccess ? 0 : 1;
  });
}
