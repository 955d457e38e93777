// alight-mavlink's parameters, link addresses and the autopilots' mode numbers.
#include "mavlink/bridge_params.hpp"

#include <gtest/gtest.h>

#include "mavlink/autopilot_modes.hpp"
#include "mavlink/link_address.hpp"
#include "test/common/expect_param_error.hpp"

namespace alight::mavlink {
namespace {

using test::expect_param_error;

BridgeParams load(const std::string& yaml) {
  return load_bridge_params(ParamNode::from_string(yaml, "ap.yaml"));
}

TEST(LinkAddressTest, ParsesSerialAndBothUdpForms) {
  auto a = parse_link_address("serial:/dev/ttyACM0:921600", nullptr);
  ASSERT_TRUE(a);
  EXPECT_EQ(a->kind, LinkAddress::Kind::kSerial);
  EXPECT_EQ(a->device, "/dev/ttyACM0");
  EXPECT_EQ(a->baud, 921600);
  a = parse_link_address("serial:/dev/serial/by-id/usb-Holybro_Pixhawk:57600", nullptr);
  ASSERT_TRUE(a);
  EXPECT_EQ(a->device, "/dev/serial/by-id/usb-Holybro_Pixhawk");
  a = parse_link_address("udp-listen:0.0.0.0:14540", nullptr);
  ASSERT_TRUE(a);
  EXPECT_EQ(a->kind, LinkAddress::Kind::kUdpListen);
  EXPECT_EQ(a->port, 14540);
  a = parse_link_address("udp:192.168.1.20:14555:14550", nullptr);
  ASSERT_TRUE(a);
  EXPECT_EQ(a->kind, LinkAddress::Kind::kUdpPeer);
  EXPECT_EQ(a->host, "192.168.1.20");
  EXPECT_EQ(a->local_port, 14550);
  EXPECT_EQ(a->text(), "udp:192.168.1.20:14555:14550");
}

TEST(LinkAddressTest, RefusesBadBaudsPortsAndKinds) {
  std::string why;
  EXPECT_FALSE(parse_link_address("serial:/dev/ttyUSB0:9600", &why));
  EXPECT_NE(why.find("9600"), std::string::npos);
  EXPECT_FALSE(parse_link_address("serial:/dev/ttyUSB0:fast", &why));
  EXPECT_FALSE(parse_link_address("serial::921600", &why));
  EXPECT_FALSE(parse_link_address("udp-listen:0.0.0.0:70000", &why));
  EXPECT_FALSE(parse_link_address("udp-listen:0.0.0.0:1:2", &why));
  EXPECT_FALSE(parse_link_address("tcp:localhost:5760", &why));
  EXPECT_NE(why.find("tcp"), std::string::npos);
  EXPECT_FALSE(parse_link_address("/dev/ttyUSB0", &why));
  for (int b : kBaudRates) EXPECT_TRUE(valid_baud(b));
}

TEST(BridgeParamsTest, ReadsAFileAndNamesTheKeyOfABadValue) {
  const auto p = load(
      "mavlink:\n  autopilot: ardupilot\n  link: serial:/dev/ttyAMA0:921600\n"
      "  control: position\n  stream_rate_hz: 20\n");
  EXPECT_EQ(p.flavour(), Flavour::kArdupilot);
  EXPECT_EQ(p.control_mode(), ControlMode::kPosition);
  EXPECT_EQ(p.stream_rate_hz, 20);

  auto e = expect_param_error([] { load("mavlink:\n  link: serial:/dev/ttyS0:1200\n"); });
  EXPECT_EQ(e.key(), "mavlink.link");
  e = expect_param_error([] { load("mavlink:\n  autopilot: inav\n"); });
  EXPECT_EQ(e.key(), "mavlink.autopilot");
  e = expect_param_error([] { load("mavlink:\n  stream_rate_hz: 1\n"); });
  EXPECT_EQ(e.key(), "mavlink.stream_rate_hz");
  e = expect_param_error([] { load("mavlink:\n  hover_thrust: 1.0\n"); });
  EXPECT_EQ(e.key(), "mavlink.hover_thrust");
  e = expect_param_error([] { load("mavlink:\n  unknown_key: 1\n"); });
}

TEST(BridgeParamsTest, TheEkfOriginTheFailsafeAndTheSigningKeyAreChecked) {
  const auto p = load(
      "mavlink:\n  autopilot: ardupilot\n  set_ekf_origin: true\n"
      "  ekf_origin: [-35.36, 149.16, 584]\n  silence_action: autopilot\n"
      "  signing_key_file: keys/link.key\n");
  EXPECT_EQ(p.ekf_origin, (std::vector<double>{-35.36, 149.16, 584}));
  EXPECT_EQ(p.silence_action, "autopilot");
  EXPECT_EQ(p.signing_key_file.substr(p.signing_key_file.size() - 13), "keys/link.key");
  // ArduPilot refuses an origin at 0, 0 (GCS_Common.cpp, handle_set_gps_global_origin).
  auto e = expect_param_error([] { load("mavlink:\n  set_ekf_origin: true\n"); });
  EXPECT_EQ(e.key(), "mavlink.ekf_origin");
  e = expect_param_error([] { load("mavlink:\n  ekf_origin: [91, 0, 0]\n"); });
  EXPECT_EQ(e.key(), "mavlink.ekf_origin");
  e = expect_param_error([] { load("mavlink:\n  ekf_origin: [1, 2]\n"); });
  EXPECT_EQ(e.key(), "mavlink.ekf_origin");
  e = expect_param_error([] { load("mavlink:\n  silence_action: hover\n"); });
  EXPECT_EQ(e.key(), "mavlink.silence_action");
  e = expect_param_error([] { load("mavlink:\n  rearm_cooldown_s: -1\n"); });
  EXPECT_EQ(e.key(), "mavlink.rearm_cooldown_s");
}

TEST(BridgeParamsTest, StreamsThatDoNotFitTheSerialLinkAreRefused) {
  // 50 Hz attitude setpoints and 50 Hz ATT_POS_MOCAP need about 9 kB/s; 57600 baud carries 5.76.
  const auto e = expect_param_error([] { load("mavlink:\n  link: serial:/dev/ttyUSB0:57600\n"); });
  EXPECT_EQ(e.key(), "mavlink.stream_rate_hz");
  EXPECT_NE(e.problem().find("57600"), std::string::npos);
  // Lower rates fit.
  EXPECT_NO_THROW(load(
      "mavlink:\n  link: serial:/dev/ttyUSB0:57600\n  stream_rate_hz: 20\n  mocap_rate_hz: 20\n"));
  EXPECT_NO_THROW(load("mavlink:\n  link: serial:/dev/ttyUSB0:921600\n"));
}

TEST(AutopilotModesTest, Px4CustomModesAndNames) {
  const uint32_t offboard = px4_mode::custom_mode(px4_mode::kOffboard);
  EXPECT_EQ(offboard, 6u << 16);
  EXPECT_EQ(mode_name(Flavour::kPx4, offboard), "OFFBOARD");
  EXPECT_EQ(
      mode_name(Flavour::kPx4, px4_mode::custom_mode(px4_mode::kAuto, px4_mode::auto_sub::kLand)),
      "AUTO.LAND");
  EXPECT_TRUE(is_fly_mode(Flavour::kPx4, ControlMode::kAttitude, offboard));
  EXPECT_TRUE(is_fly_mode(Flavour::kPx4, ControlMode::kPosition, offboard));
  EXPECT_FALSE(
      is_fly_mode(Flavour::kPx4, ControlMode::kAttitude, px4_mode::custom_mode(px4_mode::kPosctl)));
  const auto p = set_mode_params(Flavour::kPx4, offboard);
  EXPECT_EQ(p.param1, 1.0f);
  EXPECT_EQ(p.param2, 6.0f);
  EXPECT_EQ(p.param3, 0.0f);
}

TEST(AutopilotModesTest, ArduCopterFliesGuidedNoGpsOnAttitudeAndGuidedOnPosition) {
  EXPECT_EQ(fly_custom_mode(Flavour::kArdupilot, ControlMode::kAttitude), 20u);
  EXPECT_EQ(fly_custom_mode(Flavour::kArdupilot, ControlMode::kPosition), 4u);
  EXPECT_EQ(mode_name(Flavour::kArdupilot, 20), "GUIDED_NOGPS");
  EXPECT_EQ(mode_name(Flavour::kArdupilot, 99), "MODE(99)");
  EXPECT_EQ(set_mode_params(Flavour::kArdupilot, 20).param2, 20.0f);
}

}  // namespace
}  // namespace alight::mavlink
