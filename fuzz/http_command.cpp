// POST /api/command as the ground station receives it: request headers (one "Name: value" per
// line, up to an empty line) checked by the access policy for a loopback and for a token-guarded
// bind, and a form body (application/x-www-form-urlencoded, decoded by cpp-httplib as the server
// does) parsed into a command. A parsed command is then built and signed as the station does and
// must pass the vehicle's verifier unchanged: what the station sends, the vehicle accepts.
#include <cmath>

#include "autonomy/convert.hpp"
#include "common/operator_auth.hpp"
#include "fuzz/fuzz_support.hpp"
#include "fuzz/operator_support.hpp"
#include "ground_station/commands.hpp"
// After Eigen (via the alight headers): Eigen fails to compile when httplib.h comes first.
#include <httplib.h>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  using namespace alight::ground_station;
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::multimap<std::string, std::string> headers;
  size_t pos = 0;
  while (pos < text.size()) {
    const size_t eol = text.find('\n', pos);
    std::string line = text.substr(pos, eol == std::string::npos ? std::string::npos : eol - pos);
    pos = eol == std::string::npos ? text.size() : eol + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) break;
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    size_t v = colon + 1;
    while (v < line.size() && line[v] == ' ') ++v;
    headers.emplace(line.substr(0, colon), line.substr(v));
  }
  const std::string body = text.substr(pos);

  for (const auto& policy : {policy_for_bind("127.0.0.1", "0123456789abcdef0123"),
                             policy_for_bind("0.0.0.0", "0123456789abcdef0123")})
    (void)access_name(check_command_access(policy, headers));

  httplib::Params params;
  httplib::detail::parse_query_text(body, params);
  std::map<std::string, std::string> fields;
  for (const auto& [k, v] : params) fields.emplace(k, v);
  const double nudge_max_m = 2.0;
  const ParsedCommand parsed = parse_command_request(fields, nudge_max_m);
  if (!parsed.request) return 0;

  const CommandRequest& req = *parsed.request;
  for (double d : req.nudge_W)
    if (!std::isfinite(d) || std::abs(d) > nudge_max_m)
      fuzz::fail("parse_command_request passed a nudge outside +-nudge_max_m");
  const OperatorKey key = fuzz::test_key();
  CommandBuilder builder("station", key, fuzz::kVehicle);
  const int64_t now = 1'700'000'000'000'000;
  operator_cmd_t cmd = builder.build(req, fuzz::kSession, now);
  CommandVerifier verifier = fuzz::make_verifier(key);
  if (!verifier.check(cmd, now).accepted())
    fuzz::fail("a command the station built and signed is refused by the vehicle's verifier");
  if (verifier.check(cmd, now).accepted()) fuzz::fail("the same signed command accepted twice");
  // Over the wire and back: the vehicle decodes exactly what was signed.
  std::vector<uint8_t> wire(static_cast<size_t>(cmd.getEncodedSize()));
  cmd.encode(wire.data(), 0, static_cast<int>(wire.size()));
  const auto back = fuzz::decode<operator_cmd_t>(wire.data(), wire.size());
  if (!back || !signature_valid(*back, key))
    fuzz::fail("a signed command does not survive encoding and decoding");
#ifdef ALIGHT_FUZZ_HAS_COMMAND_FROM_MSG
  std::string why;
  if (!autonomy::command_from_msg(*back, &why))
    fuzz::fail("autonomy refuses a command the station built: " + why);
#else
  auto converted = autonomy::from_msg(*back);
  (void)fuzz::value_of(converted);
#endif
  return 0;
}
