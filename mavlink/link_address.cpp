#include "mavlink/link_address.hpp"

#include <cctype>

namespace alight::mavlink {

namespace {

std::optional<int> parse_port(const std::string& s) {
  if (s.empty() || s.size() > 5) return std::nullopt;
  for (char c : s)
    if (!std::isdigit(static_cast<unsigned char>(c))) return std::nullopt;
  const int v = std::stoi(s);
  if (v < 1 || v > 65535) return std::nullopt;
  return v;
}

bool plain(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s)
    if (std::isspace(static_cast<unsigned char>(c)) || std::iscntrl(static_cast<unsigned char>(c)))
      return false;
  return true;
}

}  // namespace

bool valid_baud(int baud) {
  for (int b : kBaudRates)
    if (b == baud) return true;
  return false;
}

std::string LinkAddress::text() const {
  switch (kind) {
    case Kind::kSerial:
      return "serial:" + device + ":" + std::to_string(baud);
    case Kind::kUdpListen:
      return "udp-listen:" + host + ":" + std::to_string(port);
    case Kind::kUdpPeer:
      return "udp:" + host + ":" + std::to_string(port) +
             (local_port ? ":" + std::to_string(local_port) : "");
  }
  return "";
}

std::optional<LinkAddress> parse_link_address(const std::string& text, std::string* why) {
  const auto fail = [&](const std::string& w) -> std::optional<LinkAddress> {
    if (why) *why = w;
    return std::nullopt;
  };
  const auto colon = text.find(':');
  if (colon == std::string::npos)
    return fail("must be serial:DEVICE:BAUD, udp-listen:HOST:PORT or udp:HOST:PORT[:LOCAL_PORT]");
  const std::string scheme = text.substr(0, colon), rest = text.substr(colon + 1);
  LinkAddress a;
  if (scheme == "serial") {
    const auto last = rest.rfind(':');
    if (last == std::string::npos || last == 0) return fail("must be serial:DEVICE:BAUD");
    a.kind = LinkAddress::Kind::kSerial;
    a.device = rest.substr(0, last);
    const std::string baud = rest.substr(last + 1);
    if (!plain(a.device)) return fail("serial: the device path is empty or has spaces");
    if (baud.empty() || baud.size() > 7) return fail("serial: the baud rate is not a number");
    for (char c : baud)
      if (!std::isdigit(static_cast<unsigned char>(c)))
        return fail("serial: the baud rate is not a number");
    a.baud = std::stoi(baud);
    if (!valid_baud(a.baud))
      return fail("serial: baud " + baud +
                  " is not one of 57600, 115200, 230400, 460800, 500000, 576000, 921600");
    return a;
  }
  if (scheme != "udp-listen" && scheme != "udp")
    return fail("unknown link kind '" + scheme + "' (serial, udp-listen or udp)");
  // HOST:PORT or, for udp, HOST:PORT:LOCAL_PORT (IPv4 addresses and names; no IPv6 literals).
  std::string host = rest, port, local;
  auto c1 = host.find(':');
  if (c1 == std::string::npos) return fail(scheme + ": must be " + scheme + ":HOST:PORT");
  port = host.substr(c1 + 1);
  host.resize(c1);
  if (const auto c2 = port.find(':'); c2 != std::string::npos) {
    if (scheme != "udp") return fail("udp-listen: must be udp-listen:HOST:PORT");
    local = port.substr(c2 + 1);
    port.resize(c2);
  }
  if (!plain(host)) return fail(scheme + ": the host is empty or has spaces");
  const auto p = parse_port(port);
  if (!p) return fail(scheme + ": port '" + port + "' is not in 1..65535");
  a.kind = scheme == "udp" ? LinkAddress::Kind::kUdpPeer : LinkAddress::Kind::kUdpListen;
  a.host = host;
  a.port = *p;
  if (!local.empty()) {
    const auto lp = parse_port(local);
    if (!lp) return fail("udp: local port '" + local + "' is not in 1..65535");
    a.local_port = *lp;
  }
  return a;
}

}  // namespace alight::mavlink
