// decode_message(): untrusted bytes never throw, never allocate what the buffer cannot hold.
#include "common/decode.hpp"

#include <gtest/gtest.h>

#include <alight/autonomy_status_t.hpp>
#include <alight/operator_cmd_t.hpp>
#include <alight/pose_t.hpp>
#include <cstring>
#include <vector>

namespace alight {
namespace {

template <class Msg>
std::vector<uint8_t> encode(const Msg& m) {
  std::vector<uint8_t> buf(m.getEncodedSize());
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  return buf;
}

void put_int32(std::vector<uint8_t>& buf, size_t at, int32_t v) {
  const auto u = static_cast<uint32_t>(v);
  for (int i = 0; i < 4; ++i) buf[at + i] = static_cast<uint8_t>(u >> (24 - 8 * i));
}

TEST(DecodeTest, RoundTripsAWellFormedMessage) {
  pose_t p{};
  p.utime = 42;
  p.pos[2] = 1.5;
  const auto buf = encode(p);
  pose_t out{};
  ASSERT_TRUE(decode_message(out, buf.data(), buf.size()));
  EXPECT_EQ(out.utime, 42);
  EXPECT_EQ(out.pos[2], 1.5);
}

TEST(DecodeTest, RefusesTruncatedAndTrailingBytes) {
  pose_t p{};
  auto buf = encode(p);
  pose_t out{};
  EXPECT_FALSE(decode_message(out, buf.data(), buf.size() - 1));
  buf.push_back(0);
  EXPECT_FALSE(decode_message(out, buf.data(), buf.size()));
  EXPECT_FALSE(decode_message(out, nullptr, 0));
}

// Regression (issue 14): a 28-byte OPERATOR_CMD whose sender string has length 0 made lcm-gen's
// decoder throw std::length_error out of Node::decode, and alight-autonomy exited.
TEST(DecodeTest, OperatorCmdWithZeroStringLengthIsAnErrorNotAThrow) {
  operator_cmd_t c{};
  c.sender = "gs";
  auto buf = encode(c);
  put_int32(buf, 8 + 8 + 8, 0);  // fingerprint, utime, seq, then the sender's length
  buf.resize(28);
  operator_cmd_t out{};
  EXPECT_FALSE(decode_message(out, buf.data(), buf.size()));
}

TEST(DecodeTest, StatusWithNegativeStringLengthIsAnError) {
  autonomy_status_t s{};
  s.phase_name = "HOVER";
  auto buf = encode(s);
  put_int32(buf, 8 + 8 + 1 + 1, -7);
  autonomy_status_t out{};
  EXPECT_FALSE(decode_message(out, buf.data(), buf.size()));
}

// Regression (issue 14): image_t with size -1 threw out of the decoder (vision, ground station).
TEST(DecodeTest, ImageWithNegativeSizeIsAnError) {
  image_t m{};
  m.width = 2;
  m.height = 1;
  m.size = 2;
  m.data = {1, 2};
  auto buf = encode(m);
  put_int32(buf, 8 + 8 + 16, -1);
  image_t out{};
  EXPECT_FALSE(decode_message(out, buf.data(), buf.size()));
}

// A 40-byte image claiming 2 GiB of data is refused before anything is allocated.
TEST(DecodeTest, ImageClaimingMoreDataThanTheBufferIsRefusedUpFront) {
  image_t m{};
  auto buf = encode(m);
  put_int32(buf, 8 + 8 + 16, 0x7fffffff);
  EXPECT_FALSE(wire::precheck<image_t>(buf.data(), buf.size()));
  image_t out{};
  EXPECT_FALSE(decode_message(out, buf.data(), buf.size()));
}

TEST(DecodeTest, ImageMetadataCountsAreWalked) {
  image_t m{};
  m.size = 3;
  m.data = {1, 2, 3};
  image_metadata_t e{};
  e.key = "seq";
  e.n = 2;
  e.value = {7, 8};
  m.metadata = {e};
  m.nmetadata = 1;
  auto buf = encode(m);
  EXPECT_TRUE(wire::precheck<image_t>(buf.data(), buf.size()));
  image_t out{};
  ASSERT_TRUE(decode_message(out, buf.data(), buf.size()));
  EXPECT_EQ(out.metadata.at(0).value.at(1), 8);
  // The entry's value length, after fingerprint + 6 fields, data, nmetadata, key (4 + 4 bytes).
  put_int32(buf, 8 + 8 + 20 + 3 + 4 + 8, 0x40000000);
  EXPECT_FALSE(wire::precheck<image_t>(buf.data(), buf.size()));
  EXPECT_FALSE(decode_message(out, buf.data(), buf.size()));
}

TEST(DecodeTest, ProcessStatusCountBoundedByTheBuffer) {
  process_status_t s{};
  s.launch_name = "l";
  s.session_dir = "d";
  auto buf = encode(s);
  put_int32(buf, buf.size() - 4, 100000000);
  process_status_t out{};
  EXPECT_FALSE(wire::precheck<process_status_t>(buf.data(), buf.size()));
  EXPECT_FALSE(decode_message(out, buf.data(), buf.size()));
}

// Property: every prefix and every single-byte corruption of a valid image either decodes or is
// refused; none throws or crashes.
TEST(DecodeTest, CorruptionsOfAnImageNeverThrow) {
  image_t m{};
  m.width = 4;
  m.height = 2;
  m.row_stride = 4;
  m.size = 8;
  m.data.assign(8, 9);
  image_metadata_t e{};
  e.key = "k";
  e.n = 1;
  e.value = {1};
  m.metadata = {e};
  m.nmetadata = 1;
  const auto good = encode(m);
  image_t out{};
  for (size_t n = 0; n <= good.size(); ++n)
    EXPECT_EQ(decode_message(out, good.data(), n), n == good.size()) << n;
  for (size_t i = 8; i < good.size(); ++i) {
    for (const uint8_t v : {uint8_t{0x00}, uint8_t{0x7f}, uint8_t{0x80}, uint8_t{0xff}}) {
      auto bad = good;
      bad[i] = v;
      (void)decode_message(out, bad.data(), bad.size());
    }
  }
}

// Regression (issue 14, found by the fault campaign): a string length of INT32_MIN made
// lcm-gen's decoder compute len - 1 = INT32_MAX and copy 2 GiB past the buffer (segfault in
// autonomy and the ground station). lcmtypes/harden_decoders.cmake fixes the generated code.
TEST(DecodeTest, RegressionHostileStringLengthsAreRefusedInEveryStringField) {
  for (const int32_t len : {int32_t{0}, int32_t{-1}, INT32_MIN, INT32_MAX, int32_t{0x55555556}}) {
    operator_cmd_t c{};
    c.sender = "gs";
    auto buf = encode(c);
    put_int32(buf, 8 + 8 + 8, len);
    operator_cmd_t out{};
    EXPECT_FALSE(decode_message(out, buf.data(), buf.size())) << len;

    autonomy_status_t s{};
    s.phase_name = "HOVER";
    s.reason = "why";
    auto sb = encode(s);
    put_int32(sb, 8 + 8 + 1 + 1 + 4 + 6, len);  // the reason's length, after "HOVER\0"
    autonomy_status_t sout{};
    EXPECT_FALSE(decode_message(sout, sb.data(), sb.size())) << len;
  }
}

TEST(DecodeTest, RegressionArrayCountsBeyondTheBufferAreRefusedByTheGeneratedCode) {
  image_t m{};
  auto buf = encode(m);
  for (const int32_t n : {int32_t{-1}, INT32_MIN, int32_t{1000}}) {
    put_int32(buf, 8 + 8 + 16, n);
    image_t out{};
    // Straight into the generated decoder, without decode_message's walk.
    EXPECT_LT(out.decode(buf.data(), 0, static_cast<int>(buf.size())), 0) << n;
  }
}

}  // namespace
}  // namespace alight
