#include "link/options.hpp"

#include <charconv>
#include <cmath>
#include <set>
#include <sstream>

#include "common/channels.hpp"
#include "common/params.hpp"

namespace alight::link {

namespace {

std::string known_channels() {
  std::string s;
  for (const char* c : channels::kAll) s += (s.empty() ? "" : ", ") + std::string(c);
  return s;
}

std::string format_number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

// Every channel of the options, split at commas, each known and given once in `seen`.
std::vector<std::string> channel_list(const std::vector<std::string>& values,
                                      const std::string& option, std::set<std::string>& seen) {
  std::vector<std::string> out;
  for (const std::string& value : values) {
    size_t start = 0;
    for (;;) {
      const size_t comma = value.find(',', start);
      const std::string name = value.substr(start, comma - start);
      if (name.empty())
        throw ParamError("", option, value, "expected CH[,CH...] without empty names");
      if (!channels::is_known(name))
        throw ParamError("", option, value,
                         "unknown channel '" + name + "' (known: " + known_channels() + ")");
      if (!seen.insert(name).second)
        throw ParamError("", option, value,
                         "channel '" + name +
                             "' given twice (a channel goes one way: --send or --receive, once)");
      out.push_back(name);
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
  }
  return out;
}

}  // namespace

std::string Endpoint::text() const {
  return (host.find(':') != std::string::npos ? "[" + host + "]" : host) + ":" +
         std::to_string(port);
}

Endpoint parse_endpoint(const std::string& text, const std::string& option) {
  const size_t colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == text.size())
    throw ParamError("", option, text, "expected HOST:PORT (e.g. 192.168.1.20:7670)");
  Endpoint e;
  e.host = text.substr(0, colon);
  if (e.host.front() == '[') {
    if (e.host.size() < 3 || e.host.back() != ']')
      throw ParamError("", option, text, "expected [ADDRESS]:PORT for an IPv6 address");
    e.host = e.host.substr(1, e.host.size() - 2);
  } else if (e.host.find(':') != std::string::npos) {
    throw ParamError("", option, text, "an IPv6 address goes in brackets: [ADDRESS]:PORT");
  }
  const std::string port = text.substr(colon + 1);
  const auto r = std::from_chars(port.data(), port.data() + port.size(), e.port);
  if (r.ec != std::errc() || r.ptr != port.data() + port.size() || e.port < 1 || e.port > 65535)
    throw ParamError("", option, text, "the port must be a number from 1 to 65535");
  return e;
}

Options parse_options(const RawOptions& raw) {
  Options o;
  if (raw.listen.empty() == raw.connect.empty())
    throw ParamError("", "--listen / --connect", raw.listen + raw.connect,
                     "give exactly one: --listen ADDR:PORT on the vehicle, --connect HOST:PORT "
                     "on the ground");
  o.role = raw.listen.empty() ? Role::kGround : Role::kVehicle;
  o.endpoint = raw.listen.empty() ? parse_endpoint(raw.connect, "--connect")
                                  : parse_endpoint(raw.listen, "--listen");
  std::set<std::string> seen;
  o.send = channel_list(raw.send, "--send", seen);
  o.receive = channel_list(raw.receive, "--receive", seen);
  if (o.send.empty() && o.receive.empty())
    throw ParamError("", "--send / --receive", "",
                     "the link carries nothing: name channels with --send or --receive");
  for (const std::string& value : raw.max_rate) {
    const size_t eq = value.find('=');
    if (eq == std::string::npos)
      throw ParamError("", "--max-rate", value, "expected CH=HZ (e.g. CAMERA=2)");
    const std::string name = value.substr(0, eq), hz_text = value.substr(eq + 1);
    if (!seen.count(name))
      throw ParamError("", "--max-rate", value,
                       "'" + name + "' is not a channel of --send or --receive");
    double hz = 0;
    const auto r = std::from_chars(hz_text.data(), hz_text.data() + hz_text.size(), hz);
    if (r.ec != std::errc() || r.ptr != hz_text.data() + hz_text.size() || !std::isfinite(hz) ||
        hz <= 0 || hz > kMaxRateHz)
      throw ParamError(
          "", "--max-rate", value,
          "the rate must be a number of Hz above 0, at most " + format_number(kMaxRateHz));
    if (!o.max_rate_hz.emplace(name, hz).second)
      throw ParamError("", "--max-rate", value, "a second rate for " + name);
  }
  if (!std::isfinite(raw.timeout_s) || raw.timeout_s < kMinTimeoutS || raw.timeout_s > kMaxTimeoutS)
    throw ParamError("", "--timeout", format_number(raw.timeout_s),
                     "must be from " + format_number(kMinTimeoutS) + " to " +
                         format_number(kMaxTimeoutS) + " s");
  o.timeout_s = raw.timeout_s;
  if (raw.max_frame_bytes < static_cast<int64_t>(kMinMaxFrameBytes) ||
      raw.max_frame_bytes > static_cast<int64_t>(kMaxMaxFrameBytes))
    throw ParamError("", "--max-frame-bytes", std::to_string(raw.max_frame_bytes),
                     "must be from " + std::to_string(kMinMaxFrameBytes) + " to " +
                         std::to_string(kMaxMaxFrameBytes));
  o.max_frame_bytes = static_cast<size_t>(raw.max_frame_bytes);
  return o;
}

}  // namespace alight::link
