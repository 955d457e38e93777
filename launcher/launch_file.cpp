#include "launcher/launch_file.hpp"

#include <set>

namespace alight::launcher {

void BackoffParams::validate() const {
  param_check(initial_s > 0, "backoff.initial_s", initial_s, "must be > 0");
  param_check(max_s >= initial_s, "backoff.max_s", max_s, "must be >= backoff.initial_s");
  param_check(reset_after_s > 0, "backoff.reset_after_s", reset_after_s, "must be > 0");
  // Upper bounds: a supervisor that waits hours to restart or to stop is not supervising.
  param_check(initial_s <= 60, "backoff.initial_s", initial_s, "must be <= 60");
  param_check(max_s <= 3600, "backoff.max_s", max_s, "must be <= 3600");
  param_check(reset_after_s <= 3600, "backoff.reset_after_s", reset_after_s, "must be <= 3600");
  param_check(start_limit_burst >= 0 && start_limit_burst <= 1000, "backoff.start_limit_burst",
              start_limit_burst, "must be in [0, 1000] (0: no limit)");
  param_check(start_limit_interval_s > 0 && start_limit_interval_s <= 86400,
              "backoff.start_limit_interval_s", start_limit_interval_s, "must be in (0, 86400] s");
}

void LaunchFile::validate() const {
  param_check(!name.empty(), "name", name, "must not be empty");
  param_check(stop_timeout_s > 0, "stop_timeout_s", stop_timeout_s, "must be > 0");
  param_check(status_period_s > 0, "status_period_s", status_period_s, "must be > 0");
  param_check(stop_timeout_s <= 60, "stop_timeout_s", stop_timeout_s, "must be <= 60");
  param_check(status_period_s <= 60, "status_period_s", status_period_s, "must be <= 60");
  backoff.validate();
}

namespace {
ProcessSpec parse_process(const ParamNode& n) {
  ProcessSpec p;
  n.require("name", p.name);
  n.check(!p.name.empty() && p.name.find_first_of("/ \t") == std::string::npos, "name",
          "must be a non-empty word (it names the log file)");
  n.require("command", p.command);
  n.check(!p.command.empty() && !p.command[0].empty(), "command", "must name a program");
  std::string restart = "on-failure";
  n.read("restart", restart);
  if (restart == "never") {
    p.restart = RestartPolicy::kNever;
  } else if (restart == "on-failure") {
    p.restart = RestartPolicy::kOnFailure;
  } else if (restart == "always") {
    p.restart = RestartPolicy::kAlways;
  } else {
    throw n.error("restart", restart, "must be never, on-failure or always");
  }
  n.read("max_restarts", p.max_restarts);
  n.check(p.max_restarts >= -1, "max_restarts", "must be >= 0, or -1 for unlimited");
  n.read("start_delay_s", p.start_delay_s);
  n.check(p.start_delay_s >= 0, "start_delay_s", "must be >= 0");
  n.check(p.start_delay_s <= 600, "start_delay_s", "must be <= 600");
  std::string on_exit = "restart";
  n.read("on_exit", on_exit);
  if (on_exit != "restart" && on_exit != "shutdown")
    throw n.error("on_exit", on_exit, "must be restart or shutdown");
  p.shutdown_on_exit = on_exit == "shutdown";
  if (auto env = n.optional_child("env")) {
    for (const auto& kv : env->yaml()) {
      const auto key = kv.first.as<std::string>();
      p.env[key] = env->get<std::string>(key);
    }
  }
  n.finish();
  return p;
}

LaunchFile parse_root(const ParamNode& root) {
  LaunchFile lf;
  root.require("name", lf.name);
  root.read("lcm_url", lf.lcm_url);
  root.read("bus_key", lf.bus_key);
  root.check(!lf.bus_key.empty(), "bus_key", "must be auto, none or a key file");
  root.read("record", lf.record);
  root.read("record_channels", lf.record_channels);
  root.read("stop_timeout_s", lf.stop_timeout_s);
  root.read("status_period_s", lf.status_period_s);
  root.read("status_channel", lf.status_channel);
  if (auto b = root.optional_child("backoff")) {
    b->read("initial_s", lf.backoff.initial_s);
    b->read("max_s", lf.backoff.max_s);
    b->read("reset_after_s", lf.backoff.reset_after_s);
    b->read("start_limit_burst", lf.backoff.start_limit_burst);
    b->read("start_limit_interval_s", lf.backoff.start_limit_interval_s);
    b->finish();
  }
  std::set<std::string> names;
  for (const auto& pn : root.child_list("processes")) {
    lf.processes.push_back(parse_process(pn));
    if (!names.insert(lf.processes.back().name).second)
      throw pn.error("name", lf.processes.back().name, "two processes have this name");
  }
  root.check(!lf.processes.empty(), "processes", "must list at least one process");
  root.finish();
  root.validate(lf);
  return lf;
}
}  // namespace

LaunchFile parse_launch_file(const std::string& yaml, const std::string& file_name) {
  return parse_root(ParamNode::from_string(yaml, file_name));
}

LaunchFile load_launch_file(const std::string& path) {
  return parse_root(ParamNode::load_file(path));
}

std::string substitute(const std::string& arg, const std::map<std::string, std::string>& vars) {
  std::string out;
  size_t i = 0;
  while (i < arg.size()) {
    const size_t start = arg.find("${", i);
    if (start == std::string::npos) break;
    const size_t end = arg.find('}', start);
    if (end == std::string::npos) break;
    out += arg.substr(i, start - i);
    const auto it = vars.find(arg.substr(start + 2, end - start - 2));
    out += it != vars.end() ? it->second : arg.substr(start, end - start + 1);
    i = end + 1;
  }
  return out + arg.substr(i);
}

}  // namespace alight::launcher
