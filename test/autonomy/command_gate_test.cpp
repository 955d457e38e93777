// The CommandGate's rules, one by one, with known answers: what is obeyed, what is refused, and
// what the ground station is told (counters by reason, last refused seq).

#include "autonomy/command_gate.hpp"

#include <gtest/gtest.h>

namespace alight::autonomy {
namespace {

OperatorCommand cmd(int64_t seq, CommandAuth auth, const std::string& sender = "station") {
  OperatorCommand c;
  c.seq = seq;
  c.sender = sender;
  c.command = Command::kNudge;
  c.auth = auth;
  return c;
}

OperatorCommand refused_at_link(int64_t seq, CommandReject reason) {
  OperatorCommand c = cmd(seq, CommandAuth::kHmacSha256);
  c.link_reject = reason;
  return c;
}

TEST(CommandGateTest, InternalCommandsAreObeyedAndLeaveNoSequence) {
  CommandGate gate(false);
  EXPECT_TRUE(gate.check(cmd(7, CommandAuth::kInternal)).accepted);
  EXPECT_TRUE(gate.check(cmd(7, CommandAuth::kInternal)).accepted) << "no replay check";
  EXPECT_EQ(gate.last_accepted_seq(), -1);
  EXPECT_EQ(gate.n_rejected(), 0);
}

TEST(CommandGateTest, UnsignedRefusedWhenNotAllowedAndTheStationIsTold) {
  CommandGate gate(false);
  const auto v = gate.check(cmd(3, CommandAuth::kNone));
  EXPECT_FALSE(v.accepted);
  EXPECT_FALSE(v.at_link);
  EXPECT_EQ(v.reason, CommandReject::kUnsigned);
  EXPECT_NE(v.why.find("accept_unsigned_commands"), std::string::npos) << v.why;
  EXPECT_EQ(gate.n_rejected(), 1);
  EXPECT_EQ(gate.n_rejected(CommandReject::kUnsigned), 1);
  EXPECT_EQ(gate.last_rejected_seq(), 3);
  EXPECT_EQ(gate.last_reject_reason(), CommandReject::kUnsigned);
  EXPECT_EQ(gate.last_accepted_seq(), -1);
}

TEST(CommandGateTest, UnsignedSeqMustIncreasePerSender) {
  CommandGate gate(true);
  EXPECT_TRUE(gate.check(cmd(5, CommandAuth::kNone)).accepted);
  EXPECT_EQ(gate.last_accepted_seq(), 5);
  const auto replay = gate.check(cmd(5, CommandAuth::kNone));
  EXPECT_FALSE(replay.accepted);
  EXPECT_NE(replay.why.find("replayed"), std::string::npos) << replay.why;
  EXPECT_FALSE(gate.check(cmd(4, CommandAuth::kNone)).accepted) << "out of order";
  EXPECT_TRUE(gate.check(cmd(1, CommandAuth::kNone, "other")).accepted) << "own sequence";
  EXPECT_TRUE(gate.check(cmd(6, CommandAuth::kNone)).accepted);
  // Counted in the total only: the per-reason table and the last refused seq are the link's.
  EXPECT_EQ(gate.n_rejected(), 2);
  EXPECT_EQ(gate.n_rejected(CommandReject::kReplayed), 0);
  EXPECT_EQ(gate.last_rejected_seq(), -1);
  EXPECT_EQ(gate.last_accepted_seq(), 6);
}

TEST(CommandGateTest, SignedWithoutAKeyToVerifyItIsRefused) {
  CommandGate gate(true);
  const auto v = gate.check(cmd(1, CommandAuth::kHmacSha256));
  EXPECT_FALSE(v.accepted);
  EXPECT_FALSE(v.at_link);
  EXPECT_NE(v.why.find("no operator key"), std::string::npos) << v.why;
  EXPECT_EQ(gate.n_rejected(), 1);
  EXPECT_EQ(gate.last_rejected_seq(), -1);
}

TEST(CommandGateTest, LinkRefusalsAreCountedByTheVerifiersReason) {
  CommandGate gate(false);
  const CommandReject reasons[] = {CommandReject::kUnsigned,     CommandReject::kBadSignature,
                                   CommandReject::kStale,        CommandReject::kReplayed,
                                   CommandReject::kWrongVehicle, CommandReject::kWrongSession};
  int64_t seq = 10;
  for (const auto r : reasons) {
    const auto v = gate.check(refused_at_link(++seq, r));
    EXPECT_FALSE(v.accepted);
    EXPECT_TRUE(v.at_link);
    EXPECT_EQ(v.reason, r);
    EXPECT_EQ(v.why, command_reject_name(r));
    EXPECT_EQ(gate.n_rejected(r), 1) << command_reject_name(r);
    EXPECT_EQ(gate.last_rejected_seq(), seq);
    EXPECT_EQ(gate.last_reject_reason(), r);
  }
  EXPECT_EQ(gate.n_rejected(), 6);
  EXPECT_EQ(gate.n_rejected(CommandReject::kNone), 0);
}

TEST(CommandGateTest, VerifiedCommandsAreObeyedAndBoundTheSendersUnsignedOnes) {
  CommandGate gate(true);
  EXPECT_TRUE(gate.check(cmd(2, CommandAuth::kVerified)).accepted);
  EXPECT_EQ(gate.last_accepted_seq(), 2);
  // The verifier judged the verified one's seq; unsigned ones must still come after it.
  EXPECT_FALSE(gate.check(cmd(2, CommandAuth::kNone)).accepted);
  EXPECT_TRUE(gate.check(cmd(1, CommandAuth::kVerified)).accepted) << "the verifier's to judge";
  EXPECT_TRUE(gate.check(cmd(3, CommandAuth::kNone)).accepted);
}

TEST(CommandGateTest, ARefusedCommandDoesNotBlockTheNextGenuineOne) {
  CommandGate gate(true);
  EXPECT_FALSE(gate.check(refused_at_link(100, CommandReject::kBadSignature)).accepted);
  EXPECT_TRUE(gate.check(cmd(50, CommandAuth::kNone)).accepted);
  EXPECT_EQ(gate.last_accepted_seq(), 50);
  EXPECT_EQ(gate.last_rejected_seq(), 100);
}

}  // namespace
}  // namespace alight::autonomy
