// Operator command authentication: HMAC-SHA256 known answers (RFC 4231), the canonical byte
// layout, key files, and every path by which CommandVerifier rejects a command.

#include "common/operator_auth.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>

namespace alight {
namespace {

std::string hex(const HmacTag& tag) {
  static const char* digits = "0123456789abcdef";
  std::string s;
  for (uint8_t b : tag) {
    s += digits[b >> 4];
    s += digits[b & 15];
  }
  return s;
}

std::vector<uint8_t> bytes(const std::string& s) { return {s.begin(), s.end()}; }

// RFC 4231 section 4: HMAC-SHA-256 test cases 1, 2, 3, 4, 6 and 7.
TEST(HmacSha256Test, MatchesRfc4231TestVectors) {
  EXPECT_EQ(hex(hmac_sha256(std::vector<uint8_t>(20, 0x0b), bytes("Hi There"))),
            "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7");
  EXPECT_EQ(hex(hmac_sha256(bytes("Jefe"), bytes("what do ya want for nothing?"))),
            "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843");
  EXPECT_EQ(hex(hmac_sha256(std::vector<uint8_t>(20, 0xaa), std::vector<uint8_t>(50, 0xdd))),
            "773ea91e36800e46854db8ebd09181a72959098b3ef8c122d9635514ced565fe");
  std::vector<uint8_t> key4;
  for (int i = 1; i <= 25; ++i) key4.push_back(static_cast<uint8_t>(i));
  EXPECT_EQ(hex(hmac_sha256(key4, std::vector<uint8_t>(50, 0xcd))),
            "82558a389a443c0ea4cc819899f2083a85f0faa3e578f8077a2e3ff46729665b");
  EXPECT_EQ(hex(hmac_sha256(std::vector<uint8_t>(131, 0xaa),
                            bytes("Test Using Larger Than Block-Size Key - Hash Key First"))),
            "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54");
  EXPECT_EQ(hex(hmac_sha256(std::vector<uint8_t>(131, 0xaa),
                            bytes("This is a test using a larger than block-size key and a "
                                  "larger than block-size data. The key needs to be hashed "
                                  "before being used by the HMAC algorithm."))),
            "9b09ffa71b942fcb27635fbcd5b0e944bfdc63644f0713938a7f51535c3a35e2");
}

OperatorKey test_key(uint8_t fill = 0x42) { return OperatorKey{std::vector<uint8_t>(32, fill)}; }

constexpr int64_t kSession = 0x5e5510'4a11ce;

operator_cmd_t make_cmd(int64_t utime, int64_t seq, const std::string& sender = "gs-test") {
  operator_cmd_t cmd{};
  cmd.utime = utime;
  cmd.seq = seq;
  cmd.sender = sender;
  cmd.vehicle_id = "uav-1";
  cmd.session = kSession;
  cmd.command = operator_cmd_t::CMD_GO;
  cmd.mission = 1;
  cmd.nudge_W[0] = 0.25;
  cmd.nudge_W[1] = -1.0;
  cmd.nudge_W[2] = 0.0;
  cmd.auth = operator_cmd_t::AUTH_NONE;
  std::memset(cmd.hmac, 0, sizeof cmd.hmac);
  return cmd;
}

TEST(CanonicalBytesTest, HasTheDocumentedLayout) {
  operator_cmd_t cmd = make_cmd(0x0102030405060708, 0x1112131415161718, "ab");
  cmd.vehicle_id = "v";
  cmd.session = 0x2122232425262728;
  const std::vector<uint8_t> expected = {
      0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08,  // utime
      0x11, 0x12, 0x13, 0x14, 0x15, 0x16, 0x17, 0x18,  // seq
      0x00, 0x00, 0x00, 0x03, 'a',  'b',  0x00,        // sender: length incl. NUL, bytes, NUL
      0x00, 0x00, 0x00, 0x02, 'v',  0x00,              // vehicle_id
      0x21, 0x22, 0x23, 0x24, 0x25, 0x26, 0x27, 0x28,  // session
      0x02, 0x01,                                      // command GO, mission LANDING
      0x3f, 0xd0, 0,    0,    0,    0,    0,    0,     // 0.25
      0xbf, 0xf0, 0,    0,    0,    0,    0,    0,     // -1.0
      0x00, 0x00, 0,    0,    0,    0,    0,    0};    // 0.0
  EXPECT_EQ(canonical_bytes(cmd), expected);
  EXPECT_EQ(expected.size(), 58u + 3u + 2u);
}

TEST(CanonicalBytesTest, EqualsTheLcmEncodingOfTheCoveredFields) {
  operator_cmd_t cmd = make_cmd(1700000000123456, 99, "ground-station-7");
  sign(cmd, test_key());
  std::vector<uint8_t> wire(cmd.getEncodedSize());
  ASSERT_EQ(cmd.encode(wire.data(), 0, static_cast<int>(wire.size())),
            static_cast<int>(wire.size()));
  const std::vector<uint8_t> canon = canonical_bytes(cmd);
  ASSERT_GT(wire.size(), 8 + canon.size());
  EXPECT_TRUE(std::equal(canon.begin(), canon.end(), wire.begin() + 8));  // after fingerprint
}

TEST(SignTest, SignedCommandCarriesTheHmacOfItsCanonicalBytes) {
  operator_cmd_t cmd = make_cmd(1000, 1);
  sign(cmd, test_key());
  EXPECT_EQ(cmd.auth, operator_cmd_t::AUTH_HMAC_SHA256);
  const HmacTag expected = hmac_sha256(test_key().bytes, canonical_bytes(cmd));
  EXPECT_EQ(0, std::memcmp(expected.data(), cmd.hmac, 32));
  EXPECT_TRUE(signature_valid(cmd, test_key()));
  EXPECT_FALSE(signature_valid(cmd, test_key(0x43)));
}

class VerifierTest : public ::testing::Test {
 protected:
  static constexpr int64_t kNow = 1'700'000'000'000'000;
  CommandVerifier verifier{test_key(), "uav-1", kSession, 2'000'000};
  operator_cmd_t signed_cmd(int64_t utime, int64_t seq, const std::string& sender = "gs-test") {
    operator_cmd_t c = make_cmd(utime, seq, sender);
    sign(c, test_key());
    return c;
  }
  CommandVerdict::Reason check(const operator_cmd_t& c, int64_t now = kNow) {
    return verifier.check(c, now).reason;
  }
};

using R = CommandVerdict::Reason;

// Regression (issue 14, found by fuzzing): the staleness test computed now - max_age and
// utime - max_age in signed arithmetic, which overflowed for stamps near INT64_MIN.
TEST_F(VerifierTest, RegressionExtremeStampsAreStaleWithoutOverflow) {
  EXPECT_EQ(check(signed_cmd(INT64_MIN, 1)), R::kStale);
  EXPECT_EQ(check(signed_cmd(INT64_MAX, 2)), R::kStale);
  EXPECT_EQ(check(signed_cmd(INT64_MAX, 3), INT64_MIN), R::kStale);
  EXPECT_EQ(check(signed_cmd(INT64_MIN + 1, 4), INT64_MIN), R::kNone);
}

TEST_F(VerifierTest, AcceptsAFreshCorrectlySignedCommand) {
  EXPECT_EQ(check(signed_cmd(kNow, 1)), R::kNone);
  EXPECT_EQ(verifier.last_seq("gs-test"), 1);
  EXPECT_EQ(verifier.n_rejected(), 0u);
}

TEST_F(VerifierTest, RejectsUnsignedEvenWithAValidTagInside) {
  operator_cmd_t c = signed_cmd(kNow, 1);
  c.auth = operator_cmd_t::AUTH_NONE;
  EXPECT_EQ(check(c), R::kUnsigned);
  operator_cmd_t zero = make_cmd(kNow, 2);
  EXPECT_EQ(check(zero), R::kUnsigned);
  c.auth = 7;  // unknown scheme
  EXPECT_EQ(check(c), R::kUnsigned);
  EXPECT_EQ(verifier.n_rejected(), 3u);
}

TEST_F(VerifierTest, RejectsForgedCommands) {
  // Signed with another key.
  operator_cmd_t wrong_key = make_cmd(kNow, 1);
  sign(wrong_key, test_key(0x99));
  EXPECT_EQ(check(wrong_key), R::kBadSignature);
  // Claims HMAC but carries a zero tag.
  operator_cmd_t zero_tag = make_cmd(kNow, 2);
  zero_tag.auth = operator_cmd_t::AUTH_HMAC_SHA256;
  EXPECT_EQ(check(zero_tag), R::kBadSignature);
  // A correctly signed GO altered after signing: every covered field is protected.
  auto tampered = [&](auto&& change) {
    operator_cmd_t c = signed_cmd(kNow, 3);
    change(c);
    return check(c);
  };
  EXPECT_EQ(tampered([](operator_cmd_t& c) { c.command = operator_cmd_t::CMD_KILL; }),
            R::kBadSignature);
  EXPECT_EQ(tampered([](operator_cmd_t& c) { c.mission = 2; }), R::kBadSignature);
  EXPECT_EQ(tampered([](operator_cmd_t& c) { c.seq += 1; }), R::kBadSignature);
  EXPECT_EQ(tampered([](operator_cmd_t& c) { c.utime += 1; }), R::kBadSignature);
  EXPECT_EQ(tampered([](operator_cmd_t& c) { c.sender = "gs-tesu"; }), R::kBadSignature);
  EXPECT_EQ(tampered([](operator_cmd_t& c) { c.nudge_W[2] = 1e-300; }), R::kBadSignature);
  EXPECT_EQ(tampered([](operator_cmd_t& c) { c.vehicle_id = "uav-2"; }), R::kBadSignature);
  EXPECT_EQ(tampered([](operator_cmd_t& c) { c.session += 1; }), R::kBadSignature);
  EXPECT_EQ(tampered([](operator_cmd_t& c) { c.hmac[31] ^= 1; }), R::kBadSignature);
  EXPECT_EQ(verifier.last_seq("gs-test"), INT64_MIN);  // nothing was accepted
}

TEST_F(VerifierTest, RejectsStaleAndFutureCommands) {
  EXPECT_EQ(check(signed_cmd(kNow - 2'000'001, 1)), R::kStale);
  EXPECT_EQ(check(signed_cmd(kNow + 2'000'001, 2)), R::kStale);
  EXPECT_EQ(check(signed_cmd(INT64_MIN, 3)), R::kStale);
  EXPECT_EQ(check(signed_cmd(INT64_MAX, 4)), R::kStale);
  // The window's edges are inside.
  EXPECT_EQ(check(signed_cmd(kNow - 2'000'000, 5)), R::kNone);
  EXPECT_EQ(check(signed_cmd(kNow + 2'000'000, 6)), R::kNone);
}

TEST_F(VerifierTest, RejectsReplayedAndOlderSequenceNumbers) {
  const operator_cmd_t first = signed_cmd(kNow, 10);
  EXPECT_EQ(check(first), R::kNone);
  EXPECT_EQ(check(first), R::kReplayed);                // the very same message again
  EXPECT_EQ(check(signed_cmd(kNow, 9)), R::kReplayed);  // an older one
  EXPECT_EQ(check(signed_cmd(kNow, 11)), R::kNone);
  EXPECT_EQ(verifier.last_seq("gs-test"), 11);
  EXPECT_EQ(verifier.n_rejected(), 2u);
}

TEST_F(VerifierTest, SequenceNumbersArePerSender) {
  EXPECT_EQ(check(signed_cmd(kNow, 100, "gs-a")), R::kNone);
  EXPECT_EQ(check(signed_cmd(kNow, 5, "gs-b")), R::kNone);
  EXPECT_EQ(check(signed_cmd(kNow, 100, "gs-a")), R::kReplayed);
}

TEST_F(VerifierTest, RejectedCommandsDoNotAdvanceTheSequence) {
  // A forged command with a huge seq must not lock out the genuine station.
  operator_cmd_t forged = make_cmd(kNow, INT64_MAX);
  sign(forged, test_key(0x01));
  EXPECT_EQ(check(forged), R::kBadSignature);
  // A stale one (e.g. a recording replayed later) neither.
  EXPECT_EQ(check(signed_cmd(kNow - 60'000'000, 1000)), R::kStale);
  EXPECT_EQ(check(signed_cmd(kNow, 1)), R::kNone);
}

TEST(VerifierConstructionTest, RefusesShortKeysSessionZeroAndNonPositiveAge) {
  EXPECT_THROW(CommandVerifier(OperatorKey{std::vector<uint8_t>(31, 1)}, "uav-1", kSession),
               KeyFileError);
  EXPECT_THROW(CommandVerifier(test_key(), "uav-1", 0), std::invalid_argument);
  // Was an assert (SIGABRT) reachable from `command_max_age_s: 1e-7` (issue 14).
  EXPECT_THROW(CommandVerifier(test_key(), "uav-1", kSession, 0), std::invalid_argument);
}

TEST(ReasonNameTest, NamesEveryReason) {
  EXPECT_STREQ(command_reject_name(R::kNone), "none");
  EXPECT_STREQ(command_reject_name(R::kUnsigned), "unsigned");
  EXPECT_STREQ(command_reject_name(R::kBadSignature), "bad_signature");
  EXPECT_STREQ(command_reject_name(R::kStale), "stale");
  EXPECT_STREQ(command_reject_name(R::kReplayed), "replayed");
  EXPECT_STREQ(command_reject_name(R::kWrongVehicle), "wrong_vehicle");
  EXPECT_STREQ(command_reject_name(R::kWrongSession), "wrong_session");
}

// Regression (issue 14): a recorded signed GO replayed within 2 s after autonomy restarted was
// accepted: the new verifier had no sequence history. Each start of autonomy draws a new session
// nonce, the command's tag covers the session it was signed for, and the old one is refused.
TEST(OperatorAuthRegression, SignedGoReplayedAfterAutonomyRestartIsRefused) {
  constexpr int64_t kNow = 1'700'000'000'000'000;
  const int64_t first_session = draw_session_nonce();
  CommandVerifier before_restart(test_key(), "uav-1", first_session);
  operator_cmd_t go = make_cmd(kNow, kNow);
  go.session = first_session;  // as the station signs it: for the announced session
  sign(go, test_key());
  ASSERT_EQ(before_restart.check(go, kNow).reason, R::kNone);

  // autonomy restarts 0.5 s later; the recording is replayed at once, well inside 2 s.
  CommandVerifier after_restart(test_key(), "uav-1", draw_session_nonce());
  const CommandVerdict verdict = after_restart.check(go, kNow + 500'000);
  EXPECT_EQ(verdict.reason, R::kWrongSession);
  EXPECT_EQ(after_restart.n_rejected(R::kWrongSession), 1u);
  EXPECT_EQ(after_restart.last_rejected_seq(), go.seq);
  EXPECT_EQ(after_restart.last_reject_reason(), R::kWrongSession);
}

// Regression (issue 14): the HMAC named no vehicle, so vehicles sharing a key obeyed each
// other's commands.
TEST(OperatorAuthRegression, VehiclesSharingAKeyRefuseEachOthersCommands) {
  constexpr int64_t kNow = 1'700'000'000'000'000;
  CommandVerifier uav1(test_key(), "uav-1", 11);
  CommandVerifier uav2(test_key(), "uav-2", 11);  // even with an equal session
  operator_cmd_t kill = make_cmd(kNow, 1);
  kill.command = operator_cmd_t::CMD_KILL;
  kill.vehicle_id = "uav-1";
  kill.session = 11;
  sign(kill, test_key());
  EXPECT_EQ(uav2.check(kill, kNow).reason, R::kWrongVehicle);
  EXPECT_EQ(uav1.check(kill, kNow).reason, R::kNone);
}

TEST(SessionNonceTest, IsPositiveAndDiffersBetweenDraws) {
  std::set<int64_t> seen;
  for (int i = 0; i < 100; ++i) {
    const int64_t s = draw_session_nonce();
    EXPECT_GT(s, 0);
    seen.insert(s);
  }
  EXPECT_EQ(seen.size(), 100u);
}

TEST_F(VerifierTest, SequenceReplayProtectionHoldsWithinASession) {
  const operator_cmd_t go = signed_cmd(kNow, 50);
  EXPECT_EQ(check(go), R::kNone);
  EXPECT_EQ(check(go, kNow + 100'000), R::kReplayed);
  EXPECT_EQ(verifier.n_rejected(R::kReplayed), 1u);
  EXPECT_EQ(verifier.last_rejected_seq(), 50);
}

class KeyFileTest : public ::testing::Test {
 protected:
  std::filesystem::path dir = std::filesystem::temp_directory_path() /
                              ("alight_keyfile_test_" + std::to_string(::getpid()));
  void SetUp() override { std::filesystem::create_directories(dir); }
  void TearDown() override { std::filesystem::remove_all(dir); }
  std::string write(const std::string& name, const std::string& contents, mode_t mode = 0600) {
    const auto path = (dir / name).string();
    std::ofstream(path, std::ios::binary) << contents;
    ::chmod(path.c_str(), mode);
    return path;
  }
};

TEST_F(KeyFileTest, ReadsHexKeysWithSurroundingWhitespace) {
  const std::string hex64 = "000102030405060708090a0b0c0d0e0f101112131415161718191A1B1C1D1E1F";
  const LoadedKey k = load_key_file(write("hex", "  " + hex64 + "\n"));
  ASSERT_EQ(k.key.bytes.size(), 32u);
  for (int i = 0; i < 32; ++i) EXPECT_EQ(k.key.bytes[i], i);
  EXPECT_TRUE(k.warnings.empty());
}

TEST_F(KeyFileTest, ReadsRawKeys) {
  std::string raw(32, '\0');
  for (int i = 0; i < 32; ++i) raw[i] = static_cast<char>(0xe0 + (i % 16));  // not all hex
  const LoadedKey k = load_key_file(write("raw", raw));
  ASSERT_EQ(k.key.bytes.size(), 32u);
  EXPECT_EQ(k.key.bytes[0], 0xe0);
  EXPECT_EQ(k.key.bytes[31], 0xef);
}

TEST_F(KeyFileTest, MissingFileIsAClearError) {
  try {
    load_key_file((dir / "nope").string());
    FAIL() << "no exception";
  } catch (const KeyFileError& e) {
    EXPECT_NE(std::string(e.what()).find("nope"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("missing"), std::string::npos);
  }
}

TEST_F(KeyFileTest, ShortKeysAreRefused) {
  try {
    load_key_file(write("short_hex", "00112233445566778899aabbccddeeff\n"));  // 16 bytes
    FAIL() << "no exception";
  } catch (const KeyFileError& e) {
    EXPECT_NE(std::string(e.what()).find("too short: 16 bytes"), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_key_file(write("short_raw", std::string(31, '\x80'))), KeyFileError);
  EXPECT_THROW(load_key_file(write("empty", "")), KeyFileError);
  EXPECT_THROW(load_key_file(write("odd", std::string(65, 'a'))), KeyFileError);
}

TEST_F(KeyFileTest, WarnsWhenOthersCanReadTheKey) {
  const LoadedKey k = load_key_file(write("open", std::string(64, 'a'), 0644));
  ASSERT_EQ(k.warnings.size(), 1u);
  EXPECT_NE(k.warnings[0].find("644"), std::string::npos) << k.warnings[0];
  EXPECT_NE(k.warnings[0].find("chmod 600"), std::string::npos);
}

TEST_F(KeyFileTest, DirectoryIsNotAKeyFile) {
  EXPECT_THROW(load_key_file(dir.string()), KeyFileError);
}

std::string key_file_error(const std::string& path) {
  try {
    load_key_file(path);
  } catch (const KeyFileError& e) {
    return e.what();
  }
  ADD_FAILURE() << path << ": no KeyFileError";
  return "";
}

// A FIFO without a writer would block the open or the read for good, /dev/zero never ends.
TEST_F(KeyFileTest, FifosAndDevicesAreRefusedUnopened) {
  const std::string fifo = (dir / "fifo.key").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_EQ(key_file_error(fifo).rfind(fifo + ": key file is not a regular file", 0), 0u);
  EXPECT_EQ(key_file_error("/dev/zero").rfind("/dev/zero: key file is not a regular file", 0), 0u);
}

TEST_F(KeyFileTest, LargeFilesAreRefused) {
  const std::string huge = (dir / "huge.key").string();
  const int fd = ::open(huge.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::ftruncate(fd, off_t{300} << 20), 0);  // sparse: no disk
  ::close(fd);
  EXPECT_EQ(key_file_error(huge), huge + ": key file too large: 314572800 bytes, at most 4096");
  EXPECT_NE(key_file_error(write("over", std::string(4097, 'a'))).find("too large"),
            std::string::npos);
  // At the limit: read whole, then judged as a key (an odd number of hex digits here).
  EXPECT_NE(key_file_error(write("limit", std::string(4095, 'a') + "\n")).find("odd number"),
            std::string::npos);
}

}  // namespace
}  // namespace alight
