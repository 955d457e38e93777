// OPERATOR_CMD (operator_cmd_t) from the network: decoded, converted and verified as autonomy
// does (HMAC-SHA256 with a fixed test key; the verifier's clock at the command's own stamp and
// at a fixed time, so stale and replay paths run too).
#include "autonomy/convert.hpp"
#include "common/operator_auth.hpp"
#include "fuzz/fuzz_support.hpp"
#include "fuzz/operator_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace alight;
  const auto msg = fuzz::decode<operator_cmd_t>(data, size);
  if (!msg) return 0;
#ifdef ALIGHT_FUZZ_HAS_COMMAND_FROM_MSG
  std::string why;
  auto converted = autonomy::command_from_msg(*msg, &why);
#else
  auto converted = autonomy::from_msg(*msg);
#endif
  (void)fuzz::value_of(converted);
  const OperatorKey key = fuzz::test_key();
  CommandVerifier verifier = fuzz::make_verifier(key);
  (void)verifier.check(*msg, msg->utime);
  (void)verifier.check(*msg, msg->utime);  // the same again: a replay
  (void)verifier.check(*msg, 1'700'000'000'000'000);
  (void)verifier.last_seq(msg->sender);
  // A genuine signature over the same fields must verify (canonical bytes of any field values).
  operator_cmd_t signed_msg = *msg;
  sign(signed_msg, key);
  if (!signature_valid(signed_msg, key))
    fuzz::fail("a command signed with the key does not verify");
  return 0;
}
