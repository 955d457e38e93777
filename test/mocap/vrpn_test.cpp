// The VRPN stream decoder on bytes framed by the test server's own encoder (written separately
// from the protocol description): cookie, descriptions, Pos_Quat, chunking at every byte, and
// every refusal counted without losing the stream.

#include "mocap/vrpn.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "tools/vrpn_test_server.hpp"

namespace alight::mocap::vrpn {
namespace {

using tools::ServedPose;
using tools::VrpnTestServer;

std::vector<uint8_t> cookie_bytes(const std::string& text) {
  std::vector<uint8_t> c(kCookieBytes, 0);
  std::memcpy(c.data(), text.data(), std::min(text.size(), c.size()));
  return c;
}

void append(std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  a.insert(a.end(), b.begin(), b.end());
}

std::vector<uint8_t> description(const std::string& name) {
  std::vector<uint8_t> p;
  put_u32(p, static_cast<uint32_t>(name.size() + 1));
  p.insert(p.end(), name.begin(), name.end());
  p.push_back(0);
  return p;
}

// A server's opening: cookie, sender 7 = "Pelican", sender 8 = "Other", type 11 = Pos_Quat,
// type 12 = Velocity, type 3 = a type the client has no use for.
std::vector<uint8_t> opening() {
  auto s = cookie_bytes("vrpn: ver. 07.35  0");
  append(s, VrpnTestServer::frame(-1, 7, 1, description("Pelican")));
  append(s, VrpnTestServer::frame(-1, 8, 1, description("Other")));
  append(s, VrpnTestServer::frame(-2, 11, 1, description("vrpn_Tracker Pos_Quat")));
  append(s, VrpnTestServer::frame(-2, 12, 1, description("vrpn_Tracker Velocity")));
  append(s, VrpnTestServer::frame(-2, 3, 1, description("VRPN_Connection_Got_Connection")));
  return s;
}

ServedPose pose(int64_t stamp_us, double x) {
  ServedPose p;
  p.object = "Pelican";
  p.stamp_us = stamp_us;
  p.pos[0] = x, p.pos[1] = -2.5, p.pos[2] = 1e3;
  p.quat_xyzw[0] = 0.5, p.quat_xyzw[1] = -0.5, p.quat_xyzw[2] = 0.5, p.quat_xyzw[3] = 0.5;
  return p;
}

std::vector<uint8_t> pose_frame(int32_t sender, const ServedPose& p) {
  return VrpnTestServer::frame(11, sender, p.stamp_us, VrpnTestServer::pose_payload(p));
}

TEST(VrpnCookieTest, OursIsTheMagicTwoSpacesAndTheLogModeAndPassesItsOwnCheck) {
  const auto c = make_cookie(0);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(c.data())), "vrpn: ver. 07.35  0");
  for (size_t i = 19; i < kCookieBytes; ++i) EXPECT_EQ(c[i], 0);
  EXPECT_EQ(check_cookie(c.data()).verdict, CookieVerdict::kOk);
}

TEST(VrpnCookieTest, MinorVersionMayDifferMajorMayNot) {
  auto c = cookie_bytes("vrpn: ver. 07.38  0");
  auto r = check_cookie(c.data());
  EXPECT_EQ(r.verdict, CookieVerdict::kMinorDiffers);
  EXPECT_TRUE(r.usable());
  EXPECT_EQ(r.version, "07.38");
  c = cookie_bytes("vrpn: ver. 06.35  0");
  EXPECT_EQ(check_cookie(c.data()).verdict, CookieVerdict::kBadMagic);
  c = cookie_bytes("HTTP/1.1 400 Bad Request\r\n");
  EXPECT_FALSE(check_cookie(c.data()).usable());
  c = cookie_bytes("vrpn: ver. 07.35  7");
  EXPECT_EQ(check_cookie(c.data()).verdict, CookieVerdict::kBadLogMode);
  c = cookie_bytes("vrpn: ver. 07.35  2");
  EXPECT_EQ(check_cookie(c.data()).log_mode, 2);
}

TEST(VrpnFramingTest, LengthHoldsTheUnpaddedPayloadAndTheFrameIsPaddedToEight) {
  std::vector<uint8_t> out;
  const uint8_t payload[5] = {1, 2, 3, 4, 5};
  append_message(out, -2, 9, 100, 200, payload, sizeof payload, 77);
  ASSERT_EQ(out.size(), 24u + 8u);
  EXPECT_EQ(get_u32(out.data()), 29u);
  EXPECT_EQ(get_u32(out.data() + 4), 100u);
  EXPECT_EQ(get_u32(out.data() + 8), 200u);
  EXPECT_EQ(get_u32(out.data() + 12), 9u);
  EXPECT_EQ(static_cast<int32_t>(get_u32(out.data() + 16)), -2);
  EXPECT_EQ(get_u32(out.data() + 20), 77u);
  EXPECT_EQ(out[28], 5);
  EXPECT_EQ(out[29], 0);
  EXPECT_EQ(out[31], 0);
  // The test server's independent encoder frames the same bytes (sequence word 0).
  std::vector<uint8_t> ours;
  append_message(ours, -2, 9, 1, 500000, payload, sizeof payload);
  EXPECT_EQ(ours, VrpnTestServer::frame(-2, 9, 1'500'000, {1, 2, 3, 4, 5}));
}

TEST(VrpnDecoderTest, DecodesPosQuatOfADescribedSenderWithTheServersIds) {
  auto s = opening();
  append(s, pose_frame(7, pose(1'700'000'000'123'456, 1.25)));
  StreamDecoder d;
  std::vector<TrackerReport> out;
  ASSERT_TRUE(d.feed(s.data(), s.size(), out));
  ASSERT_EQ(out.size(), 1u);
  const auto& r = out[0];
  EXPECT_EQ(r.kind, TrackerReport::Kind::kPose);
  EXPECT_EQ(r.tracker, "Pelican");
  EXPECT_EQ(r.sensor, 0);
  EXPECT_EQ(r.stamp_us, 1'700'000'000'123'456);
  EXPECT_EQ(r.v[0], 1.25);
  EXPECT_EQ(r.v[1], -2.5);
  EXPECT_EQ(r.v[2], 1e3);
  EXPECT_EQ(r.q_xyzw[0], 0.5);
  EXPECT_EQ(r.q_xyzw[1], -0.5);
  EXPECT_EQ(r.q_xyzw[3], 0.5);
  EXPECT_EQ(d.sender_name(7), "Pelican");
  EXPECT_EQ(d.type_name(11), "vrpn_Tracker Pos_Quat");
  EXPECT_EQ(d.stats().sender_descriptions, 2u);
  EXPECT_EQ(d.stats().type_descriptions, 3u);
  EXPECT_EQ(d.stats().poses, 1u);
  EXPECT_EQ(d.pending_bytes(), 0u);
}

TEST(VrpnDecoderTest, AnyChunkingGivesTheSameReports) {
  auto s = opening();
  for (int i = 0; i < 20; ++i) append(s, pose_frame(i % 2 ? 8 : 7, pose(1'000'000 + i, i)));
  StreamDecoder whole;
  std::vector<TrackerReport> expected;
  ASSERT_TRUE(whole.feed(s.data(), s.size(), expected));
  ASSERT_EQ(expected.size(), 20u);
  std::mt19937 rng(4);
  for (int trial = 0; trial < 50; ++trial) {
    StreamDecoder d;
    std::vector<TrackerReport> got;
    size_t at = 0;
    while (at < s.size()) {
      const size_t n = std::min(s.size() - at, size_t{1} + rng() % (trial < 5 ? 1 : 100));
      ASSERT_TRUE(d.feed(s.data() + at, n, got));
      at += n;
    }
    ASSERT_EQ(got.size(), expected.size());
    for (size_t i = 0; i < got.size(); ++i) {
      EXPECT_EQ(got[i].tracker, expected[i].tracker);
      EXPECT_EQ(got[i].stamp_us, expected[i].stamp_us);
      EXPECT_EQ(got[i].v, expected[i].v);
    }
  }
}

TEST(VrpnDecoderTest, RefusalsAreCountedAndTheStreamGoesOn) {
  auto s = opening();
  const auto good = pose(5'000'000, 1);
  append(s, pose_frame(99, good));  // undescribed sender
  append(s,
         VrpnTestServer::frame(40, 7, 1, VrpnTestServer::pose_payload(good)));  // undescribed type
  auto short_payload = VrpnTestServer::pose_payload(good);
  short_payload.resize(60);
  append(s, VrpnTestServer::frame(11, 7, 1, short_payload));  // wrong size
  append(s, VrpnTestServer::frame(11, 7, 1, {}));             // empty payload
  auto bad_usec = pose_frame(7, good);
  bad_usec[8] = 0x7f;  // usec >= 1e6
  append(s, bad_usec);
  // Descriptions: id out of range, length beyond the payload, no NUL, over 100 bytes, empty.
  append(s, VrpnTestServer::frame(-1, kMaxIds, 1, description("Far")));
  append(s, VrpnTestServer::frame(-1, -4, 1, description("Negative")));
  auto lying = description("Liar");
  lying[3] = 60;
  append(s, VrpnTestServer::frame(-1, 20, 1, lying));
  auto no_nul = description("Open");
  no_nul.back() = 'x';
  append(s, VrpnTestServer::frame(-1, 21, 1, no_nul));
  append(s, VrpnTestServer::frame(-1, 22, 1, description(std::string(100, 'n'))));
  append(s, VrpnTestServer::frame(-2, 23, 1, description("")));
  append(s, VrpnTestServer::frame(-2, 24, 1, {0, 0}));
  // System messages a TCP-only client ignores: UDP and log descriptions, disconnect, unknown.
  append(s, VrpnTestServer::frame(-3, 4000, 1, description("127.0.0.1")));
  append(s, VrpnTestServer::frame(-4, 0, 1, {0, 0, 0, 0, 0, 0, 0, 0, 0, 0}));
  append(s, VrpnTestServer::frame(-5, 0, 1, {}));
  append(s, VrpnTestServer::frame(-77, 0, 1, {}));
  append(s, VrpnTestServer::frame(3, 7, 1, {1, 2, 3}));  // described, not a tracker type
  append(s, pose_frame(7, good));                        // and still a pose at the end
  StreamDecoder d;
  std::vector<TrackerReport> out;
  ASSERT_TRUE(d.feed(s.data(), s.size(), out));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].stamp_us, 5'000'000);
  const auto& st = d.stats();
  EXPECT_EQ(st.undescribed, 2u);
  EXPECT_EQ(st.bad_payloads, 2u);
  EXPECT_EQ(st.bad_stamps, 1u);
  EXPECT_EQ(st.bad_descriptions, 7u);
  EXPECT_EQ(st.system_ignored, 4u);
  EXPECT_EQ(st.other_messages, 1u);
  EXPECT_EQ(st.refused(), 12u);
  EXPECT_FALSE(d.failed());
  EXPECT_EQ(d.sender_name(20), "");
}

TEST(VrpnDecoderTest, ARedescribedIdTakesItsNewName) {
  auto s = opening();
  append(s, VrpnTestServer::frame(-1, 7, 1, description("Renamed")));
  append(s, pose_frame(7, pose(1, 0)));
  StreamDecoder d;
  std::vector<TrackerReport> out;
  ASSERT_TRUE(d.feed(s.data(), s.size(), out));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].tracker, "Renamed");
}

TEST(VrpnDecoderTest, ImpossibleLengthsEndTheStream) {
  for (uint32_t length : {0u, 23u, uint32_t(24 + kMaxPayloadBytes + 1), 0xffffffffu}) {
    auto s = opening();
    std::vector<uint8_t> header;
    put_u32(header, length);
    header.resize(24, 0);
    append(s, header);
    append(s, pose_frame(7, pose(1, 0)));
    StreamDecoder d;
    std::vector<TrackerReport> out;
    EXPECT_FALSE(d.feed(s.data(), s.size(), out)) << length;
    EXPECT_TRUE(d.failed());
    EXPECT_EQ(d.stats().framing_errors, 1u);
    EXPECT_TRUE(out.empty());
    EXPECT_NE(d.error().find("length"), std::string::npos);
    EXPECT_FALSE(d.feed(s.data(), s.size(), out));  // stays failed, reads nothing more
    EXPECT_EQ(d.stats().framing_errors, 1u);
  }
}

TEST(VrpnDecoderTest, AServerThatIsNotVrpnIsRefusedAtItsCookie) {
  const std::string http = "HTTP/1.1 200 OK\r\nContent-Length: 0\r\n\r\n";
  StreamDecoder d;
  std::vector<TrackerReport> out;
  EXPECT_FALSE(d.feed(reinterpret_cast<const uint8_t*>(http.data()), http.size(), out));
  EXPECT_EQ(d.stats().cookie_errors, 1u);
  EXPECT_NE(d.error().find("not a VRPN 07 server"), std::string::npos);
}

TEST(VrpnDecoderTest, ATruncatedMessageIsPendingNotDecoded) {
  auto s = opening();
  const auto f = pose_frame(7, pose(1, 0));
  s.insert(s.end(), f.begin(), f.begin() + 40);
  StreamDecoder d;
  std::vector<TrackerReport> out;
  ASSERT_TRUE(d.feed(s.data(), s.size(), out));
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(d.pending_bytes(), 40u);
}

TEST(VrpnDecoderTest, RandomBytesNeverCrashAndBufferStaysBounded) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 300; ++trial) {
    auto s = opening();
    // A valid start, then garbage of random length, chunked at random.
    std::vector<uint8_t> garbage(rng() % 3000);
    for (auto& b : garbage) b = static_cast<uint8_t>(rng());
    append(s, garbage);
    StreamDecoder d;
    std::vector<TrackerReport> out;
    size_t at = 0;
    while (at < s.size()) {
      const size_t n = std::min(s.size() - at, size_t{1} + rng() % 700);
      d.feed(s.data() + at, n, out);
      EXPECT_LE(d.pending_bytes(), kHeaderBytes + kMaxPayloadBytes + 8);
      at += n;
    }
  }
}

TEST(VrpnDecoderTest, VelocityAndAccelerationAreDecoded) {
  auto s = opening();
  std::vector<uint8_t> p;
  put_u32(p, 2);
  put_u32(p, 0);
  for (double v : {0.1, 0.2, 0.3, 0.0, 0.0, 0.0, 1.0, 0.01}) put_f64(p, v);
  append(s, VrpnTestServer::frame(12, 7, 9, p));
  StreamDecoder d;
  std::vector<TrackerReport> out;
  ASSERT_TRUE(d.feed(s.data(), s.size(), out));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].kind, TrackerReport::Kind::kVelocity);
  EXPECT_EQ(out[0].sensor, 2);
  EXPECT_EQ(out[0].v[2], 0.3);
  EXPECT_EQ(out[0].dt_s, 0.01);
  EXPECT_EQ(d.stats().velocities, 1u);
}

}  // namespace
}  // namespace alight::mocap::vrpn
