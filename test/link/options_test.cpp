// alight-link's command line: what a vehicle and a ground link take, and every mistake refused
// with the option and the value named (ParamError: exit code 2).

#include "link/options.hpp"

#include <gtest/gtest.h>

#include "common/params.hpp"

namespace alight::link {
namespace {

RawOptions vehicle() {
  RawOptions r;
  r.listen = "0.0.0.0:7670";
  r.send = {"AUTONOMY_STATUS,NODE_STATUS", "CAMERA"};
  r.receive = {"OPERATOR_CMD"};
  r.max_rate = {"CAMERA=2", "OPERATOR_CMD=20"};
  return r;
}

// The error names `option` and `value`, and says `problem`.
void expect_error(const RawOptions& r, const std::string& option, const std::string& value,
                  const std::string& problem) {
  try {
    parse_options(r);
    ADD_FAILURE() << "accepted; expected an error about " << option;
  } catch (const ParamError& e) {
    EXPECT_EQ(e.key(), option) << e.what();
    EXPECT_EQ(e.value(), value) << e.what();
    EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
  }
}

TEST(LinkOptions, AVehicleAndAGroundLink) {
  const Options v = parse_options(vehicle());
  EXPECT_EQ(v.role, Role::kVehicle);
  EXPECT_EQ(v.endpoint.host, "0.0.0.0");
  EXPECT_EQ(v.endpoint.port, 7670);
  EXPECT_EQ(v.send, (std::vector<std::string>{"AUTONOMY_STATUS", "NODE_STATUS", "CAMERA"}));
  EXPECT_EQ(v.receive, std::vector<std::string>{"OPERATOR_CMD"});
  EXPECT_DOUBLE_EQ(v.max_rate_hz.at("CAMERA"), 2.0);
  EXPECT_DOUBLE_EQ(v.max_rate_hz.at("OPERATOR_CMD"), 20.0);
  EXPECT_DOUBLE_EQ(v.timeout_s, kDefaultTimeoutS);
  EXPECT_EQ(v.max_frame_bytes, kDefaultMaxFrameBytes);
  RawOptions g;
  g.connect = "[fe80::1]:7670";
  g.receive = {"CAMERA"};
  g.timeout_s = 2.5;
  g.max_frame_bytes = 1 << 20;
  const Options o = parse_options(g);
  EXPECT_EQ(o.role, Role::kGround);
  EXPECT_EQ(o.endpoint.host, "fe80::1");
  EXPECT_EQ(o.endpoint.text(), "[fe80::1]:7670");
  EXPECT_DOUBLE_EQ(o.timeout_s, 2.5);
  EXPECT_EQ(o.max_frame_bytes, 1u << 20);
}

TEST(LinkOptions, EndpointsAreHostColonPort) {
  EXPECT_EQ(parse_endpoint("vehicle.local:7670", "--connect").host, "vehicle.local");
  for (const std::string bad : {"7670", "host:", ":7670", "host:0", "host:65536", "host:12x",
                                "fe80::1:7670", "[fe80::1:7670", "[]:7670"}) {
    try {
      parse_endpoint(bad, "--connect");
      ADD_FAILURE() << bad << " accepted";
    } catch (const ParamError& e) {
      EXPECT_EQ(e.key(), "--connect");
      EXPECT_EQ(e.value(), bad);
    }
  }
}

TEST(LinkOptions, MistakesNameTheOptionAndTheValue) {
  RawOptions r = vehicle();
  r.connect = "10.0.0.1:7670";
  expect_error(r, "--listen / --connect", "0.0.0.0:767010.0.0.1:7670", "exactly one");
  r = vehicle();
  r.listen.clear();
  expect_error(r, "--listen / --connect", "", "exactly one");
  r = vehicle();
  r.send = {"AUTONOMY_STATUS,CAMERAA"};
  expect_error(r, "--send", "AUTONOMY_STATUS,CAMERAA", "unknown channel 'CAMERAA' (known: CAMERA");
  r = vehicle();
  r.send = {"CAMERA,"};
  expect_error(r, "--send", "CAMERA,", "empty");
  r = vehicle();
  r.send.push_back("CAMERA");
  expect_error(r, "--send", "CAMERA", "given twice");
  r = vehicle();
  r.receive = {"OPERATOR_CMD,CAMERA"};
  expect_error(r, "--receive", "OPERATOR_CMD,CAMERA", "given twice");
  r = vehicle();
  r.send.clear();
  r.receive.clear();
  r.max_rate.clear();
  expect_error(r, "--send / --receive", "", "carries nothing");
  r = vehicle();
  r.max_rate = {"CAMERA"};
  expect_error(r, "--max-rate", "CAMERA", "CH=HZ");
  r.max_rate = {"VISION_DIAG=2"};
  expect_error(r, "--max-rate", "VISION_DIAG=2", "not a channel of --send or --receive");
  for (const std::string hz : {"0", "-1", "nan", "inf", "2000", "2hz", ""}) {
    r.max_rate = {"CAMERA=" + hz};
    expect_error(r, "--max-rate", "CAMERA=" + hz, "above 0");
  }
  r.max_rate = {"CAMERA=2", "CAMERA=3"};
  expect_error(r, "--max-rate", "CAMERA=3", "a second rate");
  r = vehicle();
  r.timeout_s = 0.1;
  expect_error(r, "--timeout", "0.1", "from 0.5 to 600");
  r = vehicle();
  r.max_frame_bytes = 100;
  expect_error(r, "--max-frame-bytes", "100", "from 4096");
  r = vehicle();
  r.listen = "0.0.0.0";
  expect_error(r, "--listen", "0.0.0.0", "HOST:PORT");
}

}  // namespace
}  // namespace alight::link
