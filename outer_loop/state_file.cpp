#include "outer_loop/state_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace alight::outer_loop {

namespace {
constexpr const char* kMagic = "alight-outer-loop-state 2";
}

std::string format_state(const StateRecord& r) {
  std::ostringstream os;
  os << kMagic << "\n"
     << "disarm_latched " << (r.state.disarm_latched ? 1 : 0) << "\n"
     << "armed " << (r.state.armed ? 1 : 0) << "\n"
     << "wall_utime " << r.wall_utime << "\n"
     << "boot_id " << (r.boot_id.empty() ? "-" : r.boot_id) << "\n"
     << "steady_utime " << r.steady_utime << "\n"
     << "end\n";
  return os.str();
}

std::optional<StateRecord> parse_state(const std::string& text) {
  std::istringstream is(text);
  std::string line;
  if (!std::getline(is, line) || line != kMagic) return std::nullopt;
  StateRecord r;
  std::string key, end;
  int latched = -1, armed = -1;
  if (!(is >> key >> latched) || key != "disarm_latched" || (latched != 0 && latched != 1))
    return std::nullopt;
  if (!(is >> key >> armed) || key != "armed" || (armed != 0 && armed != 1)) return std::nullopt;
  if (!(is >> key >> r.wall_utime) || key != "wall_utime") return std::nullopt;
  if (!(is >> key >> r.boot_id) || key != "boot_id") return std::nullopt;
  if (r.boot_id == "-") r.boot_id.clear();
  if (!(is >> key >> r.steady_utime) || key != "steady_utime") return std::nullopt;
  if (!(is >> end) || end != "end") return std::nullopt;
  r.state.disarm_latched = latched == 1;
  r.state.armed = armed == 1;
  return r;
}

bool save_state(const std::string& path, const StateRecord& record, std::string* error) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path p(path);
  if (p.has_parent_path()) {
    fs::create_directories(p.parent_path(), ec);
    if (ec) {
      if (error) *error = "cannot create " + p.parent_path().string() + ": " + ec.message();
      return false;
    }
  }
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  const std::string text = format_state(record);
  std::FILE* f = std::fopen(tmp.c_str(), "w");
  if (!f) {
    if (error) *error = "cannot write " + tmp + ": " + std::strerror(errno);
    return false;
  }
  const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size() &&
                       std::fflush(f) == 0 && ::fsync(::fileno(f)) == 0;
  const bool closed = std::fclose(f) == 0;
  if (!written || !closed || std::rename(tmp.c_str(), path.c_str()) != 0) {
    if (error) *error = "cannot write " + path + ": " + std::strerror(errno);
    std::remove(tmp.c_str());
    return false;
  }
  return true;
}

std::optional<StateRecord> load_state(const std::string& path, std::string* error) {
  if (error) error->clear();
  std::ifstream in(path);
  if (!in) return std::nullopt;
  std::ostringstream ss;
  ss << in.rdbuf();
  auto r = parse_state(ss.str());
  if (!r && error) *error = path + ": not a state file of this version";
  return r;
}

PersistentState restored_state(const std::optional<StateRecord>& record, const RestoreClock& now,
                               double max_age_s) {
  PersistentState s;
  if (!record) return s;
  s.disarm_latched = record->state.disarm_latched;
  const bool same_boot = !record->boot_id.empty() && record->boot_id == now.boot_id;
  const double age_s = static_cast<double>(same_boot ? now.steady_utime - record->steady_utime
                                                     : now.wall_utime - record->wall_utime) *
                       1e-6;
  s.armed = record->state.armed && age_s >= -max_age_s && age_s <= max_age_s;
  return s;
}

std::string default_state_path(const std::string& tag) {
  std::string name = tag;
  for (char& c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '.' || c == '-';
    if (!ok) c = '_';
  }
  if (name.size() > 100) name.resize(100);
  return "/tmp/alight-" + std::to_string(::getuid()) + "/outer_loop-" + name + ".state";
}

}  // namespace alight::outer_loop
