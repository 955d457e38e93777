// Channel names (common/channels.hpp) and the --remap FROM=TO parser.

#include "common/channels.hpp"

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

namespace alight {
namespace {

// The message of the RemapError that parsing `args` throws ("" when it does not throw).
std::string remap_error(const std::vector<std::string>& args) {
  try {
    parse_remaps(args);
  } catch (const RemapError& e) {
    return e.what();
  }
  return "";
}

TEST(ChannelsTest, NamesAreDistinctAndKnown) {
  std::set<std::string> names(channels::kAll.begin(), channels::kAll.end());
  EXPECT_EQ(names.size(), channels::kAll.size());
  for (const char* c : channels::kAll) EXPECT_TRUE(channels::is_known(c)) << c;
  EXPECT_TRUE(channels::is_known("CAMERA"));
  EXPECT_FALSE(channels::is_known("camera"));
  EXPECT_FALSE(channels::is_known(""));
}

TEST(ChannelRemapTest, NoArgumentsRenameNothing) {
  const ChannelRemap r = parse_remaps({});
  EXPECT_TRUE(r.empty());
  EXPECT_EQ(r(channels::kCamera), "CAMERA");
  EXPECT_EQ(r("ANYTHING_ELSE"), "ANYTHING_ELSE");
}

TEST(ChannelRemapTest, RenamesOnlyTheChannelsGiven) {
  const ChannelRemap r = parse_remaps({"CAMERA=CAMERA_LEFT", "VISION_TARGET=drone2/VISION-TARGET"});
  EXPECT_EQ(r(channels::kCamera), "CAMERA_LEFT");
  EXPECT_EQ(r(channels::kVisionTarget), "drone2/VISION-TARGET");
  EXPECT_EQ(r(channels::kMocapPose), "MOCAP_POSE");
  EXPECT_EQ(r.map().size(), 2u);
}

TEST(ChannelRemapTest, RepeatsAndIdentitiesAreHarmless) {
  const ChannelRemap r = parse_remaps({"IMU=IMU_2", "IMU=IMU_2", "CAMERA=CAMERA"});
  EXPECT_EQ(r(channels::kImu), "IMU_2");
  EXPECT_EQ(r(channels::kCamera), "CAMERA");
}

TEST(ChannelRemapTest, TwoChannelsMaySwapNames) {
  const ChannelRemap r = parse_remaps({"CAMERA=VISION_DIAG", "VISION_DIAG=CAMERA"});
  EXPECT_EQ(r(channels::kCamera), "VISION_DIAG");
  EXPECT_EQ(r(channels::kVisionDiag), "CAMERA");
}

TEST(ChannelRemapTest, BadFormsAreRefusedNamingTheArgument) {
  for (const std::string bad : {"CAMERA", "CAMERA:=X", "=X", "CAMERA=", "=", "A=B=C", ""}) {
    const std::string e = remap_error({bad});
    EXPECT_NE(e.find("--remap '" + bad + "'"), std::string::npos) << bad << ": " << e;
  }
  EXPECT_NE(remap_error({"CAMERA"}).find("FROM=TO"), std::string::npos);
  EXPECT_NE(remap_error({"CAMERA="}).find("FROM=TO"), std::string::npos);
}

TEST(ChannelRemapTest, AnUnknownChannelIsRefusedListingTheKnownOnes) {
  const std::string e = remap_error({"CAMERA_LEFT=CAMERA"});
  EXPECT_NE(e.find("unknown channel 'CAMERA_LEFT'"), std::string::npos) << e;
  for (const char* c : channels::kAll) EXPECT_NE(e.find(c), std::string::npos) << c;
  EXPECT_NE(remap_error({"camera=X"}).find("unknown channel"), std::string::npos);
}

TEST(ChannelRemapTest, ANameLcmCannotUseIsRefused) {
  // LCM subscribes by regular expression: '.', '*', '(' ... would match other channels.
  const std::vector<std::string> bad = {"CAM.ERA", "CAM*",   "CAM ERA",
                                        "CAM(1)",  "CAMÉRA", std::string(64, 'A')};
  for (const std::string& to : bad)
    EXPECT_NE(remap_error({"CAMERA=" + to}).find("not a usable channel name"), std::string::npos)
        << to;
  EXPECT_EQ(remap_error({"CAMERA=" + std::string(63, 'A')}), "");
}

TEST(ChannelRemapTest, ConflictingRenamesAreRefused) {
  EXPECT_NE(remap_error({"CAMERA=A", "CAMERA=B"}).find("CAMERA is already remapped to A"),
            std::string::npos);
  const std::string two = remap_error({"CAMERA=SAME", "VISION_DIAG=SAME"});
  EXPECT_NE(two.find("would both be on channel SAME"), std::string::npos) << two;
  // Onto another channel's name while that one keeps it: image_t and pose_t on one channel.
  const std::string onto = remap_error({"CAMERA=MOCAP_POSE"});
  EXPECT_NE(onto.find("would both be on channel MOCAP_POSE"), std::string::npos) << onto;
  // Onto a channel of the same type that keeps its name: read that one in its place (flying on
  // the onboard estimate). Not when both move, not across types.
  EXPECT_EQ(remap_error({"MOCAP_POSE=ESTIMATE_POSE"}), "");
  EXPECT_EQ(remap_error({"MOCAP_POSE=AUTOPILOT_POSE"}), "");
  // The estimator's flow on the mission's camera when that is the downward one (landing).
  EXPECT_EQ(remap_error({"FLOW_CAMERA=CAMERA"}), "");
  EXPECT_NE(remap_error({"MOCAP_POSE=X", "ESTIMATE_POSE=X"}).find("would both be on channel X"),
            std::string::npos);
  EXPECT_NE(remap_error({"IMU=ESTIMATE_POSE"}).find("would both be on channel ESTIMATE_POSE"),
            std::string::npos);
}

TEST(ChannelsTest, EveryChannelHasItsMessageType) {
  for (const char* c : channels::kAll) EXPECT_NE(channels::message_type(c), "") << c;
  EXPECT_EQ(channels::message_type("NOT_A_CHANNEL"), "");
}

}  // namespace
}  // namespace alight
