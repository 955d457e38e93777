// Payload layout of each message: wire order, extensions, truncation and zero-extension
// (mavlink.io/en/guide/serialization.html, "Field Reordering", "Empty-Byte Payload Truncation").

#include "mavlink/messages.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <vector>

#include "test/mavlink/sample_messages.hpp"

namespace alight::mavlink {
namespace {

using testing::distinct_message;
using testing::without_extensions;
using testing::zero_message;

template <class M>
std::vector<uint8_t> encoded(const M& m) {
  std::array<uint8_t, 255> buf{};
  const uint8_t n = encode_payload(m, buf.data());
  return {buf.begin(), buf.begin() + n};
}

template <class M>
M decoded(const std::vector<uint8_t>& payload) {
  std::array<uint8_t, 255> buf{};  // zero past the payload, as in a Frame
  std::memcpy(buf.data(), payload.data(), payload.size());
  return decode_payload<M>(buf.data());
}

TEST(MavlinkMessages, EveryMessageRoundTripsWithEveryFieldSet) {
  for_each_message_type([](auto tag) {
    using M = decltype(tag);
    SCOPED_TRACE(std::string(M::kName));
    for (uint64_t seed = 1; seed <= 20; ++seed) {
      const M m = distinct_message<M>(seed);
      const auto bytes = encoded(m);
      EXPECT_LE(bytes.size(), M::kMaxLength);
      EXPECT_EQ(decoded<M>(bytes), m);
    }
  });
}

TEST(MavlinkMessages, ZeroExtensionsAreTruncatedAndReadBackAsZero) {
  for_each_message_type([](auto tag) {
    using M = decltype(tag);
    SCOPED_TRACE(std::string(M::kName));
    const M m = without_extensions(distinct_message<M>(3));
    const auto bytes = encoded(m);
    EXPECT_LE(bytes.size(), M::kBaseLength) << "zero extensions are never sent";
    EXPECT_EQ(decoded<M>(bytes), m);
  });
}

TEST(MavlinkMessages, AnAllZeroPayloadKeepsItsFirstByte) {
  // "The first byte of the payload is never truncated, even if the payload consists entirely of
  // zeros."
  for_each_message_type([](auto tag) {
    using M = decltype(tag);
    const auto bytes = encoded(zero_message<M>());
    ASSERT_EQ(bytes.size(), 1u) << M::kName;
    EXPECT_EQ(bytes[0], 0);
    EXPECT_EQ(decoded<M>({}), zero_message<M>()) << "an empty payload decodes as all zero";
  });
}

TEST(MavlinkMessages, TrailingZerosInsideTheBaseFieldsAreTruncatedToo) {
  HighresImu m = distinct_message<HighresImu>(1);
  m.id = 0;
  m.fields_updated = 0x0100;  // low byte at offset 60, high byte 0x01 at 61
  EXPECT_EQ(encoded(m).size(), 62u);
  m.fields_updated = 0x0001;  // the high byte at offset 61 is zero: dropped
  EXPECT_EQ(encoded(m).size(), 61u);
  EXPECT_EQ(decoded<HighresImu>(encoded(m)), m);
}

TEST(MavlinkMessages, CommandAckLayoutKnownAnswer) {
  // Wire order: command (uint16) result (uint8), then the extensions as declared: progress
  // (uint8), result_param2 (int32), target_system, target_component.
  CommandAck m;
  m.command = mav_cmd::kComponentArmDisarm;  // 400 = 0x0190
  m.result = mav_result::kInProgress;
  m.progress = 42;
  m.result_param2 = -2;
  m.target_system = 255;
  m.target_component = 190;
  EXPECT_EQ(encoded(m),
            (std::vector<uint8_t>{0x90, 0x01, 5, 42, 0xFE, 0xFF, 0xFF, 0xFF, 255, 190}));
}

TEST(MavlinkMessages, HeartbeatLayoutKnownAnswer) {
  Heartbeat m;
  m.type = mav_type::kQuadrotor;
  m.autopilot = mav_autopilot::kPx4;
  m.base_mode = mav_mode_flag::kCustomModeEnabled | mav_mode_flag::kSafetyArmed;
  m.custom_mode = 0x00060000;  // PX4: main mode 6 (OFFBOARD) in byte 2
  m.system_status = mav_state::kActive;
  m.mavlink_version = 3;
  EXPECT_EQ(encoded(m), (std::vector<uint8_t>{0x00, 0x00, 0x06, 0x00, 2, 12, 0x81, 4, 3}));
}

TEST(MavlinkMessages, SetAttitudeTargetPutsTheByteFieldsBeforeTheThrustVectorExtension) {
  SetAttitudeTarget m;
  m.time_boot_ms = 0x01020304;
  m.q = {1.0f, 0.0f, 0.0f, 0.0f};
  m.thrust = 0.5f;
  m.target_system = 1;
  m.target_component = 1;
  m.type_mask = attitude_target_typemask::kThrustBodySet;
  m.thrust_body = {0.0f, 0.0f, -1.0f};
  const auto b = encoded(m);
  ASSERT_EQ(b.size(), 51u);
  EXPECT_EQ(b[0], 0x04);  // time_boot_ms, little-endian
  EXPECT_EQ(b[3], 0x01);
  float w, thrust, tz;
  std::memcpy(&w, &b[4], 4);
  std::memcpy(&thrust, &b[32], 4);
  std::memcpy(&tz, &b[47], 4);
  EXPECT_EQ(w, 1.0f);
  EXPECT_EQ(thrust, 0.5f);
  EXPECT_EQ(b[36], 1);   // target_system
  EXPECT_EQ(b[38], 32);  // type_mask
  EXPECT_EQ(tz, -1.0f);  // thrust_body[2], the last extension bytes
}

TEST(MavlinkMessages, OdometryPutsFrameIdsAfterTheCovariancesAndExtensionsLast) {
  Odometry m = zero_message<Odometry>();
  m.velocity_covariance[20] = 2.0f;
  m.frame_id = mav_frame::kLocalFrd;
  m.child_frame_id = mav_frame::kBodyFrd;
  m.quality = -1;
  const auto b = encoded(m);
  ASSERT_EQ(b.size(), 233u);
  float last_cov;
  std::memcpy(&last_cov, &b[224], 4);
  EXPECT_EQ(last_cov, 2.0f);
  EXPECT_EQ(b[228], 20);
  EXPECT_EQ(b[229], 12);
  EXPECT_EQ(b[232], 0xFF);
}

TEST(MavlinkMessages, ANewerSendersExtraBytesAreIgnored) {
  // A definition with one more extension field: the bytes past kMaxLength must not matter.
  const Timesync m = distinct_message<Timesync>(7);
  auto bytes = encoded(m);
  bytes.resize(Timesync::kMaxLength, 0);
  bytes.push_back(0x5A);
  bytes.push_back(0xA5);
  EXPECT_EQ(decoded<Timesync>(bytes), m);
}

TEST(MavlinkMessages, StatustextIsCutAtFiftyBytesAndReadUpToTheFirstNul) {
  Statustext m;
  set_statustext(m, "offboard lost");
  EXPECT_EQ(statustext_string(m), "offboard lost");
  const std::string long_text(70, 'x');
  set_statustext(m, long_text);
  EXPECT_EQ(statustext_string(m), std::string(50, 'x')) << "no NUL when the text fills 50 bytes";
  const auto b = encoded(m);
  EXPECT_EQ(b.size(), 51u);
  EXPECT_EQ(statustext_string(decoded<Statustext>(b)), std::string(50, 'x'));
}

}  // namespace
}  // namespace alight::mavlink
