// Command verification (common/operator_auth) over sequences of correctly signed commands with
// arbitrary stamps, sequence numbers, senders and verifier clocks, so that the staleness and
// replay rules (which a random signature never reaches) see extreme values. Properties: a
// command accepted once is never accepted again by the same verifier; an accepted command is
// within max_age of the verifier's clock; a command with any field changed after signing fails;
// once commands name a session, one naming another session fails.
#include <fuzzer/FuzzedDataProvider.h>

#include <algorithm>
#include <cstdint>

#include "common/operator_auth.hpp"
#include "fuzz/fuzz_support.hpp"
#include "fuzz/operator_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  FuzzedDataProvider in(data, size);
  const OperatorKey key = fuzz::test_key();
  const int64_t max_age_us = in.ConsumeIntegralInRange<int64_t>(1, 10'000'000);
  CommandVerifier verifier = fuzz::make_verifier(key, max_age_us);
  std::vector<operator_cmd_t> accepted;
  while (in.remaining_bytes() > 0) {
    operator_cmd_t cmd{};
    cmd.utime = in.ConsumeIntegral<int64_t>();
    cmd.seq = in.ConsumeIntegral<int64_t>();
    cmd.sender = in.ConsumeRandomLengthString(16);
    cmd.command = in.ConsumeIntegral<int8_t>();
    cmd.mission = in.ConsumeIntegral<int8_t>();
    for (double& d : cmd.nudge_W) d = in.ConsumeFloatingPoint<double>();
    const bool bound = in.ConsumeIntegralInRange<int>(0, 7) != 0;
    if (bound) fuzz::bind_to_vehicle(cmd);
    // The verifier's clock near the stamp (saturated at the int64 range) or anywhere.
    int64_t now = in.ConsumeIntegral<int64_t>();
    if (in.ConsumeBool()) {
      const __int128 near = static_cast<__int128>(cmd.utime) + (now % 3'000'000);
      now = static_cast<int64_t>(std::clamp<__int128>(near, INT64_MIN, INT64_MAX));
    }
    sign(cmd, key);
    if (in.ConsumeBool()) {  // tamper with one signed field
      operator_cmd_t bad = cmd;
      switch (in.ConsumeIntegralInRange<int>(0, 3)) {
        case 0:
          bad.seq ^= 1;
          break;
        case 1:
          bad.utime ^= 1;
          break;
        case 2:
          bad.command ^= 1;
          break;
        default:
          bad.sender += "x";
          break;
      }
      if (verifier.check(bad, now).accepted()) fuzz::fail("a tampered command was accepted");
      continue;
    }
    if (verifier.check(cmd, now).accepted()) {
      const __int128 age = static_cast<__int128>(now) - cmd.utime;
      if (age > max_age_us || age < -static_cast<__int128>(max_age_us))
        fuzz::fail("a command outside max_age was accepted");
      for (const auto& a : accepted)
        if (a.sender == cmd.sender && a.seq == cmd.seq)
          fuzz::fail("a sequence number was accepted twice");
      if (!bound && fuzz::names_other_session(cmd))
        fuzz::fail("a command for another session was accepted");
      accepted.push_back(cmd);
    }
  }
  return 0;
}
