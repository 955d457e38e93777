// The mocap files load; every error names the file, the full key and the value as written.

#include "mocap/params.hpp"

#include <gtest/gtest.h>

#include "common/build_paths.hpp"

namespace alight::mocap {
namespace {

ParamError load_error(const std::string& yaml) {
  try {
    load_params(ParamNode::from_string(yaml, "room.yaml"));
  } catch (const ParamError& e) {
    return e;
  }
  ADD_FAILURE() << "loaded: " << yaml;
  return ParamError("", "", "", "");
}

TEST(MocapParamsTest, ShippedFilesLoad) {
  const std::string dir = std::string(alight::build::source_dir()) + "/config/mocap/";
  const auto vicon = load_params(dir + "vicon_tracker.yaml");
  EXPECT_EQ(vicon.room.up_axis, "z");
  EXPECT_EQ(vicon.room.units, "m");
  EXPECT_EQ(parse_tracker(vicon.server.tracker)->port, 3883);
  const auto motive = load_params(dir + "optitrack_motive.yaml");
  EXPECT_EQ(motive.room.up_axis, "y");
  EXPECT_EQ(motive.body.rpy_M_B_deg, Eigen::Vector3d(-90, 0, 0));
  EXPECT_EQ(motive.channel, "MOCAP_POSE");
}

TEST(MocapParamsTest, TrackerAddresses) {
  const auto a = parse_tracker("Pelican@10.0.0.2:3884");
  ASSERT_TRUE(a);
  EXPECT_EQ(a->object, "Pelican");
  EXPECT_EQ(a->host, "10.0.0.2");
  EXPECT_EQ(a->port, 3884);
  EXPECT_EQ(parse_tracker("Rigid Body 1@vicon-pc")->object, "Rigid Body 1");
  for (const char* bad : {"", "Pelican", "@host", "Pelican@", "Pelican@host:", "Pelican@host:0",
                          "Pelican@host:70000", "Pelican@host:38x3", "a@b@c", "Pelican@ho st"})
    EXPECT_FALSE(parse_tracker(bad)) << bad;
}

TEST(MocapParamsTest, ErrorsNameFileKeyAndValue) {
  auto e = load_error("mocap: {server: {sensor: 1}}");
  EXPECT_EQ(e.file(), "room.yaml");
  EXPECT_EQ(e.key(), "mocap.server.tracker");
  e = load_error("mocap: {server: {tracker: 'Pelican'}}");
  EXPECT_EQ(e.key(), "mocap.server.tracker");
  EXPECT_EQ(e.value(), "Pelican");
  e = load_error("mocap: {server: {tracker: P@h}, room: {units: cm}}");
  EXPECT_EQ(e.key(), "mocap.room.units");
  EXPECT_NE(std::string(e.what()).find("m or mm"), std::string::npos);
  e = load_error("mocap: {server: {tracker: P@h}, room: {up_axis: x}}");
  EXPECT_EQ(e.key(), "mocap.room.up_axis");
  e = load_error("mocap: {server: {tracker: P@h}, stamp: {source: gps}}");
  EXPECT_EQ(e.key(), "mocap.stamp.source");
  e = load_error("mocap: {server: {tracker: P@h, retry_initial_s: 3, retry_max_s: 1}}");
  EXPECT_EQ(e.key(), "mocap.server.retry_max_s");
  e = load_error("mocap: {server: {tracker: P@h, silence_timeout_s: .inf}}");
  EXPECT_EQ(e.key(), "mocap.server.silence_timeout_s");
  EXPECT_EQ(e.value(), ".inf");
  e = load_error("mocap: {server: {tracker: P@h}, velocity: {span_s: 0.05, max_gap_s: 0.02}}");
  EXPECT_EQ(e.key(), "mocap.velocity.max_gap_s");
  e = load_error("mocap: {server: {tracker: P@h}, room: {p_W_R_m: [0, 0]}}");
  EXPECT_EQ(e.key(), "mocap.room.p_W_R_m");
  e = load_error("mocap: {server: {tracker: P@h}, room: {unit: mm}}");  // a typo
  EXPECT_NE(std::string(e.what()).find("unit"), std::string::npos);
  e = load_error("mocap: {server: {tracker: P@h}}\nvehicle: {}");
  EXPECT_NE(std::string(e.what()).find("vehicle"), std::string::npos);
  e = load_error("server: {tracker: P@h}");
  EXPECT_NE(std::string(e.what()).find("mocap"), std::string::npos);
}

TEST(MocapParamsTest, DefaultsValidateAndDumpReadsBack) {
  MocapParams p;
  p.server.tracker = "Pelican@127.0.0.1";
  EXPECT_NO_THROW(p.validate());
  std::ostringstream out;
  out << "mocap:\n";
  MocapParams::schema().dump(out, p, 2);
  const auto back = load_params(ParamNode::from_string(out.str(), "dump.yaml"));
  EXPECT_EQ(back.server.tracker, p.server.tracker);
  EXPECT_EQ(back.stamp.source, "mapped");
  EXPECT_EQ(back.velocity.span_s, p.velocity.span_s);
}

}  // namespace
}  // namespace alight::mocap
