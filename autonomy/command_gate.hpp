#pragma once
// Operator commands: every rule that decides whether one is obeyed, and every counter the ground
// station sees about it, in one place. Pure: no LCM, no clock, no key.
//
// The cryptographic part stays where the wire message is, at the link: the node runs
// common/operator_auth's CommandVerifier (HMAC-SHA256, vehicle id, session nonce, freshness on
// the wall clock, per-sender seq) on every signed OPERATOR_CMD and writes its verdict into the
// command (auth = kVerified, or link_reject = the reason). The gate then decides, in order:
//   1. kInternal (the node's own --auto-go commands): obeyed, no sequence kept;
//   2. signed and refused by the verifier: refused with the verifier's reason;
//   3. signed, but the node had no key to verify it: refused;
//   4. unsigned while autonomy.accept_unsigned_commands is false: refused (REJECT_UNSIGNED);
//   5. unsigned with a seq not above the sender's last obeyed one, unsigned or verified: refused
//      (verified commands passed the verifier's own seq check already);
//   6. otherwise obeyed, and its seq becomes the sender's last.
// Every refusal counts in n_rejected(). Rules 2 and 4 also count by reason and set
// last_rejected_seq() / last_reject_reason() (what the station shows); rules 3 and 5 count in the
// total only, as they did before the gate (the per-reason table is the link's).

#include <array>
#include <cstdint>
#include <map>
#include <string>

#include "autonomy/types.hpp"

namespace alight::autonomy {

class CommandGate {
 public:
  struct Verdict {
    bool accepted = true;
    CommandReject reason = CommandReject::kNone;  ///< kNone also for rules 3 and 5
    /// Why it was refused, for the status reason (empty when accepted).
    std::string why;
    /// Refused at the link (rule 2): the verifier's verdict on a forged or stale message. The
    /// autonomy does not put it into its status reason, so a flood of forgeries cannot hide
    /// why the vehicle is holding.
    bool at_link = false;
  };

  explicit CommandGate(bool accept_unsigned) : accept_unsigned_(accept_unsigned) {}

  Verdict check(const OperatorCommand& cmd);

  int n_rejected() const { return n_rejected_; }
  int n_rejected(CommandReject reason) const { return by_reason_[static_cast<size_t>(reason)]; }
  const std::array<int, kCommandRejectSlots>& n_rejected_by_reason() const { return by_reason_; }
  /// seq of the last command refused with a reason (-1: none).
  int64_t last_rejected_seq() const { return last_rejected_seq_; }
  CommandReject last_reject_reason() const { return last_reject_reason_; }
  /// seq of the last obeyed operator command (-1: none; internal ones are not counted).
  int64_t last_accepted_seq() const { return last_accepted_seq_; }

 private:
  Verdict refuse(const OperatorCommand& cmd, CommandReject reason, std::string why);

  bool accept_unsigned_;
  std::map<std::string, int64_t> last_seq_;  // per sender
  int n_rejected_ = 0;
  std::array<int, kCommandRejectSlots> by_reason_{};
  int64_t last_rejected_seq_ = -1;
  CommandReject last_reject_reason_ = CommandReject::kNone;
  int64_t last_accepted_seq_ = -1;
};

}  // namespace alight::autonomy
