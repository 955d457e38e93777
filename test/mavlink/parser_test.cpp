// The streaming parser: chunking, resynchronisation, unknown messages, flags, MAVLink 1, and
// that every byte is accounted for.

#include "mavlink/parser.hpp"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "test/mavlink/sample_messages.hpp"

namespace alight::mavlink {
namespace {

using testing::distinct_message;

using Bytes = std::vector<uint8_t>;

void append(Bytes& out, const FrameBytes& f) {
  out.insert(out.end(), f.data.begin(), f.data.begin() + f.size);
}

// One frame of every known message, several times over.
Bytes sample_stream(int rounds, std::vector<uint32_t>* ids = nullptr) {
  Sender s(1, 1);
  Bytes out;
  for (int r = 0; r < rounds; ++r)
    for_each_message_type([&](auto tag) {
      using M = decltype(tag);
      append(out, s.pack(distinct_message<M>(r + 1), 0));
      if (ids) ids->push_back(M::kId);
    });
  return out;
}

std::vector<Frame> parse_all(Parser& p, const Bytes& bytes, size_t chunk = 0) {
  std::vector<Frame> frames;
  Frame f;
  size_t pos = 0;
  while (pos < bytes.size()) {
    const size_t n = chunk == 0 ? bytes.size() - pos : std::min(chunk, bytes.size() - pos);
    p.push({bytes.data() + pos, n});
    pos += n;
    while (p.next(f)) frames.push_back(f);
  }
  return frames;
}

// Every byte pushed is in a delivered frame, a skipped frame, dropped, or still buffered.
void expect_accounted(const Parser& p) {
  const ParserStats& s = p.stats();
  EXPECT_EQ(s.bytes_in, s.bytes_delivered + s.bytes_skipped + s.bytes_dropped + p.buffered());
}

// A message's decoding equals what was sent.
template <class M>
void expect_message(const Frame& f, uint64_t seed) {
  const auto m = decode<M>(f);
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(*m, distinct_message<M>(seed));
}

TEST(MavlinkParser, SameFramesWhateverTheChunking) {
  std::vector<uint32_t> ids;
  const Bytes stream = sample_stream(3, &ids);
  for (size_t chunk : {0, 1, 2, 3, 7, 64, 279, 280, 281}) {
    SCOPED_TRACE(chunk);
    Parser p;
    const auto frames = parse_all(p, stream, chunk);
    ASSERT_EQ(frames.size(), ids.size());
    for (size_t i = 0; i < ids.size(); ++i) EXPECT_EQ(frames[i].msgid, ids[i]);
    EXPECT_EQ(p.stats().frames_ok, ids.size());
    EXPECT_EQ(p.stats().bytes_delivered, stream.size());
    EXPECT_EQ(p.buffered(), 0u);
    expect_accounted(p);
  }
}

TEST(MavlinkParser, DecodedMessagesEqualTheSentOnes) {
  Sender s(3, 4);
  Bytes stream;
  append(stream, s.pack(distinct_message<AttPosMocap>(9), 0));
  append(stream, s.pack(distinct_message<Odometry>(9), 0));
  append(stream, s.pack(distinct_message<Statustext>(9), 0));
  Parser p;
  const auto frames = parse_all(p, stream, 5);
  ASSERT_EQ(frames.size(), 3u);
  expect_message<AttPosMocap>(frames[0], 9);
  expect_message<Odometry>(frames[1], 9);
  expect_message<Statustext>(frames[2], 9);
  EXPECT_EQ(frames[1].sysid, 3);
  EXPECT_EQ(frames[1].compid, 4);
  EXPECT_EQ(frames[1].seq, 1);
  EXPECT_FALSE(decode<Heartbeat>(frames[0]).has_value()) << "another message's frame";
}

TEST(MavlinkParser, ResynchronisesAfterGarbageFullOfStartMarkers) {
  // Noise between every frame, a third of it start markers: every frame still arrives.
  std::mt19937 rng(16);
  std::vector<uint32_t> ids;
  Sender s(1, 1);
  Bytes stream;
  for (int r = 0; r < 40; ++r)
    for_each_message_type([&](auto tag) {
      using M = decltype(tag);
      const int n = static_cast<int>(rng() % 40);
      for (int i = 0; i < n; ++i) {
        const uint32_t x = rng();
        stream.push_back(x % 3 == 0 ? (x & 8 ? kStxV2 : kStxV1) : static_cast<uint8_t>(x >> 8));
      }
      append(stream, s.pack(distinct_message<M>(r), 0));
      ids.push_back(M::kId);
    });
  for (size_t chunk : {0, 1, 13}) {
    SCOPED_TRACE(chunk);
    Parser p;
    const auto frames = parse_all(p, stream, chunk);
    ASSERT_EQ(frames.size(), ids.size());
    for (size_t i = 0; i < ids.size(); ++i) ASSERT_EQ(frames[i].msgid, ids[i]) << i;
    EXPECT_GT(p.stats().bytes_dropped, 0u);
    expect_accounted(p);
  }
}

TEST(MavlinkParser, ABadChecksumDropsOnlyTheStartMarker) {
  // A frame whose checksum is wrong hides a real frame inside its declared length: the real
  // frame is still found.
  Sender s(1, 1);
  const FrameBytes inner = s.pack(distinct_message<Heartbeat>(1), 0);
  Bytes stream = {kStxV2, static_cast<uint8_t>(inner.size + 4), 0, 0, 0, 1, 1, 0, 0,
                  0};  // HEARTBEAT
  append(stream, inner);
  stream.insert(stream.end(), {0x12, 0x34, 0x56, 0x78, 0xAB, 0xCD});  // rest of payload, "crc"
  Parser p;
  const auto frames = parse_all(p, stream);
  ASSERT_EQ(frames.size(), 1u);
  expect_message<Heartbeat>(frames[0], 1);
  EXPECT_EQ(p.stats().crc_errors, 1u);
  expect_accounted(p);
}

TEST(MavlinkParser, EveryCorruptedByteIsCaughtAndTheNextFrameStillArrives) {
  Sender s(1, 1);
  const FrameBytes a = s.pack(distinct_message<HighresImu>(1), 0);
  const FrameBytes b = s.pack(distinct_message<LocalPositionNed>(2), 0);
  for (size_t i = 1; i < a.size; ++i)
    for (uint8_t bit : {0x01, 0x80}) {
      Bytes stream;
      append(stream, a);
      stream[i] ^= bit;
      append(stream, b);
      Parser p;
      const auto frames = parse_all(p, stream);
      ASSERT_FALSE(frames.empty()) << "byte " << i;
      EXPECT_EQ(frames.back().msgid, LocalPositionNed::kId) << "byte " << i;
      for (const Frame& f : frames) EXPECT_NE(f.msgid, HighresImu::kId) << "byte " << i;
      expect_accounted(p);
    }
}

TEST(MavlinkParser, UnknownMessagesAreSkippedWholeAndCounted) {
  Sender s(1, 1);
  Bytes stream;
  const uint8_t payload[20] = {1, 2, 3, kStxV2, 5, 6, kStxV1, 8, 9, 10};
  // MISSION_ITEM_INT (73) and a 24-bit id: unknown to alight.
  append(stream, s.pack_payload(73, 38, payload, 20, 0));
  append(stream, s.pack_payload(0xABCDEF, 1, payload, 7, 0));
  append(stream, s.pack(distinct_message<Heartbeat>(1), 0));
  Parser p;
  const auto frames = parse_all(p, stream, 3);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].msgid, Heartbeat::kId);
  EXPECT_EQ(p.stats().unknown_ids, 2u);
  EXPECT_EQ(p.stats().bytes_dropped, 0u);
  expect_accounted(p);
}

TEST(MavlinkParser, AnUnknownFrameFollowedByNoiseIsTakenForNoise) {
  Sender s(1, 1);
  Bytes stream;
  const uint8_t payload[4] = {1, 2, 3, 4};
  append(stream, s.pack_payload(9999, 0, payload, 4, 0));
  stream.push_back(0x00);  // not a start marker
  append(stream, s.pack(distinct_message<Heartbeat>(1), 0));
  Parser p;
  const auto frames = parse_all(p, stream);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(p.stats().unknown_ids, 0u);
  expect_accounted(p);
}

TEST(MavlinkParser, AFalseStartWithAnUnknownIdDoesNotSwallowTheFrameInside) {
  // A start marker with a length reaching exactly to the start of the next real frame, so the
  // "another frame starts right after" test alone would skip the first real frame.
  Sender s(1, 1);
  const FrameBytes first = s.pack(distinct_message<Timesync>(1), 0);
  const FrameBytes second = s.pack(distinct_message<Heartbeat>(2), 0);
  const uint8_t len = static_cast<uint8_t>(first.size - 2);  // 10 + len + 2 = 10 + first.size
  Bytes stream = {kStxV2, len, 0, 0, 0, 1, 1, 0x42, 0x42, 0x42};
  append(stream, first);
  append(stream, second);
  Parser p;
  const auto frames = parse_all(p, stream);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].msgid, Timesync::kId);
  EXPECT_EQ(frames[1].msgid, Heartbeat::kId);
  EXPECT_EQ(p.stats().unknown_ids, 0u);
  expect_accounted(p);
}

TEST(MavlinkParser, UnknownIncompatibilityFlagsAreRefused) {
  Sender s(1, 1);
  FrameBytes f = s.pack(distinct_message<Heartbeat>(1), 0);
  f.data[2] = 0x02;  // a flag alight does not know (the checksum does not matter)
  Bytes stream;
  append(stream, f);
  append(stream, s.pack(distinct_message<Heartbeat>(2), 0));
  Parser p;
  const auto frames = parse_all(p, stream);
  ASSERT_EQ(frames.size(), 1u);
  expect_message<Heartbeat>(frames[0], 2);
  EXPECT_EQ(p.stats().incompat_flags, 1u);
  expect_accounted(p);
}

TEST(MavlinkParser, CompatibilityFlagsAreIgnored) {
  const Heartbeat hb = distinct_message<Heartbeat>(1);
  std::array<uint8_t, 9> payload;
  const uint8_t n = encode_payload(hb, payload.data());
  FrameBytes f;
  f.size = write_frame({0, 1, 1, 0x80}, Heartbeat::kId, Heartbeat::kCrcExtra, payload.data(), n,
                       std::nullopt, f.data.data());
  Parser p;
  Bytes stream;
  append(stream, f);
  const auto frames = parse_all(p, stream);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].compat_flags, 0x80);
}

TEST(MavlinkParser, UntruncatedAndEmptyPayloadsAreZeroExtended) {
  Sender s(1, 1);
  CommandAck ack = distinct_message<CommandAck>(1);
  ack.target_component = 0;  // so that a truncating sender would send fewer bytes
  std::array<uint8_t, CommandAck::kMaxLength> payload;
  encode_payload(ack, payload.data());
  Bytes stream;
  append(stream, s.pack_payload(CommandAck::kId, CommandAck::kCrcExtra, payload.data(),
                                CommandAck::kMaxLength, 0));  // trailing zero kept: allowed
  append(stream, s.pack_payload(CommandAck::kId, CommandAck::kCrcExtra, payload.data(), 0, 0));
  append(stream, s.pack_payload(CommandAck::kId, CommandAck::kCrcExtra, payload.data(),
                                CommandAck::kBaseLength, 0));  // an older sender: no extensions
  Parser p;
  const auto frames = parse_all(p, stream);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(*decode<CommandAck>(frames[0]), ack);
  EXPECT_EQ(*decode<CommandAck>(frames[1]), CommandAck{}) << "len 0: every field zero";
  const CommandAck old = *decode<CommandAck>(frames[2]);
  EXPECT_EQ(old.command, ack.command);
  EXPECT_EQ(old.result, ack.result);
  EXPECT_EQ(old.progress, 0);
  EXPECT_EQ(old.result_param2, 0);
}

TEST(MavlinkParser, PayloadsLongerThanKnownAreDeliveredOrRefusedAsConfigured) {
  // A newer definition of TIMESYNC with one more extension byte.
  Sender s(1, 1);
  const Timesync ts = distinct_message<Timesync>(1);
  std::array<uint8_t, 32> payload{};
  encode_payload(ts, payload.data());
  payload[Timesync::kMaxLength] = 0x77;
  Bytes stream;
  append(stream, s.pack_payload(Timesync::kId, Timesync::kCrcExtra, payload.data(),
                                Timesync::kMaxLength + 1, 0));
  {
    Parser p;
    const auto frames = parse_all(p, stream);
    ASSERT_EQ(frames.size(), 1u);
    EXPECT_EQ(*decode<Timesync>(frames[0]), ts);
    EXPECT_EQ(p.stats().longer_than_known, 1u);
  }
  {
    ParserOptions o;
    o.refuse_longer_than_known = true;
    Parser p(o);
    EXPECT_TRUE(parse_all(p, stream).empty());
    EXPECT_EQ(p.stats().longer_than_known, 1u);
    expect_accounted(p);
  }
}

TEST(MavlinkParser, ReadsMavlinkOneFramesOfKnownMessages) {
  const LocalPositionNed lp = distinct_message<LocalPositionNed>(1);
  std::array<uint8_t, LocalPositionNed::kMaxLength> payload;
  encode_payload(lp, payload.data());
  std::array<uint8_t, kMaxFrameLength> v1{};
  const size_t n = write_frame_v1({9, 2, 3, 0}, LocalPositionNed::kId, LocalPositionNed::kCrcExtra,
                                  payload.data(), LocalPositionNed::kBaseLength, v1.data());
  Bytes stream(v1.begin(), v1.begin() + n);
  {
    Parser p;
    const auto frames = parse_all(p, stream, 4);
    ASSERT_EQ(frames.size(), 1u);
    EXPECT_EQ(frames[0].version, 1);
    EXPECT_EQ(frames[0].seq, 9);
    EXPECT_EQ(frames[0].sysid, 2);
    EXPECT_EQ(frames[0].compid, 3);
    EXPECT_EQ(*decode<LocalPositionNed>(frames[0]), lp);
    EXPECT_EQ(p.stats().frames_v1, 1u);
  }
  {
    ParserOptions o;
    o.accept_v1 = false;
    Parser p(o);
    Sender s(1, 1);
    append(stream, s.pack(distinct_message<Heartbeat>(1), 0));  // confirms the skipped length
    const auto frames = parse_all(p, stream);
    ASSERT_EQ(frames.size(), 1u);
    EXPECT_EQ(frames[0].msgid, Heartbeat::kId);
    EXPECT_EQ(p.stats().v1_skipped, 1u);
    expect_accounted(p);
  }
}

TEST(MavlinkParser, RefusesMavlinkOneFramesShorterThanTheMessage) {
  const Heartbeat hb = distinct_message<Heartbeat>(1);
  std::array<uint8_t, 9> payload;
  encode_payload(hb, payload.data());
  std::array<uint8_t, kMaxFrameLength> v1{};
  const size_t n =
      write_frame_v1({0, 1, 1, 0}, 0, Heartbeat::kCrcExtra, payload.data(), 8, v1.data());
  Parser p;
  EXPECT_TRUE(parse_all(p, Bytes(v1.begin(), v1.begin() + n)).empty());
  EXPECT_EQ(p.stats().bad_length, 1u);
  expect_accounted(p);
}

TEST(MavlinkParser, WaitsForTheRestOfAFrameAndClearForgetsIt) {
  Sender s(1, 1);
  const FrameBytes f = s.pack(distinct_message<Odometry>(1), 0);
  Parser p;
  p.push({f.data.data(), f.size - 1});
  Frame out;
  EXPECT_FALSE(p.next(out));
  EXPECT_EQ(p.buffered(), f.size - 1);
  p.clear();
  EXPECT_EQ(p.buffered(), 0u);
  EXPECT_EQ(p.stats().bytes_dropped, f.size - 1);
  p.push({f.data.data(), f.size});
  EXPECT_TRUE(p.next(out));
  EXPECT_EQ(out.msgid, Odometry::kId);
  expect_accounted(p);
}

TEST(MavlinkParser, RandomBytesNeverCrashAndAreAllAccountedFor) {
  std::mt19937 rng(1);
  for (int round = 0; round < 200; ++round) {
    Bytes noise(1 + rng() % 2000);
    for (auto& b : noise) b = static_cast<uint8_t>(rng() % 7 == 0 ? kStxV2 : rng());
    Parser p;
    parse_all(p, noise, 1 + rng() % 100);
    expect_accounted(p);
  }
}

}  // namespace
}  // namespace alight::mavlink
