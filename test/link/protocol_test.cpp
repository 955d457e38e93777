// The link's protocol on byte strings: a handshake and messages both ways; then everything an
// attacker or a broken peer can send (a flipped bit anywhere, a replayed frame, a recording of an
// earlier session, another key, a reflection, every truncation, oversized lengths, garbage):
// refused with the right reason, never a crash, never a message that was not sent.

#include "link/protocol.hpp"

#include <gtest/gtest.h>

#include <random>

#include "common/operator_auth.hpp"

namespace alight::link {
namespace {

bus::BusKey key_of(uint8_t seed) {
  std::vector<uint8_t> bytes(32);
  for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<uint8_t>(seed * 31 + i * 7);
  return bus::make_bus_key(bytes);
}

Nonce nonce_of(uint8_t seed) {
  Nonce n{};
  for (size_t i = 0; i < n.size(); ++i) n[i] = static_cast<uint8_t>(seed + 13 * i);
  return n;
}

std::vector<uint8_t> bytes_of(const std::string& s) { return {s.begin(), s.end()}; }

std::vector<uint8_t> concat(std::initializer_list<std::vector<uint8_t>> parts) {
  std::vector<uint8_t> out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

std::vector<uint8_t> hello_of(const Session& s) {
  const auto h = s.hello();
  return {h.begin(), h.end()};
}

// A vehicle and a ground session that exchanged hellos and READYs; `*_stream` hold every byte
// each side sent, in order (what a recorder on the path would capture).
struct Pair {
  Session vehicle, ground;
  std::vector<uint8_t> from_vehicle, from_ground;

  Pair(const bus::BusKey& key, uint8_t vn, uint8_t gn, size_t max_frame = kDefaultMaxFrameBytes)
      : vehicle(key, Role::kVehicle, nonce_of(vn), max_frame),
        ground(key, Role::kGround, nonce_of(gn), max_frame) {}

  bool handshake() {
    from_vehicle = hello_of(vehicle);
    from_ground = hello_of(ground);
    std::vector<Message> none;
    if (!vehicle.feed(from_ground, none) || !ground.feed(from_vehicle, none)) return false;
    const auto vr = vehicle.take_control(), gr = ground.take_control();
    from_vehicle.insert(from_vehicle.end(), vr.begin(), vr.end());
    from_ground.insert(from_ground.end(), gr.begin(), gr.end());
    return vehicle.feed(gr, none) && ground.feed(vr, none) && none.empty() && vehicle.open() &&
           ground.open();
  }
  std::vector<uint8_t> ground_sends(const std::string& channel, const std::vector<uint8_t>& p) {
    auto f = ground.seal_data(channel, p);
    from_ground.insert(from_ground.end(), f.begin(), f.end());
    return f;
  }
};

TEST(LinkProtocol, HelloRoundTripsAndRefusesWhatIsNotOne) {
  const Hello h{Role::kGround, 42, nonce_of(3)};
  const auto b = encode_hello(h);
  Failure why = Failure::kNone;
  const auto back = parse_hello(b, &why);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->role, Role::kGround);
  EXPECT_EQ(back->key_id, 42);
  EXPECT_EQ(back->nonce, h.nonce);
  auto bad = b;
  bad[0] = 'X';  // magic
  EXPECT_FALSE(parse_hello(bad, &why));
  EXPECT_EQ(why, Failure::kBadHello);
  bad = b;
  bad[4] = 3;  // role
  EXPECT_FALSE(parse_hello(bad, &why));
  bad = b;
  bad[5] = 0;  // key id 0 means no key
  EXPECT_FALSE(parse_hello(bad, &why));
  bad = b;
  bad[7] = 1;  // reserved
  EXPECT_FALSE(parse_hello(bad, &why));
  EXPECT_FALSE(parse_hello(std::span<const uint8_t>(b.data(), b.size() - 1), &why));
}

// The session key and the tags are HMAC-SHA256 as common/operator_auth.hpp computes it (RFC 4231
// vectors tested there), over the bytes the header comment of link/protocol.hpp lists.
TEST(LinkProtocol, SessionKeyAndTagAreHmacSha256OverTheDocumentedBytes) {
  const auto key = key_of(1);
  const Nonce v = nonce_of(10), g = nonce_of(20);
  const SessionKey sk = derive_session_key(key, v, g);
  std::vector<uint8_t> input = bytes_of("alight-link session");
  input.insert(input.end(), v.begin(), v.end());
  input.insert(input.end(), g.begin(), g.end());
  const HmacTag expected = hmac_sha256(key.bytes, input);
  EXPECT_TRUE(std::equal(sk.begin(), sk.end(), expected.begin()));
  EXPECT_NE(derive_session_key(key, g, v), sk) << "the roles' nonces are not interchangeable";

  const std::vector<uint8_t> payload = {1, 2, 3, 4, 5};
  const auto f = seal_frame(sk, FrameType::kData, Role::kVehicle, 7, "POSE", payload);
  const std::vector<uint8_t> head = {0,   0,   0,   static_cast<uint8_t>(kFrameOverhead + 4 + 5),
                                     2,   1,   0,   0,
                                     0,   0,   0,   0,
                                     0,   7,   4,   'P',
                                     'O', 'S', 'E', 1,
                                     2,   3,   4,   5};
  ASSERT_EQ(f.size(), head.size() + kTagBytes);
  EXPECT_TRUE(std::equal(head.begin(), head.end(), f.begin()));
  const HmacTag tag = hmac_sha256(std::vector<uint8_t>(sk.begin(), sk.end()), head);
  EXPECT_TRUE(std::equal(f.begin() + head.size(), f.end(), tag.begin()));
}

TEST(LinkProtocol, MessagesCrossBothWaysAfterTheHandshake) {
  Pair p(key_of(1), 1, 2);
  ASSERT_TRUE(p.handshake());
  std::vector<Message> got;
  const std::vector<uint8_t> cmd = {9, 8, 7};
  ASSERT_TRUE(p.vehicle.feed(p.ground.seal_data("OPERATOR_CMD", cmd), got));
  ASSERT_TRUE(p.vehicle.feed(p.ground.seal_keepalive(), got));
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].channel, "OPERATOR_CMD");
  EXPECT_EQ(got[0].payload, cmd);
  got.clear();
  std::vector<uint8_t> image(300'000);
  for (size_t i = 0; i < image.size(); ++i) image[i] = static_cast<uint8_t>(i * 7);
  const auto frame = p.vehicle.seal_data("CAMERA", image);
  const auto status = p.vehicle.seal_data("AUTONOMY_STATUS", {});
  // In pieces of every size the socket may hand over.
  const auto stream = concat({frame, status});
  for (size_t at = 0, step = 1; at < stream.size(); at += step, step = step * 3 % 70001 + 1)
    ASSERT_TRUE(p.ground.feed(
        std::span<const uint8_t>(stream).subspan(at, std::min(step, stream.size() - at)), got));
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].channel, "CAMERA");
  EXPECT_EQ(got[0].payload, image);
  EXPECT_EQ(got[1].channel, "AUTONOMY_STATUS");
  EXPECT_TRUE(got[1].payload.empty());
  EXPECT_EQ(p.vehicle.stats().data_sent, 2u);
  EXPECT_EQ(p.ground.stats().data_received, 2u);
  EXPECT_EQ(p.ground.stats().frames_received, 3u);   // READY and two messages
  EXPECT_EQ(p.vehicle.stats().frames_received, 3u);  // READY, a message, a keepalive
}

TEST(LinkProtocol, NothingIsSentOrTakenBeforeThePeersReady) {
  Session v(key_of(1), Role::kVehicle, nonce_of(1));
  Session g(key_of(1), Role::kGround, nonce_of(2));
  std::vector<Message> got;
  EXPECT_TRUE(v.take_control().empty()) << "no READY before the peer's hello";
  ASSERT_TRUE(v.feed(hello_of(g), got));
  EXPECT_FALSE(v.open());
  EXPECT_FALSE(v.take_control().empty());
  EXPECT_FALSE(v.open()) << "our READY sent is not the peer's verified";
  // A DATA frame, correctly tagged, in place of the READY.
  ASSERT_TRUE(g.feed(hello_of(v), got));
  const SessionKey sk = derive_session_key(key_of(1), nonce_of(1), nonce_of(2));
  const auto data = seal_frame(sk, FrameType::kData, Role::kGround, 0, "OPERATOR_CMD", {{1, 2}});
  EXPECT_FALSE(v.feed(data, got));
  EXPECT_TRUE(got.empty());
  EXPECT_TRUE(v.failed());
  // Its length alone gives it away: before READY nothing longer than a READY is buffered.
  EXPECT_EQ(v.failure(), Failure::kOversized);
  Session v2(key_of(1), Role::kVehicle, nonce_of(1));
  ASSERT_TRUE(v2.feed(hello_of(g), got));
  const auto keepalive = seal_frame(sk, FrameType::kKeepalive, Role::kGround, 0, "", {});
  EXPECT_FALSE(v2.feed(keepalive, got));
  EXPECT_EQ(v2.failure(), Failure::kOutOfOrder);
}

TEST(LinkProtocol, EveryFlippedBitOfAFrameIsRefused) {
  Pair p(key_of(1), 1, 2);
  ASSERT_TRUE(p.handshake());
  const auto frame = p.ground.seal_data("OPERATOR_CMD", {{1, 2, 3, 4, 5, 6, 7, 8}});
  for (size_t byte = 0; byte < frame.size(); ++byte) {
    for (int bit = 0; bit < 8; ++bit) {
      Session receiver = p.vehicle;  // the open session, as it was before the frame
      auto bad = frame;
      bad[byte] ^= static_cast<uint8_t>(1 << bit);
      std::vector<Message> got;
      // A flipped length may leave the frame incomplete: the rest never comes, nothing is taken.
      const bool ok = receiver.feed(bad, got);
      EXPECT_TRUE(got.empty()) << byte << "." << bit;
      if (ok) {
        EXPECT_LT(byte, 4u) << "only a longer length can wait for more";
      } else {
        EXPECT_TRUE(receiver.failure() == Failure::kBadTag ||
                    receiver.failure() == Failure::kOversized ||
                    receiver.failure() == Failure::kMalformed)
            << byte << "." << bit << ": " << failure_name(receiver.failure());
      }
    }
  }
}

TEST(LinkProtocol, AReplayedOrDroppedFrameEndsTheSession) {
  Pair p(key_of(1), 1, 2);
  ASSERT_TRUE(p.handshake());
  const auto a = p.ground.seal_data("OPERATOR_CMD", {{1}});
  const auto b = p.ground.seal_data("OPERATOR_CMD", {{2}});
  const auto c = p.ground.seal_data("OPERATOR_CMD", {{3}});
  std::vector<Message> got;
  Session replay = p.vehicle;
  ASSERT_TRUE(replay.feed(a, got));
  EXPECT_FALSE(replay.feed(a, got));
  EXPECT_EQ(replay.failure(), Failure::kBadCounter);
  EXPECT_TRUE(is_auth_failure(replay.failure()));
  EXPECT_EQ(got.size(), 1u);
  Session dropped = p.vehicle;
  got.clear();
  ASSERT_TRUE(dropped.feed(a, got));
  EXPECT_FALSE(dropped.feed(c, got)) << "b went missing on the way";
  EXPECT_EQ(dropped.failure(), Failure::kBadCounter);
  Session reordered = p.vehicle;
  EXPECT_FALSE(reordered.feed(b, got));
  EXPECT_FALSE(reordered.feed(concat({a, b}), got)) << "a failed session takes nothing more";
}

TEST(LinkProtocol, ARecordingOfAnEarlierSessionDoesNotVerifyInANewOne) {
  const auto key = key_of(1);
  Pair earlier(key, 1, 2);
  ASSERT_TRUE(earlier.handshake());
  earlier.ground_sends("OPERATOR_CMD", {{1, 2, 3}});
  // The whole capture of the ground's side, played to a vehicle that draws a new nonce.
  Session vehicle(key, Role::kVehicle, nonce_of(77));
  std::vector<Message> got;
  EXPECT_FALSE(vehicle.feed(earlier.from_ground, got));
  EXPECT_EQ(vehicle.failure(), Failure::kBadTag);
  EXPECT_TRUE(got.empty());
  EXPECT_FALSE(vehicle.open());
  // And a frame of the earlier session injected into a genuine later one.
  Pair later(key, 3, 4);
  ASSERT_TRUE(later.handshake());
  const auto old_frame = earlier.ground.seal_data("OPERATOR_CMD", {{4}});
  EXPECT_FALSE(later.vehicle.feed(old_frame, got));
  EXPECT_EQ(later.vehicle.failure(), Failure::kBadTag);
  EXPECT_TRUE(got.empty());
  // The vehicle's side played back to a ground link fares no better.
  Session ground(key, Role::kGround, nonce_of(99));
  EXPECT_FALSE(ground.feed(earlier.from_vehicle, got));
  EXPECT_EQ(ground.failure(), Failure::kBadTag);
}

TEST(LinkProtocol, AnotherKeyIsRefusedAtTheHelloOrAtTheReady) {
  Pair p(key_of(1), 1, 2);
  Session stranger(key_of(2), Role::kGround, nonce_of(5));
  ASSERT_NE(key_of(1).id, key_of(2).id);
  std::vector<Message> got;
  EXPECT_FALSE(p.vehicle.feed(hello_of(stranger), got));
  EXPECT_EQ(p.vehicle.failure(), Failure::kOtherKey);
  EXPECT_TRUE(is_auth_failure(p.vehicle.failure()));
  // A key that happens to share the id (1 in 255) gets as far as its READY.
  bus::BusKey same_id = key_of(3);
  same_id.id = key_of(1).id;
  Session forger(same_id, Role::kGround, nonce_of(6));
  Session vehicle(key_of(1), Role::kVehicle, nonce_of(7));
  ASSERT_TRUE(vehicle.feed(hello_of(forger), got));
  ASSERT_TRUE(forger.feed(hello_of(vehicle), got));
  EXPECT_FALSE(vehicle.feed(forger.take_control(), got));
  EXPECT_EQ(vehicle.failure(), Failure::kBadTag);
  EXPECT_FALSE(vehicle.open());
}

TEST(LinkProtocol, ReflectionsSameRolesAndEchoedNoncesAreRefused) {
  Pair p(key_of(1), 1, 2);
  ASSERT_TRUE(p.handshake());
  std::vector<Message> got;
  Session vehicle = p.vehicle;
  EXPECT_FALSE(vehicle.feed(p.vehicle.seal_data("CAMERA", {{1}}), got));
  EXPECT_EQ(vehicle.failure(), Failure::kReflected);
  Session v1(key_of(1), Role::kVehicle, nonce_of(1)), v2(key_of(1), Role::kVehicle, nonce_of(2));
  EXPECT_FALSE(v1.feed(hello_of(v2), got));
  EXPECT_EQ(v1.failure(), Failure::kSameRole);
  Session v3(key_of(1), Role::kVehicle, nonce_of(1));
  const auto echoed = encode_hello(Hello{Role::kGround, key_of(1).id, nonce_of(1)});
  EXPECT_FALSE(v3.feed(echoed, got));
  EXPECT_EQ(v3.failure(), Failure::kSameNonce);
  EXPECT_TRUE(got.empty());
}

TEST(LinkProtocol, EveryTruncationOfAStreamTakesOnlyWhatCameWhole) {
  Pair p(key_of(1), 1, 2);
  ASSERT_TRUE(p.handshake());
  p.ground_sends("OPERATOR_CMD", {{1, 2, 3}});
  const size_t first_end = p.from_ground.size();
  p.ground_sends("NODE_STATUS", std::vector<uint8_t>(100, 5));
  const auto stream = p.from_ground;
  for (size_t cut = 0; cut <= stream.size(); ++cut) {
    Session v(key_of(1), Role::kVehicle, nonce_of(1));
    std::vector<Message> got;
    ASSERT_TRUE(v.feed(std::span<const uint8_t>(stream.data(), cut), got)) << cut;
    const size_t expected = cut == stream.size() ? 2 : cut >= first_end ? 1 : 0;
    EXPECT_EQ(got.size(), expected) << cut;
    EXPECT_EQ(v.open(), cut >= kHelloBytes + 4 + kControlFrameLength) << cut;
  }
}

TEST(LinkProtocol, LengthsBeyondTheBoundAreRefusedBeforeTheyAreBuffered) {
  Pair p(key_of(1), 1, 2, kMinMaxFrameBytes);
  ASSERT_TRUE(p.handshake());
  std::vector<Message> got;
  Session v = p.vehicle;
  const uint32_t huge = 0xffffffffu;
  const std::vector<uint8_t> length = {static_cast<uint8_t>(huge >> 24),
                                       static_cast<uint8_t>(huge >> 16),
                                       static_cast<uint8_t>(huge >> 8), static_cast<uint8_t>(huge)};
  EXPECT_FALSE(v.feed(length, got));
  EXPECT_EQ(v.failure(), Failure::kOversized);
  EXPECT_FALSE(is_auth_failure(v.failure()));
  // One byte over the bound, and the largest frame that fits.
  EXPECT_TRUE(p.ground.fits("CAMERA", kMinMaxFrameBytes - kFrameOverhead - 6));
  EXPECT_FALSE(p.ground.fits("CAMERA", kMinMaxFrameBytes - kFrameOverhead - 5));
  Session v2 = p.vehicle;
  const auto largest =
      p.ground.seal_data("CAMERA", std::vector<uint8_t>(kMinMaxFrameBytes - kFrameOverhead - 6));
  EXPECT_TRUE(v2.feed(largest, got));
  EXPECT_EQ(got.size(), 1u);
  const SessionKey sk = derive_session_key(key_of(1), nonce_of(1), nonce_of(2));
  const auto over = seal_frame(sk, FrameType::kData, Role::kGround, 2, "CAMERA",
                               std::vector<uint8_t>(kMinMaxFrameBytes - kFrameOverhead - 5));
  EXPECT_FALSE(v2.feed(over, got));
  EXPECT_EQ(v2.failure(), Failure::kOversized);
  // Shorter than any frame.
  Session v3 = p.vehicle;
  EXPECT_FALSE(v3.feed(std::vector<uint8_t>{0, 0, 0, 5}, got));
  EXPECT_EQ(v3.failure(), Failure::kMalformed);
}

// Frames an authenticated but broken peer could send (correct tags, wrong structure).
TEST(LinkProtocol, MalformedFramesWithGoodTagsAreRefused) {
  Pair p(key_of(1), 1, 2);
  ASSERT_TRUE(p.handshake());
  const SessionKey sk = derive_session_key(key_of(1), nonce_of(1), nonce_of(2));
  const auto refused = [&](std::vector<uint8_t> frame, Failure expected, const char* what) {
    Session v = p.vehicle;
    std::vector<Message> got;
    EXPECT_FALSE(v.feed(frame, got)) << what;
    EXPECT_EQ(v.failure(), expected) << what << ": " << failure_name(v.failure());
    EXPECT_TRUE(got.empty()) << what;
  };
  // The tag recomputed after an edit, as only a key holder could.
  const auto retag = [&](std::vector<uint8_t> f) {
    const std::vector<uint8_t> covered(f.begin(), f.end() - kTagBytes);
    const HmacTag t = hmac_sha256(std::vector<uint8_t>(sk.begin(), sk.end()), covered);
    std::copy(t.begin(), t.begin() + kTagBytes, f.end() - kTagBytes);
    return f;
  };
  auto f = seal_frame(sk, FrameType::kData, Role::kGround, 1, "CAMERA", {{1, 2}});
  f[14] = 200;  // channel length beyond the frame
  refused(retag(f), Failure::kMalformed, "channel length");
  refused(seal_frame(sk, FrameType::kData, Role::kGround, 1, "A B", {{1}}), Failure::kMalformed,
          "a space in the channel");
  refused(seal_frame(sk, FrameType::kData, Role::kGround, 1, "", {{1}}), Failure::kMalformed,
          "no channel");
  f = seal_frame(sk, FrameType::kKeepalive, Role::kGround, 1, "", {});
  f[4] = 9;
  refused(retag(f), Failure::kMalformed, "type 9");
  f[4] = static_cast<uint8_t>(FrameType::kReady);
  refused(retag(f), Failure::kOutOfOrder, "a second READY");
  f[4] = static_cast<uint8_t>(FrameType::kKeepalive);
  f[5] = 7;
  refused(retag(f), Failure::kMalformed, "direction 7");
}

TEST(LinkProtocol, GarbageNeverCrashesAndNeverYieldsAMessage) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<uint8_t> junk(1 + rng() % 2000);
    for (auto& b : junk) b = static_cast<uint8_t>(rng());
    if (trial % 3 == 0) {  // a valid hello first, so the garbage reaches the frame reader
      const auto h = encode_hello(Hello{Role::kGround, key_of(1).id, nonce_of(2)});
      junk.insert(junk.begin(), h.begin(), h.end());
    }
    Session v(key_of(1), Role::kVehicle, nonce_of(1));
    std::vector<Message> got;
    v.feed(junk, got);
    EXPECT_TRUE(got.empty());
    EXPECT_FALSE(v.open());
  }
}

}  // namespace
}  // namespace alight::link
