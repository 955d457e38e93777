// The attack campaign's messages (tools/attack.hpp): each attack sends what it says, decodable by
// the vehicle's nodes, and LCM's datagram layout.
#include "tools/attack.hpp"

#include <gtest/gtest.h>

#include "common/bus_auth.hpp"
#include "common/channels.hpp"
#include "common/decode.hpp"

namespace alight::tools::attack {
namespace {

constexpr int64_t kAttackNow = 1'800'000'000'000'000;

Overheard overheard() {
  Overheard h;
  pose_t p{};
  p.utime = kAttackNow - 10'000;
  p.pos[0] = 0.5;
  p.pos[2] = 1.5;
  p.orientation[0] = 1;
  h.pose = p;
  position_setpoint_t s{};
  s.utime = kAttackNow - 5000;
  s.p_W[2] = 1.5;
  s.motors = position_setpoint_t::MOTORS_ON;
  h.setpoint = s;
  std::vector<uint8_t> raw(static_cast<size_t>(p.getEncodedSize()));
  p.encode(raw.data(), 0, static_cast<int>(raw.size()));
  bus::Sealer genuine(0xabcdefULL, std::nullopt);
  genuine.seal(raw, channels::kMocapPose, kAttackNow - 10'000);
  h.raw.emplace_back(channels::kMocapPose, raw);
  return h;
}

template <class Msg>
Msg decoded(const Datagram& d) {
  Msg m;
  EXPECT_TRUE(decode_message(m, d.payload.data(), d.payload.size())) << d.channel;
  return m;
}

TEST(AttackTest, EveryAttackSendsDecodableMessagesHeardOrNot) {
  std::mt19937_64 rng(1);
  for (Kind k : all()) {
    for (const Overheard& h : {Overheard{}, overheard()}) {
      const auto out = round(k, 0.0, kAttackNow, h, rng);
      ASSERT_FALSE(out.empty()) << name(k);
      for (const auto& d : out) {
        EXPECT_TRUE(channels::is_known(d.channel)) << name(k) << " " << d.channel;
        EXPECT_LE(d.payload.size(), 60000u) << "fits one datagram";
      }
    }
    EXPECT_EQ(parse(name(k)), k);
  }
}

TEST(AttackTest, TheForgeriesAreWhatTheCampaignSays) {
  std::mt19937_64 rng(1);
  const Overheard h = overheard();
  const auto kill =
      decoded<position_setpoint_t>(round(Kind::kKillSetpoint, 0, kAttackNow, h, rng)[0]);
  EXPECT_EQ(kill.motors, position_setpoint_t::MOTORS_KILL);
  EXPECT_EQ(kill.utime, kAttackNow + 450'000);
  const auto far =
      decoded<position_setpoint_t>(round(Kind::kSetpointStream, 0, kAttackNow, h, rng)[0]);
  EXPECT_DOUBLE_EQ(far.p_W[0], 20.0);
  const auto off = decoded<pose_t>(round(Kind::kPoseOffset, 0, kAttackNow, h, rng)[0]);
  EXPECT_DOUBLE_EQ(off.pos[0], 0.8);
  EXPECT_EQ(off.utime, h.pose->utime + 50'000);
  const auto grown = decoded<pose_t>(round(Kind::kPoseGrowing, 2.0, kAttackNow, h, rng)[0]);
  EXPECT_DOUBLE_EQ(grown.pos[0], 1.5);
  const auto target = decoded<target_t>(round(Kind::kVisionTarget, 0, kAttackNow, h, rng)[0]);
  EXPECT_TRUE(target.found);
  EXPECT_DOUBLE_EQ(target.p_W_target[0], 0.8 + 0.25);
  // Spoofed: the live publisher's id, a counter just above its last, no signature.
  const auto spoof = round(Kind::kPoseSpoofed, 0, kAttackNow, h, rng)[0];
  const auto r = bus::split(spoof.payload.data(), spoof.payload.size());
  ASSERT_TRUE(r.trailer);
  EXPECT_EQ(r.trailer->source, 0xabcdefULL);
  EXPECT_EQ(r.trailer->counter, static_cast<uint64_t>(kAttackNow - 10'000 + 1));
  EXPECT_EQ(r.trailer->key_id, 0);
  // A second publisher: the same content without the publisher's trailer.
  const auto copy = round(Kind::kSecondPublisher, 0, kAttackNow, h, rng)[0];
  EXPECT_FALSE(bus::split(copy.payload.data(), copy.payload.size()).trailer);
  EXPECT_EQ(decoded<pose_t>(copy).pos[0], 0.5);
}

TEST(AttackTest, LcmDatagramLayout) {
  const auto d = lcm_datagram("AB", {1, 2, 3}, 0x01020304);
  const std::vector<uint8_t> want = {'L', 'C', '0', '2', 1, 2, 3, 4, 'A', 'B', 0, 1, 2, 3};
  EXPECT_EQ(d, want);
}

}  // namespace
}  // namespace alight::tools::attack
