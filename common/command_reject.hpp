#pragma once
// Why an operator command was refused: one list for the link's verifier (common/operator_auth,
// CommandVerdict) and autonomy's command gate, so the two cannot drift apart. The values are
// autonomy_status_t.REJECT_* (autonomy/convert.cpp checks them at compile time).

#include <cstdint>

namespace alight {

enum class CommandReject : int8_t {
  kNone = 0,  ///< not refused
  kUnsigned = 1,
  kBadSignature = 2,
  kStale = 3,
  kReplayed = 4,
  kWrongVehicle = 5,
  kWrongSession = 6,
};
inline constexpr int kCommandRejectCount = 7;

/// The name logs, AUTONOMY_STATUS readers and the ground station show ("bad_signature").
inline const char* command_reject_name(CommandReject reason) {
  switch (reason) {
    case CommandReject::kNone:
      return "none";
    case CommandReject::kUnsigned:
      return "unsigned";
    case CommandReject::kBadSignature:
      return "bad_signature";
    case CommandReject::kStale:
      return "stale";
    case CommandReject::kReplayed:
      return "replayed";
    case CommandReject::kWrongVehicle:
      return "wrong_vehicle";
    case CommandReject::kWrongSession:
      return "wrong_session";
  }
  return "unknown";
}

}  // namespace alight
