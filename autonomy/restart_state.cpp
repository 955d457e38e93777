#include "autonomy/restart_state.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

namespace alight::autonomy {

namespace {
constexpr const char* kMagic = "alight-autonomy-state 1";

const char* failsafe_key(Failsafe f) {
  switch (f) {
    case Failsafe::kNone:
      return "NONE";
    case Failsafe::kPoseStale:
      return "POSE_STALE";
    case Failsafe::kPoseLost:
      return "POSE_LOST";
    case Failsafe::kOperatorAbort:
      return "OPERATOR_ABORT";
    case Failsafe::kKill:
      return "KILL";
    case Failsafe::kEstimateLost:
      return "ESTIMATE_LOST";
    case Failsafe::kVisionDisagrees:
      return "VISION_DISAGREES";
    case Failsafe::kPlatformTooFast:
      return "PLATFORM_TOO_FAST";
  }
  return "NONE";
}

std::optional<Failsafe> failsafe_from_key(const std::string& s) {
  for (Failsafe f : {Failsafe::kNone, Failsafe::kPoseStale, Failsafe::kPoseLost,
                     Failsafe::kOperatorAbort, Failsafe::kKill, Failsafe::kEstimateLost,
                     Failsafe::kVisionDisagrees, Failsafe::kPlatformTooFast}) {
    if (s == failsafe_key(f)) return f;
  }
  return std::nullopt;
}

std::optional<int64_t> to_int(const std::string& s) {
  if (s.empty() || s.size() > 20) return std::nullopt;
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(s.c_str(), &end, 10);
  if (errno != 0 || end != s.c_str() + s.size()) return std::nullopt;
  return static_cast<int64_t>(v);
}

bool fail(std::string* why, const std::string& text) {
  if (why) *why = text;
  return false;
}
}  // namespace

std::string format_record(const RestartRecord& r) {
  std::ostringstream os;
  os << kMagic << "\n"
     << "boot_id " << r.boot_id << "\n"
     << "session " << r.session << "\n"
     << "steady_utime " << r.steady_utime << "\n"
     << "killed " << (r.state.killed ? 1 : 0) << "\n"
     << "failsafe " << failsafe_key(r.state.failsafe) << "\n"
     << "motors_on " << (r.state.motors_on ? 1 : 0) << "\n";
  return os.str();
}

std::optional<RestartRecord> parse_record(const std::string& text, std::string* why) {
  std::istringstream in(text);
  std::string line;
  if (!std::getline(in, line) || line != kMagic) {
    fail(why, "not an autonomy state record (first line)");
    return std::nullopt;
  }
  std::map<std::string, std::string> kv;
  while (std::getline(in, line)) {
    const auto sp = line.find(' ');
    if (sp == std::string::npos) continue;
    kv[line.substr(0, sp)] = line.substr(sp + 1);
  }
  RestartRecord r;
  const auto need = [&](const char* k) -> const std::string* {
    const auto it = kv.find(k);
    return it == kv.end() ? nullptr : &it->second;
  };
  const std::string *boot = need("boot_id"), *session = need("session"),
                    *steady = need("steady_utime"), *killed = need("killed"),
                    *failsafe = need("failsafe"), *motors = need("motors_on");
  if (!boot || !session || !steady || !killed || !failsafe || !motors) {
    fail(why, "incomplete record");
    return std::nullopt;
  }
  const auto s = to_int(*session), t = to_int(*steady);
  const auto f = failsafe_from_key(*failsafe);
  if (!s || !t || !f || (*killed != "0" && *killed != "1") || (*motors != "0" && *motors != "1")) {
    fail(why, "malformed value in the record");
    return std::nullopt;
  }
  r.boot_id = *boot;
  r.session = *s;
  r.steady_utime = *t;
  r.state.killed = *killed == "1";
  r.state.failsafe = *f;
  r.state.motors_on = *motors == "1";
  return r;
}

RestartState restore_state(const std::optional<RestartRecord>& record, const std::string& boot_id,
                           int64_t session, int64_t steady_now_utime, double max_age_s,
                           std::string* why) {
  const auto fresh = [&](const std::string& text) {
    if (why) *why = text;
    return RestartState{};
  };
  if (!record) return fresh("no state record: a fresh start");
  if (boot_id.empty() || record->boot_id != boot_id)
    return fresh("state record from another boot: a fresh start");
  if (record->session != session)
    return fresh("state record from another session (parent " + std::to_string(record->session) +
                 "): a fresh start");
  const double age_s = static_cast<double>(steady_now_utime - record->steady_utime) * 1e-6;
  if (!(age_s >= 0 && age_s <= max_age_s))
    return fresh("state record " + std::to_string(age_s) + " s old: a fresh start");
  if (why) {
    *why = std::string("restart: restored killed=") + (record->state.killed ? "1" : "0") +
           " failsafe=" + failsafe_key(record->state.failsafe) +
           " motors_on=" + (record->state.motors_on ? "1" : "0") + " (" + std::to_string(age_s) +
           " s old)";
  }
  return record->state;
}

std::string default_state_path(const std::string& lcm_url) {
  std::string dir;
  if (const char* x = std::getenv("XDG_RUNTIME_DIR"); x && *x) {
    dir = std::string(x) + "/alight";
  } else {
    dir = "/tmp/alight-" + std::to_string(::getuid());
  }
  uint64_t h = 1469598103934665603ull;  // FNV-1a: stable across builds, unlike std::hash
  for (const unsigned char c : lcm_url) h = (h ^ c) * 1099511628211ull;
  std::ostringstream os;
  os << dir << "/alight-autonomy-" << std::hex << h << ".state";
  return os.str();
}

std::optional<std::string> read_state_file(const std::string& path, std::string* why) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) {
    fail(why, path + ": " + std::strerror(errno));
    return std::nullopt;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || st.st_uid != ::getuid()) {
    ::close(fd);
    fail(why, path + ": not a regular file of ours");
    return std::nullopt;
  }
  std::string text(4096, '\0');
  const ssize_t n = ::read(fd, text.data(), text.size());
  ::close(fd);
  if (n < 0) {
    fail(why, path + ": " + std::strerror(errno));
    return std::nullopt;
  }
  text.resize(static_cast<size_t>(n));
  return text;
}

bool write_state_file(const std::string& path, const std::string& text, std::string* why) {
  const auto slash = path.rfind('/');
  if (slash != std::string::npos && slash > 0) {
    const std::string dir = path.substr(0, slash);
    if (::mkdir(dir.c_str(), 0700) != 0 && errno != EEXIST)
      return fail(why, dir + ": " + std::strerror(errno));
    // /tmp is shared: a directory someone else made could feed us their latches.
    struct stat st {};
    if (::lstat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode) || st.st_uid != ::getuid())
      return fail(why, dir + ": not a directory of ours");
  }
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0600);
  if (fd < 0) return fail(why, tmp + ": " + std::strerror(errno));
  const ssize_t n = ::write(fd, text.data(), text.size());
  ::close(fd);
  // No fsync: the record must survive the process, not the machine (a reboot starts clean).
  if (n != static_cast<ssize_t>(text.size())) {
    ::unlink(tmp.c_str());
    return fail(why, tmp + ": short write");
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0)
    return fail(why, path + ": " + std::strerror(errno));
  return true;
}

}  // namespace alight::autonomy
