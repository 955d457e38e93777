#include "tools/fault_gen.hpp"

#include <gtest/gtest.h>

#include <alight/attitude_cmd_t.hpp>
#include <alight/autonomy_status_t.hpp>
#include <alight/image_t.hpp>
#include <alight/imu_t.hpp>
#include <alight/node_status_t.hpp>
#include <alight/operator_cmd_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/position_setpoint_t.hpp>
#include <alight/process_status_t.hpp>
#include <alight/sim_truth_t.hpp>
#include <alight/target_t.hpp>
#include <cmath>
#include <cstdlib>

#include "common/channels.hpp"
#include "common/decode.hpp"

namespace alight::tools::faults {
namespace {

constexpr int64_t kNow = 1'790'000'000'000'000;

// Decodes `b` as the type named `type` with the stack's own boundary (common/decode.hpp).
bool decodes(const std::string& type, const Bytes& b) {
  const auto d = [&](auto msg) { return decode_message(msg, b.data(), b.size()); };
  if (type == "pose_t") return d(pose_t{});
  if (type == "imu_t") return d(imu_t{});
  if (type == "position_setpoint_t") return d(position_setpoint_t{});
  if (type == "attitude_cmd_t") return d(attitude_cmd_t{});
  if (type == "target_t") return d(target_t{});
  if (type == "autonomy_status_t") return d(autonomy_status_t{});
  if (type == "operator_cmd_t") return d(operator_cmd_t{});
  if (type == "process_status_t") return d(process_status_t{});
  if (type == "node_status_t") return d(node_status_t{});
  if (type == "sim_truth_t") return d(sim_truth_t{});
  if (type == "image_t") return d(image_t{});
  ADD_FAILURE() << "no such type " << type;
  return false;
}

int32_t int32_at(const Bytes& b, size_t at) {
  uint32_t u = 0;
  for (size_t i = 0; i < 4; ++i) u = (u << 8) | b.at(at + i);
  return static_cast<int32_t>(u);
}

template <class Msg>
Bytes encode(const Msg& m) {
  Bytes out(static_cast<size_t>(m.getEncodedSize()));
  m.encode(out.data(), 0, static_cast<int>(out.size()));
  return out;
}

std::vector<std::string> all_types() {
  return {"pose_t",
          "imu_t",
          "position_setpoint_t",
          "attitude_cmd_t",
          "target_t",
          "autonomy_status_t",
          "operator_cmd_t",
          "process_status_t",
          "node_status_t",
          "sim_truth_t",
          "image_t"};
}

TEST(FaultGenTest, KindsRoundTripAndChannelsHaveTypes) {
  for (Kind k : all_kinds()) EXPECT_EQ(parse_kind(to_string(k)), k);
  EXPECT_FALSE(parse_kind("bogus"));
  EXPECT_EQ(type_of_channel(channels::kMocapPose), "pose_t");
  EXPECT_EQ(type_of_channel(channels::kVisionDiag), "image_t");
  EXPECT_FALSE(type_of_channel("NO_SUCH_CHANNEL"));
  const auto chans = injectable_channels();
  EXPECT_EQ(std::count(chans.begin(), chans.end(), channels::kSimTruth), 0);  // the referee
  EXPECT_EQ(std::count(chans.begin(), chans.end(), channels::kOperatorCmd), 1);
  for (const auto& c : chans) EXPECT_TRUE(type_of_channel(c)) << c;
}

TEST(FaultGenTest, GarbageIsSeeded) {
  std::mt19937_64 a(7), b(7), c(8);
  const Bytes ga = garbage(a, 100), gb = garbage(b, 100), gc = garbage(c, 100);
  EXPECT_EQ(ga.size(), 100u);
  EXPECT_EQ(ga, gb);
  EXPECT_NE(ga, gc);
}

TEST(FaultGenTest, DefaultMessagesAreWellFormedAndStampedNow) {
  for (const auto& type : all_types()) {
    const Bytes m = default_message(type, kNow);
    EXPECT_TRUE(decodes(type, m)) << type;
    EXPECT_EQ(utime_of(m), kNow) << type;
  }
  EXPECT_TRUE(default_message("no_such_t", kNow).empty());
}

TEST(FaultGenTest, LengthOffsetsPointAtTheLengthsTheDecoderReads) {
  // Strings are encoded with their length + 1 (the NUL); arrays with their count.
  const Bytes status = default_message("autonomy_status_t", kNow);
  const auto so = length_field_offsets("autonomy_status_t", status);
  ASSERT_EQ(so.size(), 2u);
  EXPECT_EQ(int32_at(status, so[0]), 6);                                              // "HOVER"
  EXPECT_EQ(int32_at(status, so[1]), static_cast<int32_t>(sizeof "fault campaign"));  // reason
  const Bytes cmd = default_message("operator_cmd_t", kNow);
  EXPECT_EQ(length_field_offsets("operator_cmd_t", cmd), std::vector<size_t>{24});
  EXPECT_EQ(int32_at(cmd, 24), static_cast<int32_t>(sizeof "alight-inject"));
  const Bytes image = default_message("image_t", kNow);
  const auto io = length_field_offsets("image_t", image);
  ASSERT_EQ(io.size(), 4u);  // size, nmetadata, metadata[0].key, metadata[0].n
  EXPECT_EQ(int32_at(image, io[0]), 32);
  EXPECT_EQ(int32_at(image, io[1]), 1);
  EXPECT_EQ(int32_at(image, io[2]), 4);  // "seq"
  EXPECT_EQ(int32_at(image, io[3]), 8);
  const Bytes ps = default_message("process_status_t", kNow);
  const auto po = length_field_offsets("process_status_t", ps);
  ASSERT_EQ(po.size(), 4u);  // launch_name, session_dir, n, processes[0].name
  EXPECT_EQ(int32_at(ps, po[0]), 7);
  EXPECT_EQ(int32_at(ps, po[1]), 5);
  EXPECT_EQ(int32_at(ps, po[2]), 1);
  EXPECT_EQ(int32_at(ps, po[3]), 9);  // "autonomy"
  const Bytes ns = default_message("node_status_t", kNow);
  const auto no = length_field_offsets("node_status_t", ns);
  ASSERT_EQ(no.size(), 3u);  // node, n, channels[0].channel
  EXPECT_EQ(int32_at(ns, no[0]), static_cast<int32_t>(sizeof "alight-inject"));
  EXPECT_EQ(int32_at(ns, no[1]), 1);
  EXPECT_EQ(int32_at(ns, no[2]), static_cast<int32_t>(sizeof channels::kMocapPose));
  EXPECT_TRUE(length_field_offsets("pose_t", default_message("pose_t", kNow)).empty());
}

TEST(FaultGenTest, IssueFourteensOperatorCmdWithAZeroStringLengthIsAmongTheBadLengths) {
  std::mt19937_64 rng(1);
  const auto msgs = generate(Kind::kBadLengths, "operator_cmd_t", {}, kNow, rng);
  bool found = false;
  for (const auto& m : msgs) found = found || (m.size() >= 28 && int32_at(m, 24) == 0);
  EXPECT_TRUE(found);
}

// The stack's decoder runs in a child process: a crash fails this message, not the test binary.
void expect_refused(const std::string& type, const Bytes& b, const std::string& what) {
  EXPECT_EXIT(std::_Exit(decodes(type, b) ? 1 : 0), ::testing::ExitedWithCode(0), "") << what;
}

// Also a regression test of common/decode.hpp: on main (75dfc60) a string length of INT32_MIN
// makes lcm-gen's decoder copy 2 GiB (its `len - 1` wraps to INT32_MAX) and decode_message dies
// of SIGSEGV, for every type with a string the precheck does not walk (autonomy_status_t,
// operator_cmd_t, node_status_t, sim_truth_t).
TEST(FaultGenRegression, GarbageTruncatedAndBadLengthsAreRefusedWithoutCrashing) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  std::mt19937_64 rng(3);
  for (const auto& type : all_types()) {
    for (Kind k : {Kind::kGarbage, Kind::kTruncated, Kind::kBadLengths}) {
      const auto msgs = generate(k, type, {}, kNow, rng);
      EXPECT_GE(msgs.size(), 3u) << type << " " << to_string(k);
      // The last garbage message is the fingerprint then noise of the message's length: a type
      // without lengths decodes it, with random values (a hostile message too).
      const bool fixed_size = length_field_offsets(type, default_message(type, kNow)).empty();
      const size_t n = k == Kind::kGarbage && fixed_size ? msgs.size() - 1 : msgs.size();
      for (size_t i = 0; i < n; ++i)
        if (k == Kind::kBadLengths)
          expect_refused(type, msgs[i], type + " " + to_string(k) + " #" + std::to_string(i));
        else
          EXPECT_FALSE(decodes(type, msgs[i])) << type << " " << to_string(k) << " #" << i;
    }
  }
}

TEST(FaultGenTest, NonFiniteMessagesDecodeWithOneFieldNonFiniteEach) {
  pose_t base{};
  base.utime = kNow;
  base.seq = 42;
  base.pos[0] = 1.0;
  base.orientation[0] = 1.0;
  std::mt19937_64 rng(1);
  const auto msgs = generate(Kind::kNaN, "pose_t", encode(base), kNow + 5, rng);
  ASSERT_EQ(msgs.size(), 5u);  // pos, vel, orientation, angular_velocity_B, then all at once
  for (size_t i = 0; i < msgs.size(); ++i) {
    pose_t m;
    ASSERT_TRUE(decode_message(m, msgs[i].data(), msgs[i].size()));
    EXPECT_EQ(m.utime, kNow);  // built from the live message, not made up
    EXPECT_EQ(m.seq, 42);
    EXPECT_EQ(std::isnan(m.pos[0]), i == 0 || i == 4);
    EXPECT_EQ(std::isnan(m.vel[2]), i == 1 || i == 4);
    EXPECT_EQ(std::isnan(m.orientation[3]), i == 2 || i == 4);
    EXPECT_EQ(std::isnan(m.angular_velocity_B[1]), i == 3 || i == 4);
  }
  const auto infs = generate(Kind::kInf, "imu_t", {}, kNow, rng);
  ASSERT_EQ(infs.size(), 6u);  // accel, gyro, both; +Inf then -Inf
  imu_t m;
  ASSERT_TRUE(decode_message(m, infs[5].data(), infs[5].size()));
  EXPECT_TRUE(std::isinf(m.accel_B[0]) && m.accel_B[0] < 0);
}

TEST(FaultGenTest, FutureStampIsAnHourAheadOfTheLiveMessageAndNothingElseChanges) {
  position_setpoint_t sp{};
  sp.utime = kNow;
  sp.p_W[2] = 1.2;
  sp.motors = position_setpoint_t::MOTORS_ON;
  const Bytes base = encode(sp);
  std::mt19937_64 rng(1);
  const auto fut = generate(Kind::kFuture, "position_setpoint_t", base, kNow, rng);
  ASSERT_EQ(fut.size(), 1u);
  EXPECT_EQ(utime_of(fut[0]), kNow + int64_t{3600} * 1000000);
  EXPECT_TRUE(std::equal(base.begin() + 16, base.end(), fut[0].begin() + 16));
  const auto zero = generate(Kind::kZeroStamp, "position_setpoint_t", base, kNow, rng);
  ASSERT_EQ(zero.size(), 2u);  // the live setpoint at utime 0, and issue 14's motors-off one
  position_setpoint_t off;
  ASSERT_TRUE(decode_message(off, zero[1].data(), zero[1].size()));
  EXPECT_EQ(off.utime, 0);
  EXPECT_EQ(off.motors, position_setpoint_t::MOTORS_OFF);
  EXPECT_EQ(utime_of(zero[0]), 0);
}

TEST(FaultGenTest, ABaseThatDoesNotDecodeIsReplacedByADefault) {
  std::mt19937_64 rng(1);
  const auto msgs = generate(Kind::kFuture, "imu_t", Bytes{1, 2, 3}, kNow, rng);
  ASSERT_EQ(msgs.size(), 1u);
  EXPECT_TRUE(decodes("imu_t", msgs[0]));
  EXPECT_EQ(utime_of(msgs[0]), kNow + int64_t{3600} * 1000000);
  EXPECT_TRUE(generate(Kind::kNaN, "no_such_t", {}, kNow, rng).empty());
}

}  // namespace
}  // namespace alight::tools::faults
