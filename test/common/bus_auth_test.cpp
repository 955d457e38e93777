// The bus's origin trailer: sealing, splitting, signatures, replays and second publishers
// (common/bus_auth.hpp).
#include "common/bus_auth.hpp"

#include <gtest/gtest.h>

#include <alight/pose_t.hpp>

#include "common/decode.hpp"
#include "common/operator_auth.hpp"

namespace alight::bus {
namespace {

constexpr int64_t kT0 = 1'700'000'000'000'000;  // a bus time [us]
constexpr int64_t kMs = 1000;

std::vector<uint8_t> encoded_pose(int64_t utime, double x = 1.0) {
  pose_t m{};
  m.utime = utime;
  m.pos[0] = x;
  m.orientation[0] = 1.0;
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

BusKey key_a() { return make_bus_key(std::vector<uint8_t>(32, 0x11)); }
BusKey key_b() { return make_bus_key(std::vector<uint8_t>(32, 0x22)); }

std::vector<uint8_t> sealed(Sealer& s, const std::string& channel, int64_t t, double x = 1.0) {
  auto b = encoded_pose(t, x);
  s.seal(b, channel, t);
  return b;
}

Received rx(const std::vector<uint8_t>& b) { return split(b.data(), b.size()); }

TEST(BusTrailerTest, SplitReturnsThePayloadAndTheTrailer) {
  Sealer s(0x0123456789abcdefULL, std::nullopt);
  const auto plain = encoded_pose(kT0);
  const auto b = sealed(s, "MOCAP_POSE", kT0);
  ASSERT_EQ(b.size(), plain.size() + kTrailerBytes);
  const Received r = rx(b);
  ASSERT_TRUE(r.trailer);
  EXPECT_EQ(r.trailer->source, 0x0123456789abcdefULL);
  EXPECT_EQ(r.trailer->counter, static_cast<uint64_t>(kT0));
  EXPECT_EQ(r.trailer->key_id, 0);
  EXPECT_EQ(std::vector<uint8_t>(r.payload.begin(), r.payload.end()), plain);
  // A message without a trailer is all payload.
  const Received none = rx(plain);
  EXPECT_FALSE(none.trailer);
  EXPECT_EQ(none.payload.size(), plain.size());
}

// lcm-spy, lcm-logplayer and Python's decode() read a trailed message: lcm-gen's decoders read
// the fields and stop, whatever follows.
TEST(BusTrailerTest, LcmGenDecodersIgnoreTheTrailer) {
  Sealer s(7, key_a());
  const auto b = sealed(s, "MOCAP_POSE", kT0, 2.5);
  pose_t m{};
  ASSERT_GT(m.decode(b.data(), 0, static_cast<int>(b.size())), 0);
  EXPECT_EQ(m.utime, kT0);
  EXPECT_EQ(m.pos[0], 2.5);
  // Ours demands the exact length but for a trailer; other bytes after the message are refused.
  pose_t strict{};
  const Received r = rx(b);
  EXPECT_TRUE(decode_message(strict, r.payload.data(), r.payload.size()));
  EXPECT_TRUE(decode_message(strict, b.data(), b.size()));
  auto extra = encoded_pose(kT0);
  extra.push_back(0);
  EXPECT_FALSE(decode_message(strict, extra.data(), extra.size()));
}

// The tag's layout, checked with an independent HMAC over the bytes the header says it covers.
TEST(BusTrailerTest, TheTagIsHmacSha256OverMagicChannelPayloadAndHeader) {
  const BusKey k = key_a();
  Sealer s(0xfeedULL, k);
  const auto b = sealed(s, "CAMERA", kT0);
  const Received r = rx(b);
  ASSERT_TRUE(r.trailer);
  EXPECT_EQ(r.trailer->key_id, k.id);
  EXPECT_NE(k.id, 0);
  std::vector<uint8_t> covered = {'A', 'L', 'B', '1'};
  for (char c : std::string("CAMERA")) covered.push_back(static_cast<uint8_t>(c));
  covered.push_back(0);
  covered.insert(covered.end(), r.payload.begin(), r.payload.end());
  const uint8_t* header = b.data() + b.size() - kTrailerBytes;
  covered.insert(covered.end(), header, header + 18);
  const HmacTag full = hmac_sha256(k.bytes, covered);
  EXPECT_TRUE(std::equal(r.trailer->tag.begin(), r.trailer->tag.end(), full.begin()));
}

TEST(BusTrailerTest, CountersStrictlyIncreaseEvenWhenTheClockStepsBack) {
  Sealer s(1, std::nullopt);
  uint64_t last = 0;
  for (int64_t t : {kT0, kT0, kT0 - 5'000'000, kT0 + 1}) {
    const auto b = sealed(s, "IMU", t);
    const uint64_t c = rx(b).trailer->counter;
    EXPECT_GT(c, last);
    last = c;
  }
}

TEST(GatekeeperTest, ASignedBusRefusesUnsignedWronglySignedAndAlteredMessages) {
  Gatekeeper g(key_a());
  Sealer genuine(1, key_a());
  EXPECT_EQ(g.check("MOCAP_POSE", rx(sealed(genuine, "MOCAP_POSE", kT0)), 0), Verdict::kNewOwner);

  const auto plain = encoded_pose(kT0 + 10 * kMs);
  EXPECT_EQ(g.check("MOCAP_POSE", rx(plain), 10 * kMs), Verdict::kUnsigned);
  Sealer unsigned_sealer(2, std::nullopt);
  EXPECT_EQ(g.check("MOCAP_POSE", rx(sealed(unsigned_sealer, "MOCAP_POSE", kT0)), 10 * kMs),
            Verdict::kUnsigned);
  Sealer other_key(3, key_b());
  EXPECT_EQ(g.check("MOCAP_POSE", rx(sealed(other_key, "MOCAP_POSE", kT0)), 10 * kMs),
            Verdict::kWrongKey);

  auto altered = sealed(genuine, "MOCAP_POSE", kT0 + 20 * kMs);
  altered[20] ^= 0x01;  // a bit of the pose
  EXPECT_EQ(g.check("MOCAP_POSE", rx(altered), 20 * kMs), Verdict::kBadTag);
  // Signed for another channel: the channel is covered.
  const auto moved = sealed(genuine, "POSITION_SETPOINT", kT0 + 30 * kMs);
  EXPECT_EQ(g.check("MOCAP_POSE", rx(moved), 30 * kMs), Verdict::kBadTag);
  EXPECT_EQ(g.stats("MOCAP_POSE").rejected_auth, 5u);
  EXPECT_EQ(g.check("MOCAP_POSE", rx(sealed(genuine, "MOCAP_POSE", kT0 + 40 * kMs)), 40 * kMs),
            Verdict::kAccepted);
}

TEST(GatekeeperTest, AReplayedMessageIsRefused) {
  Gatekeeper g(key_a());
  Sealer s(1, key_a());
  const auto first = sealed(s, "POSITION_SETPOINT", kT0);
  const auto second = sealed(s, "POSITION_SETPOINT", kT0 + kMs);
  EXPECT_TRUE(accepted(g.check("POSITION_SETPOINT", rx(first), 0)));
  EXPECT_TRUE(accepted(g.check("POSITION_SETPOINT", rx(second), kMs)));
  EXPECT_EQ(g.check("POSITION_SETPOINT", rx(second), 2 * kMs), Verdict::kReplayed);
  EXPECT_EQ(g.check("POSITION_SETPOINT", rx(first), 3 * kMs), Verdict::kReplayed);
}

// A recording signed with the same key, replayed as a "new" publisher a minute later.
TEST(GatekeeperTest, ANewPublisherFarBehindTheBusTimeIsStale) {
  Gatekeeper g(key_a());
  Sealer live(1, key_a()), old(2, key_a()), recent(3, key_a());
  ASSERT_TRUE(accepted(g.check("IMU", rx(sealed(live, "IMU", kT0)), 0)));
  EXPECT_EQ(g.check("CAMERA", rx(sealed(old, "CAMERA", kT0 - 61'000'000)), kMs), Verdict::kStale);
  EXPECT_EQ(g.check("CAMERA", rx(sealed(recent, "CAMERA", kT0 - 10'000'000)), 2 * kMs),
            Verdict::kNewOwner);
  EXPECT_EQ(g.bus_time_us(), kT0);
}

// Regression: one forged POSITION_SETPOINT from another publisher disarmed the vehicle in the air;
// setpoints from a second publisher for 8 s flew it out of the room.
TEST(GatekeeperTest, ASecondPublisherIsRefusedWhileTheFirstIsAliveEvenUnsigned) {
  Gatekeeper g;  // no key: the insecure bus
  Sealer genuine(1, std::nullopt), attacker(2, std::nullopt);
  int64_t t = 0;
  for (int i = 0; i < 50; ++i, t += 10 * kMs) {
    EXPECT_TRUE(accepted(
        g.check("POSITION_SETPOINT", rx(sealed(genuine, "POSITION_SETPOINT", kT0 + t)), t)));
    if (i % 5 == 4) {
      EXPECT_EQ(
          g.check("POSITION_SETPOINT", rx(sealed(attacker, "POSITION_SETPOINT", kT0 + t)), t + 1),
          Verdict::kSecondPublisher);
      // A plain lcm-gen message (no trailer) is another publisher too.
      EXPECT_EQ(g.check("POSITION_SETPOINT", rx(encoded_pose(kT0 + t)), t + 2),
                Verdict::kSecondPublisher);
    }
  }
  EXPECT_EQ(g.stats("POSITION_SETPOINT").second_publisher, 20u);
  EXPECT_TRUE(g.contested("POSITION_SETPOINT", t, 2'000'000));
  EXPECT_FALSE(g.contested("POSITION_SETPOINT", t + 3'000'000, 2'000'000));
  EXPECT_EQ(g.stats("POSITION_SETPOINT").owner, 1u);
}

// A restarted node has a new publisher id: it takes the channel once the old one is silent.
TEST(GatekeeperTest, ASilentOwnerIsSucceededByTheNextPublisher) {
  Gatekeeper g;
  Sealer before(1, std::nullopt), after(2, std::nullopt);
  int64_t t = 0;
  for (int i = 0; i < 20; ++i, t += 10 * kMs)
    ASSERT_TRUE(accepted(g.check("MOCAP_POSE", rx(sealed(before, "MOCAP_POSE", kT0 + t)), t)));
  // 100 Hz: silent for 10 periods (0.1 s) is not enough, the 0.2 s floor is.
  EXPECT_EQ(g.check("MOCAP_POSE", rx(sealed(after, "MOCAP_POSE", kT0 + t)), t + 150 * kMs),
            Verdict::kSecondPublisher);
  EXPECT_EQ(g.check("MOCAP_POSE", rx(sealed(after, "MOCAP_POSE", kT0 + t + 1)), t + 250 * kMs),
            Verdict::kNewOwner);
  EXPECT_EQ(g.stats("MOCAP_POSE").owner_changes, 1u);
  EXPECT_EQ(g.check("MOCAP_POSE", rx(sealed(before, "MOCAP_POSE", kT0 + t + 2)), t + 260 * kMs),
            Verdict::kSecondPublisher);
}

TEST(GatekeeperTest, AChannelWithManyPublishersTakesThemAll) {
  Gatekeeper g;
  Sealer a(1, std::nullopt), b(2, std::nullopt);
  for (int i = 0; i < 10; ++i) {
    EXPECT_TRUE(accepted(g.check("NODE_STATUS", rx(sealed(a, "NODE_STATUS", kT0 + i)), i, false)));
    EXPECT_TRUE(accepted(g.check("NODE_STATUS", rx(sealed(b, "NODE_STATUS", kT0 + i)), i, false)));
  }
  EXPECT_EQ(g.stats("NODE_STATUS").second_publisher, 0u);
}

// An attacker drawing a new publisher id for every message neither grows memory nor takes over.
TEST(GatekeeperTest, AFloodOfPublisherIdsIsBoundedAndRefused) {
  Gatekeeper g;
  Sealer genuine(1, std::nullopt);
  int64_t t = 0;
  for (int i = 0; i < 5000; ++i, t += kMs) {
    if (i % 10 == 0) {
      ASSERT_TRUE(accepted(g.check("CAMERA", rx(sealed(genuine, "CAMERA", kT0 + t)), t)));
    }
    Sealer flood(1000 + static_cast<uint64_t>(i), std::nullopt);
    EXPECT_EQ(g.check("CAMERA", rx(sealed(flood, "CAMERA", kT0 + t)), t + 1),
              Verdict::kSecondPublisher);
  }
  EXPECT_LE(g.known_sources("CAMERA"), kMaxSourcesPerChannel);
  EXPECT_EQ(g.stats("CAMERA").owner, 1u);
}

TEST(BusKeyTest, KeyIdsDifferAndAreNeverZero) {
  EXPECT_NE(key_a().id, 0);
  EXPECT_NE(key_b().id, 0);
  EXPECT_NE(key_a().id, key_b().id);
}

}  // namespace
}  // namespace alight::bus
