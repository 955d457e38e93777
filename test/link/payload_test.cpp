// The link carries a message only when it is one well-formed message of its channel's type: for
// every channel of common/channels.hpp, a message of its type passes and a cut, lengthened,
// trailed or foreign one does not.

#include "link/payload.hpp"

#include <gtest/gtest.h>

#include <alight/attitude_cmd_t.hpp>
#include <alight/autonomy_status_t.hpp>
#include <alight/autopilot_status_t.hpp>
#include <alight/baro_t.hpp>
#include <alight/image_t.hpp>
#include <alight/imu_t.hpp>
#include <alight/node_status_t.hpp>
#include <alight/operator_cmd_t.hpp>
#include <alight/platform_motion_t.hpp>
#include <alight/platform_truth_t.hpp>
#include <alight/pose_t.hpp>
#include <alight/position_setpoint_t.hpp>
#include <alight/process_status_t.hpp>
#include <alight/range_t.hpp>
#include <alight/sim_control_t.hpp>
#include <alight/sim_truth_t.hpp>
#include <alight/state_estimate_t.hpp>
#include <alight/target_t.hpp>
#include <alight/vision_timing_t.hpp>
#include <functional>
#include <map>

#include "common/bus_auth.hpp"
#include "common/channels.hpp"

namespace alight::link {
namespace {

template <class Msg>
std::vector<uint8_t> encode(Msg m) {
  std::vector<uint8_t> b(static_cast<size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

// A message of each type (empty strings encode as a length of 1 and decode; the variable-length
// arrays get an element where the type has one).
std::vector<uint8_t> sample(const std::string& type) {
  const std::map<std::string, std::function<std::vector<uint8_t>()>> make = {
      {"attitude_cmd_t", [] { return encode(attitude_cmd_t{}); }},
      {"autonomy_status_t", [] { return encode(autonomy_status_t{}); }},
      {"autopilot_status_t", [] { return encode(autopilot_status_t{}); }},
      {"baro_t", [] { return encode(baro_t{}); }},
      {"image_t",
       [] {
         image_t m{};
         m.width = 4;
         m.height = 2;
         m.row_stride = 4;
         m.size = 8;
         m.data.assign(8, 1);
         return encode(m);
       }},
      {"imu_t", [] { return encode(imu_t{}); }},
      {"node_status_t",
       [] {
         node_status_t m{};
         m.node = "alight-vision";
         m.n = 1;
         m.channels.resize(1);
         m.channels[0].channel = "CAMERA";
         return encode(m);
       }},
      {"operator_cmd_t", [] { return encode(operator_cmd_t{}); }},
      {"platform_truth_t", [] { return encode(platform_truth_t{}); }},
      {"platform_motion_t", [] { return encode(platform_motion_t{}); }},
      {"pose_t", [] { return encode(pose_t{}); }},
      {"position_setpoint_t", [] { return encode(position_setpoint_t{}); }},
      {"process_status_t",
       [] {
         process_status_t m{};
         m.n = 1;
         m.processes.resize(1);
         m.processes[0].name = "vision";
         return encode(m);
       }},
      {"range_t", [] { return encode(range_t{}); }},
      {"sim_control_t", [] { return encode(sim_control_t{}); }},
      {"sim_truth_t", [] { return encode(sim_truth_t{}); }},
      {"state_estimate_t", [] { return encode(state_estimate_t{}); }},
      {"target_t", [] { return encode(target_t{}); }},
      {"vision_timing_t", [] { return encode(vision_timing_t{}); }},
  };
  const auto it = make.find(type);
  return it == make.end() ? std::vector<uint8_t>{} : it->second();
}

TEST(LinkPayload, EveryChannelTakesItsTypeAndNothingElse) {
  for (const char* channel : channels::kAll) {
    const std::string type = channels::message_type(channel);
    const auto good = sample(type);
    ASSERT_FALSE(good.empty()) << channel << ": no sample of " << type;
    EXPECT_TRUE(valid_payload(channel, good)) << channel;
    EXPECT_FALSE(valid_payload(channel, std::span<const uint8_t>(good.data(), good.size() - 1)))
        << channel << " cut by a byte";
    auto longer = good;
    longer.push_back(0);
    EXPECT_FALSE(valid_payload(channel, longer)) << channel << " with a byte more";
    EXPECT_FALSE(valid_payload(channel, {})) << channel << " empty";
    // Another type's message: the fingerprint differs.
    const auto other = sample(type == "pose_t" ? "imu_t" : "pose_t");
    EXPECT_FALSE(valid_payload(channel, other)) << channel << " with another type";
  }
  EXPECT_FALSE(valid_payload("NOT_A_CHANNEL", sample("pose_t")));
}

TEST(LinkPayload, APayloadEndingInAnOriginTrailerIsNotOne) {
  auto bytes = sample("pose_t");
  bus::Sealer sealer(1234, std::nullopt);
  sealer.seal(bytes, "MOCAP_POSE", 1);
  EXPECT_FALSE(valid_payload("MOCAP_POSE", bytes));
}

TEST(LinkPayload, AnImageClaimingGigabytesIsRefusedWithoutAllocatingThem) {
  auto bytes = sample("image_t");
  // The data count (after fingerprint, utime, width, height, row_stride, pixelformat) set huge.
  bytes[32] = 0x7f;
  EXPECT_FALSE(valid_payload("CAMERA", bytes));
}

TEST(LinkPayload, RawMessageKeepsTheBytesItIsGiven) {
  const std::vector<uint8_t> in = {1, 2, 3, 4, 5};
  RawMessage m;
  EXPECT_EQ(m.decode(in.data(), 1, 3), 3);
  EXPECT_EQ(m.bytes, (std::vector<uint8_t>{2, 3, 4}));
}

}  // namespace
}  // namespace alight::link
