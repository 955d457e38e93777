#pragma once
// The operator link's test setup for the fuzz targets: the key (32 bytes 0x5a, as
// fuzz/make-corpus signs its seed commands with), and a verifier / command bound to one vehicle
// and session. Written against both forms of common/operator_auth.hpp (before and after
// commands were bound to a vehicle id and the verifier's session) so the targets build
// with either.

#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "common/operator_auth.hpp"

namespace alight::fuzz {

inline constexpr int64_t kSession = 0x5a5a5a5a5a;
inline const std::string kVehicle = "fuzz-vehicle";

inline OperatorKey test_key() { return OperatorKey{std::vector<uint8_t>(32, 0x5a)}; }

template <class V = CommandVerifier>
V make_verifier(const OperatorKey& key, int64_t max_age_us = 2'000'000) {
  if constexpr (std::is_constructible_v<V, OperatorKey, std::string, int64_t, int64_t>) {
    return V(key, kVehicle, kSession, max_age_us);
  } else {
    return V(key, max_age_us);
  }
}

/// Names the verifier's vehicle and session in `cmd` (where the message has those fields).
template <class M>
void bind_to_vehicle(M& cmd) {
  if constexpr (requires { cmd.vehicle_id; }) cmd.vehicle_id = kVehicle;
  if constexpr (requires { cmd.session; }) cmd.session = kSession;
}

/// The station names the vehicle and the session autonomy announced; where the builder does not
/// know this test's ones, they are set here and the command signed again.
template <class M>
void bind_and_sign(M& cmd, const OperatorKey& key) {
  if constexpr (requires { cmd.session; }) {
    if (cmd.session != kSession || cmd.vehicle_id != kVehicle) {
      bind_to_vehicle(cmd);
      sign(cmd, key);
    }
  }
}

/// True when `cmd` names a session (the message has one) other than the verifier's.
template <class M>
bool names_other_session(const M& cmd) {
  if constexpr (requires { cmd.session; }) {
    return cmd.session != kSession;
  } else {
    return false;
  }
}

}  // namespace alight::fuzz
