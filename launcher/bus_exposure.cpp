#include "launcher/bus_exposure.hpp"

#include <arpa/inet.h>

#include <cstdio>
#include <sstream>

namespace alight::launcher {

std::optional<UdpmUrl> parse_udpm_url(const std::string& url) {
  const std::string scheme = "udpm://";
  if (url.rfind(scheme, 0) != 0) return std::nullopt;
  const std::string rest = url.substr(scheme.size());
  const size_t colon = rest.find(':');
  const size_t query = rest.find('?');
  UdpmUrl u;
  u.group = rest.substr(0, colon == std::string::npos ? query : colon);
  in_addr a{};
  if (inet_pton(AF_INET, u.group.c_str(), &a) != 1) return std::nullopt;
  if (colon != std::string::npos) {
    try {
      u.port = std::stoi(rest.substr(
          colon + 1, query == std::string::npos ? std::string::npos : query - colon - 1));
    } catch (const std::exception&) {
      return std::nullopt;
    }
  }
  if (query != std::string::npos) {
    std::stringstream options(rest.substr(query + 1));
    std::string kv;
    while (std::getline(options, kv, '&')) {
      if (kv.rfind("ttl=", 0) != 0) continue;
      try {
        u.ttl = std::stoi(kv.substr(4));
      } catch (const std::exception&) {
        return std::nullopt;
      }
    }
  }
  return u;
}

std::vector<std::string> interfaces_joined(const std::string& igmp_text, const std::string& group) {
  // /proc/net/igmp: a line "Idx Device : Count Querier" per interface, then its groups as
  // 8 hex digits of the address in host (little-endian) byte order.
  in_addr a{};
  if (inet_pton(AF_INET, group.c_str(), &a) != 1) return {};
  char want[16];
  std::snprintf(want, sizeof want, "%08X", static_cast<unsigned>(a.s_addr));
  std::vector<std::string> out;
  std::stringstream lines(igmp_text);
  std::string line, device;
  while (std::getline(lines, line)) {
    if (line.empty()) continue;
    std::stringstream words(line);
    std::string first;
    words >> first;
    if (line[0] != ' ' && line[0] != '\t') {
      if (first == "Idx") continue;
      words >> device;  // "1 lo : ..." -> "lo"
      continue;
    }
    if (first == want && (out.empty() || out.back() != device)) out.push_back(device);
  }
  return out;
}

std::vector<std::string> url_warnings(const std::string& url, bool signed_bus) {
  std::vector<std::string> w;
  const auto u = parse_udpm_url(url);
  if (!u) return w;
  if (u->ttl > 0)
    w.push_back("the LCM bus leaves this computer (" + url + ": ttl=" + std::to_string(u->ttl) +
                "): what the onboard processes publish reaches the network" +
                (signed_bus ? "" : ", and anything on it can publish to them: set bus_key"));
  if (!signed_bus)
    w.push_back("the bus is unsigned (bus_key: none): any process that reaches UDP port " +
                std::to_string(u->port) + " (LCM's socket takes unicast from any interface) " +
                "can publish on it");
  return w;
}

std::vector<std::string> join_warnings(const std::string& url, bool signed_bus,
                                       const std::vector<std::string>& joined) {
  std::vector<std::string> w;
  const auto u = parse_udpm_url(url);
  if (!u) return w;
  for (const auto& dev : joined) {
    if (dev == "lo") continue;
    w.push_back("the LCM group " + u->group + " is joined on " + dev +
                ": messages from that network reach the onboard processes" +
                (signed_bus ? " (refused: the bus is signed)" : ", unsigned and unchecked") +
                ". Keep the bus on this computer: ip route add " + u->group +
                "/32 dev lo (scripts/setup)");
  }
  return w;
}

}  // namespace alight::launcher
