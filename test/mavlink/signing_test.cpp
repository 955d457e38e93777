// Message signing: keys, timestamps, and what the parser accepts with a key
// (mavlink.io/en/guide/message_signing.html).

#include "mavlink/signing.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "mavlink/parser.hpp"
#include "test/mavlink/sample_messages.hpp"

namespace alight::mavlink {
namespace {

using testing::distinct_message;
using Bytes = std::vector<uint8_t>;

SigningKey key_of(uint8_t fill) {
  SigningKey k;
  k.fill(fill);
  return k;
}

constexpr int64_t kT0 = kSigningEpochUnixUtime + 350'000'000'000'000;  // 2026

std::vector<Frame> feed(Parser& p, const std::vector<FrameBytes>& frames) {
  std::vector<Frame> out;
  Frame f;
  for (const FrameBytes& b : frames) {
    p.push(b.bytes());
    while (p.next(f)) out.push_back(f);
  }
  return out;
}

ParserOptions with_key(const SigningKey& k) {
  ParserOptions o;
  o.key = k;
  return o;
}

TEST(MavlinkSigning, TimestampIsTenMicrosecondUnitsSince2015) {
  EXPECT_EQ(signing_timestamp_from_unix_utime(kSigningEpochUnixUtime), 0u);
  EXPECT_EQ(signing_timestamp_from_unix_utime(kSigningEpochUnixUtime + 10), 1u);
  EXPECT_EQ(signing_timestamp_from_unix_utime(kSigningEpochUnixUtime + 1'000'000), 100'000u);
  EXPECT_EQ(signing_timestamp_from_unix_utime(0), 0u) << "before 2015";
  EXPECT_EQ(signing_timestamp_from_unix_utime(-5), 0u);
  EXPECT_EQ(signing_timestamp_from_unix_utime(INT64_MAX), kMaxSigningTimestamp);
}

TEST(MavlinkSigning, KeysFromPassphraseAndHex) {
  // SHA-256 of the empty string.
  const SigningKey empty = signing_key_from_passphrase("");
  EXPECT_EQ(empty[0], 0xE3);
  EXPECT_EQ(empty[1], 0xB0);
  EXPECT_EQ(empty[31], 0x55);
  const auto k =
      signing_key_from_hex(" 000102030405060708090a0b0c0d0e0f101112131415161718191A1B1C1D1E1F\n");
  ASSERT_TRUE(k.has_value());
  for (size_t i = 0; i < k->size(); ++i) EXPECT_EQ((*k)[i], i);
  EXPECT_FALSE(signing_key_from_hex("00").has_value());
  EXPECT_FALSE(signing_key_from_hex(std::string(64, 'g')).has_value());
}

TEST(MavlinkSigning, CorrectlySignedFramesAreVerifiedAndDelivered) {
  const SigningKey key = key_of(0x42);
  Sender s(1, 1, SigningConfig{key, 5});
  Parser p(with_key(key));
  const auto frames = feed(
      p, {s.pack(distinct_message<Heartbeat>(1), kT0), s.pack(distinct_message<Odometry>(1), kT0)});
  ASSERT_EQ(frames.size(), 2u);
  for (const Frame& f : frames) {
    ASSERT_TRUE(f.signature.has_value());
    EXPECT_TRUE(f.signature_verified);
    EXPECT_EQ(f.signature->link_id, 5);
  }
  EXPECT_LT(frames[0].signature->timestamp, frames[1].signature->timestamp);
  EXPECT_EQ(p.streams().stream_count(), 1u);
}

TEST(MavlinkSigning, AWrongKeyOrATamperedFrameIsRefused) {
  Sender s(1, 1, SigningConfig{key_of(0x42), 5});
  {
    Parser p(with_key(key_of(0x43)));
    EXPECT_TRUE(feed(p, {s.pack(distinct_message<Heartbeat>(1), kT0)}).empty());
    EXPECT_EQ(p.stats().signature_failures, 1u);
  }
  for (size_t byte : {1u, 5u, 12u, 20u}) {  // len, sysid, payload; the checksum is redone
    FrameBytes f = s.pack(distinct_message<HighresImu>(1), kT0);
    f.data[byte] ^= 0x04;
    const size_t len = f.data[1];
    if (byte != 1) {  // re-checksum so that only the signature can catch it
      uint16_t crc = crc_accumulate(f.data.data() + 1, 9 + len, kCrcInit);
      crc = crc_accumulate(HighresImu::kCrcExtra, crc);
      f.data[10 + len] = crc & 0xFF;
      f.data[11 + len] = crc >> 8;
    }
    Parser p(with_key(key_of(0x42)));
    EXPECT_TRUE(feed(p, {f}).empty()) << "byte " << byte;
    EXPECT_EQ(p.stats().frames_ok, 0u);
  }
}

TEST(MavlinkSigning, AReplayedFrameIsRefused) {
  const SigningKey key = key_of(7);
  Sender s(1, 1, SigningConfig{key, 0});
  const FrameBytes a = s.pack(distinct_message<CommandLong>(1), kT0);
  const FrameBytes b = s.pack(distinct_message<CommandLong>(2), kT0);
  Parser p(with_key(key));
  const auto frames = feed(p, {a, b, a, b});
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(p.stats().replays, 2u);
}

TEST(MavlinkSigning, StreamsAreSystemComponentAndLinkEach) {
  const SigningKey key = key_of(7);
  Sender s1(1, 1, SigningConfig{key, 0});
  Sender s2(2, 1, SigningConfig{key, 0});
  Sender s3(1, 1, SigningConfig{key, 1});
  Parser p(with_key(key));
  // The same timestamp on three streams: each is its stream's first.
  const auto frames =
      feed(p, {s1.pack(Heartbeat{}, kT0), s2.pack(Heartbeat{}, kT0), s3.pack(Heartbeat{}, kT0)});
  EXPECT_EQ(frames.size(), 3u);
  EXPECT_EQ(p.streams().stream_count(), 3u);
}

TEST(MavlinkSigning, ANewStreamMoreThanAMinuteBehindIsRefused) {
  const SigningKey key = key_of(7);
  Parser p(with_key(key));
  p.observe_time(kT0);
  Sender late(1, 1, SigningConfig{key, 0});
  Sender recent(2, 1, SigningConfig{key, 0});
  EXPECT_TRUE(feed(p, {late.pack(Heartbeat{}, kT0 - 61'000'000)}).empty());
  EXPECT_EQ(p.stats().replays, 1u);
  EXPECT_EQ(feed(p, {recent.pack(Heartbeat{}, kT0 - 59'000'000)}).size(), 1u);
  // A known stream may lag the receiver's clock: only its own order matters.
  EXPECT_EQ(feed(p, {recent.pack(Heartbeat{}, kT0 - 58'000'000)}).size(), 1u);
}

TEST(MavlinkSigning, UnsignedFramesNeedPermissionWhenAKeyIsSet) {
  Sender plain(1, 1);
  {
    Parser p(with_key(key_of(1)));
    EXPECT_TRUE(feed(p, {plain.pack(Heartbeat{}, 0)}).empty());
    EXPECT_EQ(p.stats().unsigned_refused, 1u);
  }
  {
    ParserOptions o = with_key(key_of(1));
    o.accept_unsigned = true;
    Parser p(o);
    const auto frames = feed(p, {plain.pack(Heartbeat{}, 0)});
    ASSERT_EQ(frames.size(), 1u);
    EXPECT_FALSE(frames[0].signature.has_value());
  }
}

TEST(MavlinkSigning, WithoutAKeySignedFramesAreDeliveredUnverified) {
  Sender s(1, 1, SigningConfig{key_of(3), 2});
  Parser p;
  const auto frames = feed(p, {s.pack(Heartbeat{}, kT0)});
  ASSERT_EQ(frames.size(), 1u);
  ASSERT_TRUE(frames[0].signature.has_value());
  EXPECT_FALSE(frames[0].signature_verified);
  EXPECT_EQ(p.stats().signed_unverified, 1u);
}

TEST(MavlinkSigning, SignedStreamsKeepTheNewestTimestamp) {
  SignedStreams st;
  EXPECT_EQ(st.accept(1, 1, 0, 1000), SignedStreams::Verdict::kAccepted);
  EXPECT_EQ(st.accept(1, 1, 0, 1000), SignedStreams::Verdict::kReplay);
  EXPECT_EQ(st.accept(1, 1, 0, 999), SignedStreams::Verdict::kReplay);
  EXPECT_EQ(st.accept(1, 1, 0, 1001), SignedStreams::Verdict::kAccepted);
  EXPECT_EQ(st.local_timestamp(), 1001u);
  st.observe(500);
  EXPECT_EQ(st.local_timestamp(), 1001u) << "never lowered";
  st.observe(kNewStreamMaxLag + 2000);
  EXPECT_EQ(st.accept(9, 9, 9, 1999), SignedStreams::Verdict::kTooOld);
  EXPECT_EQ(st.accept(9, 9, 9, 2000), SignedStreams::Verdict::kAccepted);
}

}  // namespace
}  // namespace alight::mavlink
