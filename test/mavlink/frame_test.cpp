// Frame encoding: header layout, checksum, signing trailer, sequence numbers and signing
// timestamps (mavlink.io/en/guide/serialization.html "MAVLink 2 Packet Format",
// message_signing.html "Timestamp Handling").

#include "mavlink/frame.hpp"

#include <gtest/gtest.h>

#include "mavlink/crc.hpp"
#include "test/mavlink/sample_messages.hpp"

namespace alight::mavlink {
namespace {

using testing::distinct_message;

TEST(MavlinkFrame, HeaderChecksumAndPayloadKnownAnswer) {
  Sender s(7, 191);
  CommandAck ack;
  ack.command = 400;
  ack.result = 0;
  const FrameBytes f = s.pack(ack, 0);
  // command 400 = 90 01, result 0 truncated away: a 2-byte payload.
  ASSERT_EQ(f.size, 10u + 2u + 2u);
  const uint8_t header[] = {0xFD, 2, 0, 0, 0, 7, 191, 77, 0, 0, 0x90, 0x01};
  EXPECT_EQ(std::vector<uint8_t>(f.data.begin(), f.data.begin() + 12),
            std::vector<uint8_t>(std::begin(header), std::end(header)));
  uint16_t crc = crc_accumulate(f.data.data() + 1, 11, kCrcInit);
  crc = crc_accumulate(CommandAck::kCrcExtra, crc);
  EXPECT_EQ(f.data[12], crc & 0xFF);
  EXPECT_EQ(f.data[13], crc >> 8);
}

TEST(MavlinkFrame, SequenceNumbersIncreaseAndWrap) {
  Sender s(1, 1);
  for (int i = 0; i < 300; ++i) {
    const FrameBytes f = s.pack(Heartbeat{}, 0);
    EXPECT_EQ(f.data[4], static_cast<uint8_t>(i));
  }
  EXPECT_EQ(s.next_seq(), static_cast<uint8_t>(300));
}

TEST(MavlinkFrame, MessageIdIsTwentyFourBitsLittleEndian) {
  Sender s(1, 1);
  const FrameBytes f = s.pack(distinct_message<Odometry>(1), 0);
  EXPECT_EQ(f.data[7], 331 & 0xFF);
  EXPECT_EQ(f.data[8], 331 >> 8);
  EXPECT_EQ(f.data[9], 0);
}

TEST(MavlinkFrame, SignedFrameCarriesLinkTimestampAndTheSignatureOfEverythingBefore) {
  SigningKey key{};
  key.fill(0x11);
  Sender s(1, 1, SigningConfig{key, 9});
  const int64_t now = kSigningEpochUnixUtime + 123'456'789'000;  // 123456.789 s after 2015
  const FrameBytes f = s.pack(distinct_message<Timesync>(1), now);
  const size_t len = f.data[1];
  ASSERT_EQ(f.size, 10 + len + 2 + 13);
  EXPECT_EQ(f.data[2], kIncompatSigned);
  const uint8_t* sig = f.data.data() + 10 + len + 2;
  EXPECT_EQ(sig[0], 9);
  uint64_t ts = 0;
  for (int i = 0; i < 6; ++i) ts |= uint64_t{sig[1 + i]} << (8 * i);
  EXPECT_EQ(ts, 12'345'678'900u);  // 10 us units
  const auto expected = compute_signature(key, f.data.data(), f.size - 6);
  EXPECT_EQ(std::vector<uint8_t>(sig + 7, sig + 13),
            std::vector<uint8_t>(expected.begin(), expected.end()));
  // The checksum covers the header with the signed flag.
  uint16_t crc = crc_accumulate(f.data.data() + 1, 9 + len, kCrcInit);
  crc = crc_accumulate(Timesync::kCrcExtra, crc);
  EXPECT_EQ(f.data[10 + len] | (f.data[11 + len] << 8), crc);
}

TEST(MavlinkFrame, SigningTimestampsIncreaseWhenTheClockStandsStillOrStepsBack) {
  Sender s(1, 1, SigningConfig{SigningKey{}, 0});
  const int64_t t = kSigningEpochUnixUtime + 1'000'000;
  const auto stamp = [](const FrameBytes& f) {
    const uint8_t* sig = f.data.data() + f.size - kSignatureLength;
    uint64_t ts = 0;
    for (int i = 0; i < 6; ++i) ts |= uint64_t{sig[1 + i]} << (8 * i);
    return ts;
  };
  EXPECT_EQ(stamp(s.pack(Heartbeat{}, t)), 100'000u);
  EXPECT_EQ(stamp(s.pack(Heartbeat{}, t)), 100'001u);
  EXPECT_EQ(stamp(s.pack(Heartbeat{}, t - 500'000)), 100'002u);
  EXPECT_EQ(stamp(s.pack(Heartbeat{}, 0)), 100'003u) << "a clock before 2015";
  EXPECT_EQ(stamp(s.pack(Heartbeat{}, t + 1'000'000)), 200'000u);
  s.raise_signing_timestamp(kMaxSigningTimestamp);
  EXPECT_EQ(stamp(s.pack(Heartbeat{}, t)), kMaxSigningTimestamp) << "saturates at 48 bits";
}

TEST(MavlinkFrame, VersionOneFrameLayout) {
  const Heartbeat hb = distinct_message<Heartbeat>(1);
  std::array<uint8_t, Heartbeat::kMaxLength> payload{};
  encode_payload(hb, payload.data());
  std::array<uint8_t, kMaxFrameLength> out{};
  const size_t n = write_frame_v1({5, 2, 3, 0}, 0, Heartbeat::kCrcExtra, payload.data(),
                                  Heartbeat::kBaseLength, out.data());
  ASSERT_EQ(n, 6u + 9u + 2u);
  EXPECT_EQ(out[0], 0xFE);
  EXPECT_EQ(out[1], 9);
  EXPECT_EQ(out[2], 5);
  EXPECT_EQ(out[3], 2);
  EXPECT_EQ(out[4], 3);
  EXPECT_EQ(out[5], 0);
  const uint16_t crc =
      crc_accumulate(Heartbeat::kCrcExtra, crc_accumulate(out.data() + 1, 5 + 9, kCrcInit));
  EXPECT_EQ(out[15] | (out[16] << 8), crc);
}

}  // namespace
}  // namespace alight::mavlink
