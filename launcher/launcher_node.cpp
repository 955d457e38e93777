// alight-launch: the onboard launcher. Starts the processes of a launch file in order, writes each
// one's output to its own file in the session folder, restarts crashed ones with backoff, records
// the session with alight-record, reports every process's state on stdout and PROCESS_STATUS, and
// on SIGINT / SIGTERM stops everything in reverse order (SIGINT, then SIGKILL after a timeout). The
// anchor is libbot's bot-procman deputy.
#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <alight/process_status_t.hpp>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <optional>
#include <sstream>
#include <thread>

#include "common/build_paths.hpp"
#include "common/node.hpp"
#include "common/operator_auth.hpp"
#include "common/params.hpp"
#include "launcher/bus_exposure.hpp"
#include "launcher/launch_file.hpp"
#include "launcher/process_tracker.hpp"

namespace fs = std::filesystem;
using alight::launcher::LaunchFile;
using alight::launcher::ProcessSpec;
using alight::launcher::ProcessTracker;
using alight::launcher::ProcState;

namespace {

std::atomic<int> g_stop_signal{0};
extern "C" void on_stop_signal(int sig) { g_stop_signal = sig; }

std::string clock_text() {
  const auto now = std::chrono::system_clock::now();
  const std::time_t t = std::chrono::system_clock::to_time_t(now);
  const auto ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(now.time_since_epoch()).count() % 1000;
  char buf[32];
  std::strftime(buf, sizeof buf, "%H:%M:%S", std::localtime(&t));
  char out[48];
  std::snprintf(out, sizeof out, "%s.%03lld", buf, static_cast<long long>(ms));
  return out;
}

class Launcher {
 public:
  Launcher(LaunchFile lf, std::string lf_file, fs::path session_dir, fs::path bin_dir,
           std::string root)
      : lf_(std::move(lf)),
        lf_file_(std::move(lf_file)),
        session_(std::move(session_dir)),
        bin_dir_(std::move(bin_dir)),
        root_(std::move(root)) {
    log_.open(session_ / "launcher.log", std::ios::app);
    // The launcher's environment first (e.g. ALIGHT_SCENARIO from scripts/demo), then the
    // built-in variables, which win.
    for (char** e = environ; *e; ++e) {
      const std::string kv = *e;
      const size_t eq = kv.find('=');
      if (eq != std::string::npos) vars_[kv.substr(0, eq)] = kv.substr(eq + 1);
    }
    vars_["ALIGHT_ROOT"] = root_;
    vars_["SESSION_DIR"] = session_.string();
    vars_["LCM_URL"] = lf_.lcm_url;
    if (lf_.record) {
      ProcessSpec logger;
      logger.name = "recorder";
      // alight-record, not lcm-logger: it keeps every message with both cores busy, and counts
      // what it could not keep (tools/record_main.cpp). Its log is lcm-logger's format.
      logger.command = {"alight-record",     "--lcm-url",
                        lf_.lcm_url,         "-c",
                        lf_.record_channels, (session_ / "session.lcmlog").string()};
      logger.restart = alight::launcher::RestartPolicy::kAlways;
      trackers_.push_back(std::make_unique<ProcessTracker>(logger, lf_.backoff));
    }
    for (const auto& p : lf_.processes)
      trackers_.push_back(std::make_unique<ProcessTracker>(p, lf_.backoff));
    setup_bus_key();
    lcm_ = std::make_unique<lcm::LCM>(lf_.lcm_url);
    if (!lcm_->good()) say("warning: cannot open LCM at " + lf_.lcm_url + "; no PROCESS_STATUS");
  }

  ~Launcher() {
    // A key made for this launch dies with it.
    if (!made_key_path_.empty()) std::remove(made_key_path_.c_str());
  }

  int run() {
    say("session " + session_.string());
    for (const auto& w : alight::launcher::url_warnings(lf_.lcm_url, key_.has_value()))
      say("WARNING: " + w);
    for (size_t i = 0; i < trackers_.size() && !g_stop_signal; ++i) {
      auto& t = *trackers_[i];
      // The logger must subscribe before anyone publishes.
      const double delay = i > 0 && lf_.record && i == 1 ? std::max(0.3, t.spec().start_delay_s)
                                                         : t.spec().start_delay_s;
      wait_while_supervising(delay);
      if (g_stop_signal || ended_) break;
      start(t);
    }
    const int64_t check_bus_at = alight::steady_utime() + 1'000'000;
    bool bus_checked = false;
    while (!g_stop_signal && !ended_) {
      supervise();
      if (!bus_checked && alight::steady_utime() >= check_bus_at) {
        bus_checked = true;
        check_bus_joins();
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (g_stop_signal) say(std::string("received ") + strsignal(g_stop_signal) + ", stopping");
    stop_all();
    publish_status();
    summary();
    return exit_code_;
  }

 private:
  // bus_key: a key file, a fresh key for this launch, or none. The children get it as
  // ALIGHT_BUS_KEY_FILE (or no such variable at all), the launcher signs PROCESS_STATUS with it.
  void setup_bus_key() {
    const std::string spec = alight::launcher::substitute(lf_.bus_key, vars_);
    std::string path;
    if (spec == "auto") {
      const char* env = std::getenv("ALIGHT_BUS_KEY_FILE");
      path = env && *env ? env : make_launch_key();
    } else if (spec != "none") {
      path = spec;
    }
    if (!path.empty()) {
      std::vector<std::string> warnings;
      try {
        key_ = alight::bus::load_bus_key(path, &warnings);
      } catch (const alight::KeyFileError& e) {
        throw alight::ParamError(lf_file_, "bus_key", spec, e.what());
      }
      for (const auto& w : warnings) say("warning: " + w);
      key_path_ = path;
      say("bus signed with key id " + std::to_string(key_->id) + " (" +
          (made_key_path_.empty() ? path : "made for this launch") + ")");
    }
    sealer_.emplace(alight::bus::draw_source_id(), key_);
  }

  std::string make_launch_key() {
    const char* xdg = std::getenv("XDG_RUNTIME_DIR");
    const fs::path dir = xdg && *xdg ? fs::path(xdg) / "alight"
                                     : fs::path("/tmp") / ("alight-" + std::to_string(getuid()));
    fs::create_directories(dir);
    fs::permissions(dir, fs::perms::owner_all, fs::perm_options::replace);
    const fs::path file = dir / ("bus-" + std::to_string(getpid()) + ".key");
    const int fd = open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    if (fd < 0) throw std::runtime_error("cannot write the bus key " + file.string());
    const std::string hex = alight::random_key_hex();
    const bool ok = write(fd, hex.data(), hex.size()) == static_cast<ssize_t>(hex.size());
    close(fd);
    if (!ok) throw std::runtime_error("cannot write the bus key " + file.string());
    made_key_path_ = file.string();
    return made_key_path_;
  }

  void check_bus_joins() {
    const auto u = alight::launcher::parse_udpm_url(lf_.lcm_url);
    if (!u) return;
    std::ifstream f("/proc/net/igmp");
    std::stringstream text;
    text << f.rdbuf();
    const auto joined = alight::launcher::interfaces_joined(text.str(), u->group);
    for (const auto& w : alight::launcher::join_warnings(lf_.lcm_url, key_.has_value(), joined))
      say("WARNING: " + w);
  }

  void say(const std::string& text) {
    const std::string line = "[alight-launch " + clock_text() + "] " + text;
    std::cout << line << std::endl;
    log_ << line << std::endl;
  }

  void wait_while_supervising(double seconds) {
    const int64_t end = alight::steady_utime() + static_cast<int64_t>(seconds * 1e6);
    while (alight::steady_utime() < end && !g_stop_signal && !ended_) {
      supervise();
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    supervise();
  }

  // Finds command[0]: next to alight-launch first, then on PATH.
  std::string resolve(const std::string& program) const {
    if (program.find('/') != std::string::npos) return program;
    const fs::path local = bin_dir_ / program;
    if (access(local.c_str(), X_OK) == 0) return local.string();
    const char* path = std::getenv("PATH");
    std::string dirs = path ? path : "/usr/bin:/bin";
    size_t start = 0;
    while (start <= dirs.size()) {
      const size_t end = dirs.find(':', start);
      const fs::path cand = fs::path(dirs.substr(start, end - start)) / program;
      if (access(cand.c_str(), X_OK) == 0) return cand.string();
      if (end == std::string::npos) break;
      start = end + 1;
    }
    return "";
  }

  void start(ProcessTracker& t) {
    const int64_t now = alight::steady_utime();
    std::vector<std::string> argv;
    for (const auto& a : t.spec().command) argv.push_back(alight::launcher::substitute(a, vars_));
    const std::string program = resolve(argv[0]);
    if (program.empty()) {
      t.start_failed("program not found: " + argv[0], now);
      report(t);
      return;
    }
    const fs::path out_path = session_ / (t.spec().name + ".log");
    const int out = open(out_path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
    if (out < 0) {
      t.start_failed("cannot open " + out_path.string() + ": " + std::strerror(errno), now);
      report(t);
      return;
    }
    const std::string banner = "=== " + clock_text() + " start #" +
                               std::to_string(t.restarts() + (t.state() == ProcState::kBackoff)) +
                               ": " + program + " ===\n";
    (void)!write(out, banner.data(), banner.size());
    int exec_pipe[2];
    if (pipe2(exec_pipe, O_CLOEXEC) != 0) throw std::runtime_error("pipe2 failed");
    const pid_t launcher_pid = getpid();
    const pid_t pid = fork();
    if (pid < 0) {
      close(out);
      close(exec_pipe[0]);
      close(exec_pipe[1]);
      t.start_failed(std::string("fork failed: ") + std::strerror(errno), now);
      report(t);
      return;
    }
    if (pid == 0) {
      // Child: own process group (so a stop reaches its children too), dies with the launcher.
      setpgid(0, 0);
      prctl(PR_SET_PDEATHSIG, SIGTERM);
      if (getppid() != launcher_pid) _exit(1);
      signal(SIGINT, SIG_DFL);
      signal(SIGTERM, SIG_DFL);
      const int devnull = open("/dev/null", O_RDONLY);
      dup2(devnull, 0);
      dup2(out, 1);
      dup2(out, 2);
      setenv("LCM_DEFAULT_URL", lf_.lcm_url.c_str(), 1);
      setenv("ALIGHT_SESSION_DIR", session_.c_str(), 1);
      if (key_path_.empty())
        unsetenv("ALIGHT_BUS_KEY_FILE");
      else
        setenv("ALIGHT_BUS_KEY_FILE", key_path_.c_str(), 1);
      for (const auto& [k, v] : t.spec().env)
        setenv(k.c_str(), alight::launcher::substitute(v, vars_).c_str(), 1);
      std::vector<char*> cargv;
      for (auto& a : argv) cargv.push_back(a.data());
      cargv.push_back(nullptr);
      execv(program.c_str(), cargv.data());
      const int err = errno;
      (void)!write(exec_pipe[1], &err, sizeof err);
      _exit(127);
    }
    setpgid(pid, pid);  // also here: no race with a stop right after the fork
    close(out);
    close(exec_pipe[1]);
    int err = 0;
    const ssize_t n = read(exec_pipe[0], &err, sizeof err);
    close(exec_pipe[0]);
    if (n == sizeof err) {
      waitpid(pid, nullptr, 0);
      t.start_failed("cannot execute " + program + ": " + std::strerror(err), now);
    } else {
      t.started(pid, now);
    }
    report(t);
  }

  void report(const ProcessTracker& t) {
    std::string text = t.spec().name + ": " + to_string(t.state());
    if (t.state() == ProcState::kRunning) text += " (pid " + std::to_string(t.pid()) + ")";
    if (!t.last_reason().empty()) text += ", " + t.last_reason();
    if (t.state() == ProcState::kBackoff) {
      char buf[64];
      std::snprintf(buf, sizeof buf, "; restart %d in %.3f s", t.restarts() + 1, t.backoff_s());
      text += buf;
    }
    if (t.restarts() > 0) text += " [restarts: " + std::to_string(t.restarts()) + "]";
    say(text);
    status_dirty_ = true;
  }

  ProcessTracker* find(pid_t pid) {
    for (auto& t : trackers_)
      if (t->pid() == pid) return t.get();
    return nullptr;
  }

  void reap() {
    int status = 0;
    pid_t pid;
    while ((pid = waitpid(-1, &status, WNOHANG)) > 0) {
      ProcessTracker* t = find(pid);
      if (!t) continue;
      // Anything the process left behind in its group goes with it.
      kill(-pid, SIGKILL);
      if (WIFEXITED(status)) {
        t->exited(WEXITSTATUS(status), 0, alight::steady_utime());
      } else if (WIFSIGNALED(status)) {
        t->exited(0, WTERMSIG(status), alight::steady_utime());
      }
      report(*t);
      if (t->ends_session() && !ended_) {
        ended_ = true;
        const auto info = t->info();
        exit_code_ = info.signal ? 128 + info.signal : info.exit_code;
        say(t->spec().name + " ended the session (on_exit: shutdown)");
      }
    }
  }

  void supervise() {
    reap();
    const int64_t now = alight::steady_utime();
    if (!ended_ && !g_stop_signal)
      for (auto& t : trackers_)
        if (t->restart_due(now)) start(*t);
    if (status_dirty_ || now >= next_status_utime_) publish_status();
  }

  void publish_status() {
    status_dirty_ = false;
    const int64_t now = alight::steady_utime();
    next_status_utime_ = now + static_cast<int64_t>(lf_.status_period_s * 1e6);
    if (!lcm_->good()) return;
    // The trackers and every delay run on the steady clock; the report is stamped with the wall
    // clock, and each start time is carried over to it.
    const int64_t wall = alight::wall_utime();
    alight::process_status_t msg{};
    msg.utime = wall;
    msg.launch_name = lf_.name;
    msg.session_dir = session_.string();
    for (const auto& t : trackers_) {
      alight::process_info_t info = t->info();
      if (info.started_utime != 0) info.started_utime = wall - (now - info.started_utime);
      msg.processes.push_back(info);
    }
    msg.n = static_cast<int32_t>(msg.processes.size());
    std::vector<uint8_t> bytes(static_cast<size_t>(msg.getEncodedSize()));
    msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    sealer_->seal(bytes, lf_.status_channel, wall);
    lcm_->publish(lf_.status_channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  }

  void stop_all() {
    for (auto& t : trackers_) t->stopping();
    // Reverse start order: the logger (started first) records everything until the end.
    for (auto it = trackers_.rbegin(); it != trackers_.rend(); ++it) {
      ProcessTracker& t = **it;
      const int pid = t.pid();
      if (pid <= 0) continue;
      // The logger goes last; give the final statuses time to reach it.
      if (lf_.record && &t == trackers_.front().get())
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
      kill(-pid, SIGINT);
      const int64_t deadline =
          alight::steady_utime() + static_cast<int64_t>(lf_.stop_timeout_s * 1e6);
      while (t.pid() == pid && alight::steady_utime() < deadline) {
        reap();
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      if (t.pid() == pid) {
        say(t.spec().name + ": did not stop within " + std::to_string(lf_.stop_timeout_s) +
            " s of SIGINT, sending SIGKILL");
        kill(-pid, SIGKILL);
        while (t.pid() == pid) {
          reap();
          std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
      }
      publish_status();
    }
  }

  void summary() {
    say("session ended; processes:");
    for (const auto& t : trackers_) {
      const auto i = t->info();
      say("  " + t->spec().name + ": " + to_string(t->state()) + ", restarts " +
          std::to_string(i.restarts) +
          (t->last_reason().empty() ? "" : ", last: " + t->last_reason()));
    }
    if (lf_.record) say("log: " + (session_ / "session.lcmlog").string());
  }

  LaunchFile lf_;
  std::string lf_file_;
  std::optional<alight::bus::BusKey> key_;
  std::string key_path_, made_key_path_;
  std::optional<alight::bus::Sealer> sealer_;
  fs::path session_, bin_dir_;
  std::string root_;
  std::map<std::string, std::string> vars_;
  std::vector<std::unique_ptr<ProcessTracker>> trackers_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::ofstream log_;
  bool status_dirty_ = true;
  bool ended_ = false;
  int exit_code_ = 0;
  int64_t next_status_utime_ = 0;
};

fs::path make_session_dir(const fs::path& root, const std::string& name) {
  const std::time_t t = std::time(nullptr);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", std::localtime(&t));
  fs::path dir = root / (std::string(stamp) + "-" + name);
  for (int i = 2; fs::exists(dir); ++i)
    dir = root / (std::string(stamp) + "-" + name + "-" + std::to_string(i));
  fs::create_directories(dir);
  return dir;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"alight-launch: start, supervise, record and stop the onboard processes"};
  std::string launch_path, log_root, lcm_url;
  bool no_record = false;
  app.add_option("launchfile", launch_path, "Launch file (YAML)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--log-root", log_root,
                 "Folder for session folders (default: $ALIGHT_LOG_ROOT, else <source>/logs)");
  app.add_option("--lcm-url", lcm_url, "Override the launch file's LCM URL");
  app.add_flag("--no-record", no_record, "Do not record the session (alight-record)");
  CLI11_PARSE(app, argc, argv);

  return alight::run_node_main("alight-launch", [&]() -> int {
    LaunchFile lf = alight::launcher::load_launch_file(launch_path);
    if (!lcm_url.empty()) lf.lcm_url = lcm_url;
    if (no_record) lf.record = false;
    const char* env_root = std::getenv("ALIGHT_ROOT");
    const std::string root = env_root && *env_root ? env_root : alight::build::source_dir();
    if (log_root.empty()) {
      const char* env_logs = std::getenv("ALIGHT_LOG_ROOT");
      log_root = env_logs && *env_logs ? env_logs : root + "/logs";
    }
    const fs::path session = make_session_dir(log_root, lf.name);
    fs::copy_file(launch_path, session / "launch.yaml");

    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    sigaction(SIGHUP, &sa, nullptr);
    const fs::path bin_dir = fs::read_symlink("/proc/self/exe").parent_path();
    Launcher launcher(std::move(lf), launch_path, session, bin_dir, root);
    return launcher.run();
  });
}
