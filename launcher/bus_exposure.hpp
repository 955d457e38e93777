#pragma once
// Does a launch file's LCM bus stay on this computer? LCM's udpm transport sends with the URL's
// ttl (0: never leaves the host) and receives on a UDP socket bound to INADDR_ANY that joins the
// multicast group on the interface the kernel routes the group to: with the default route on the
// room's network, anyone there can publish on the bus (and unicast to the port reaches it
// whatever the route). The shipped launch files keep the bus on the host (ttl=0, and a route of
// the group via lo, which scripts/setup adds) and sign it (bus_key: auto). The launcher checks
// both at start and says loudly what is exposed (docs/security.md). Pure: the node passes the
// URL and the text of /proc/net/igmp.

#include <optional>
#include <string>
#include <vector>

namespace alight::launcher {

struct UdpmUrl {
  std::string group;  ///< dotted quad, e.g. 239.255.76.67
  int port = 0;
  int ttl = 0;  ///< LCM's default when the URL names none
};
/// Parses udpm://GROUP:PORT?ttl=N&...; nullopt for another provider or a malformed URL.
std::optional<UdpmUrl> parse_udpm_url(const std::string& url);

/// The interfaces /proc/net/igmp lists as members of `group` (dotted quad).
std::vector<std::string> interfaces_joined(const std::string& igmp_text, const std::string& group);

/// What the launcher says about the bus at start: one loud line per exposure (empty: ttl=0 and
/// signed). `signed_bus`: the launch file has a bus key.
std::vector<std::string> url_warnings(const std::string& url, bool signed_bus);
/// ... and once the processes have joined the group: a line per interface other than lo in
/// `joined` (interfaces_joined()).
std::vector<std::string> join_warnings(const std::string& url, bool signed_bus,
                                       const std::vector<std::string>& joined);

}  // namespace alight::launcher
