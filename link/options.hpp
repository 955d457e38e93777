#pragma once
// alight-link's command line, checked (docs/link.md). Pure: the node hands over the strings
// CLI11 collected; every error is a ParamError naming the option and its value (exit code 2).

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "link/protocol.hpp"

namespace alight::link {

/// Bounds of --timeout [s]: a Wi-Fi hiccup must not end a session; a dead peer must not hold
/// the vehicle's one session for long.
inline constexpr double kMinTimeoutS = 0.5;
inline constexpr double kMaxTimeoutS = 600.0;
inline constexpr double kDefaultTimeoutS = 5.0;
/// Bound of --max-rate [Hz]: above it a limit limits nothing on any channel we have.
inline constexpr double kMaxRateHz = 1000.0;

struct Endpoint {
  std::string host;  ///< a name or address; an IPv6 address without its brackets
  int port = 0;
  std::string text() const;
};

/// What CLI11 collected, unchecked.
struct RawOptions {
  std::string listen;
  std::string connect;
  std::vector<std::string> send;      ///< each "CH" or "CH,CH,..."
  std::vector<std::string> receive;   ///< idem
  std::vector<std::string> max_rate;  ///< each "CH=HZ"
  double timeout_s = kDefaultTimeoutS;
  int64_t max_frame_bytes = static_cast<int64_t>(kDefaultMaxFrameBytes);
};

struct Options {
  Role role = Role::kVehicle;  ///< --listen: the vehicle; --connect: the ground
  Endpoint endpoint;
  std::vector<std::string> send;     ///< channel names in the code (common/channels.hpp)
  std::vector<std::string> receive;  ///< idem
  std::map<std::string, double> max_rate_hz;
  double timeout_s = kDefaultTimeoutS;
  size_t max_frame_bytes = kDefaultMaxFrameBytes;
};

/// HOST:PORT ([ADDR]:PORT for IPv6); throws ParamError naming `option`.
Endpoint parse_endpoint(const std::string& text, const std::string& option);
/// Checks everything: exactly one of --listen and --connect; known channels (common/channels.hpp),
/// none twice, none both sent and received, at least one; rates CH=HZ on a carried channel;
/// --timeout and --max-frame-bytes within their bounds.
Options parse_options(const RawOptions& raw);

}  // namespace alight::link
