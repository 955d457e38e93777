#include "autonomy/command_gate.hpp"

namespace alight::autonomy {

CommandGate::Verdict CommandGate::refuse(const OperatorCommand& cmd, CommandReject reason,
                                         std::string why) {
  ++n_rejected_;
  if (reason != CommandReject::kNone) {
    ++by_reason_[static_cast<size_t>(reason)];
    last_rejected_seq_ = cmd.seq;
    last_reject_reason_ = reason;
  }
  return Verdict{false, reason, std::move(why), false};
}

CommandGate::Verdict CommandGate::check(const OperatorCommand& cmd) {
  switch (cmd.auth) {
    case CommandAuth::kInternal:
      return {};
    case CommandAuth::kHmacSha256: {
      if (cmd.link_reject == CommandReject::kNone) {
        return refuse(cmd, CommandReject::kNone,
                      "signed command, but no operator key to verify it "
                      "(autonomy.operator_key_file)");
      }
      Verdict v = refuse(cmd, cmd.link_reject, command_reject_name(cmd.link_reject));
      v.at_link = true;
      return v;
    }
    case CommandAuth::kNone:
      if (!accept_unsigned_) {
        return refuse(cmd, CommandReject::kUnsigned,
                      "unsigned command refused (autonomy.accept_unsigned_commands is false)");
      }
      break;
    case CommandAuth::kVerified:
      break;
  }
  // Unsigned commands get the one replay protection they can have here; verified ones passed
  // the verifier's, and a sender's unsigned and verified commands share one sequence.
  const auto it = last_seq_.find(cmd.sender);
  if (cmd.auth == CommandAuth::kNone && it != last_seq_.end() && cmd.seq <= it->second) {
    return refuse(
        cmd, CommandReject::kNone,
        "replayed or out-of-order seq " + std::to_string(cmd.seq) + " from '" + cmd.sender + "'");
  }
  last_seq_[cmd.sender] = cmd.seq;
  last_accepted_seq_ = cmd.seq;
  return {};
}

}  // namespace alight::autonomy
