#include "common/channels.hpp"

#include <algorithm>
#include <cctype>

namespace alight {

namespace channels {
bool is_known(const std::string& name) {
  return std::any_of(kAll.begin(), kAll.end(), [&](const char* c) { return name == c; });
}
}  // namespace channels

namespace {

// LCM_MAX_CHANNEL_NAME_LENGTH in lcm/lcm.h.
constexpr size_t kMaxChannelNameLength = 63;

std::string known_list() {
  std::string s;
  for (const char* c : channels::kAll) s += (s.empty() ? "" : ", ") + std::string(c);
  return s;
}

// A subscription takes the name as a regular expression: only characters that match themselves.
bool usable_name(const std::string& name) {
  return !name.empty() && name.size() <= kMaxChannelNameLength &&
         std::all_of(name.begin(), name.end(), [](unsigned char c) {
           return std::isalnum(c) || c == '_' || c == '-' || c == '/';
         });
}

}  // namespace

ChannelRemap parse_remaps(const std::vector<std::string>& args) {
  ChannelRemap remap;
  for (const std::string& arg : args) {
    const std::string where = "--remap '" + arg + "': ";
    const auto eq = arg.find('=');
    if (eq == std::string::npos || arg.find('=', eq + 1) != std::string::npos)
      throw RemapError(where + "expected FROM=TO (e.g. CAMERA=CAMERA_LEFT)");
    const std::string from = arg.substr(0, eq), to = arg.substr(eq + 1);
    if (from.empty() || to.empty())
      throw RemapError(where + "expected FROM=TO with both names given (e.g. CAMERA=CAMERA_LEFT)");
    if (!channels::is_known(from))
      throw RemapError(where + "unknown channel '" + from + "' (known: " + known_list() + ")");
    if (!usable_name(to))
      throw RemapError(where + "'" + to +
                       "' is not a usable channel name (letters, digits, '_', '-', '/'; at most " +
                       std::to_string(kMaxChannelNameLength) + " characters)");
    const auto it = remap.to_.find(from);
    if (it != remap.to_.end() && it->second != to)
      throw RemapError(where + from + " is already remapped to " + it->second);
    remap.to_[from] = to;
  }
  // Two channels on one name would mix message types on it.
  std::map<std::string, std::string> owner;  // name on LCM -> channel
  for (const char* c : channels::kAll) {
    const std::string name = remap(c);
    const auto [it, fresh] = owner.emplace(name, c);
    if (!fresh)
      throw RemapError("--remap: " + it->second + " and " + c + " would both be on channel " +
                       name + ": two channels cannot share one name");
  }
  return remap;
}

}  // namespace alight
