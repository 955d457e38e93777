// Ground-station parameters: defaults valid, file overrides, errors naming file, key and value.

#include "ground_station/params.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "common/params.hpp"

namespace alight::ground_station {
namespace {

std::string write_yaml(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("alight_gs_" + std::to_string(::getpid()) + "_" + name + ".yaml");
  std::ofstream(path) << text;
  return path.string();
}

TEST(GroundStationParamsTest, DefaultsAreValidWithoutAFile) {
  const GroundStationParams p = load_params("");
  EXPECT_EQ(p.http_port, 8080);
  EXPECT_EQ(p.command_channel, "OPERATOR_CMD");
}

TEST(GroundStationParamsTest, FileOverridesDefaults) {
  const auto path =
      write_yaml("ok", "ground_station:\n  http_port: 9000\n  camera_channel: CAM2\n");
  const GroundStationParams p = load_params(path);
  EXPECT_EQ(p.http_port, 9000);
  EXPECT_EQ(p.camera_channel, "CAM2");
  std::filesystem::remove(path);
}

TEST(GroundStationParamsTest, BadValuesNameFileKeyAndValue) {
  const auto path = write_yaml("bad", "ground_station:\n  jpeg_quality: 0\n");
  try {
    load_params(path);
    FAIL() << "no exception";
  } catch (const ParamError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.key(), "ground_station.jpeg_quality");
    EXPECT_EQ(e.value(), "0");
  }
  std::filesystem::remove(path);
}

TEST(GroundStationParamsTest, UnknownKeysAreRejected) {
  const auto path = write_yaml("typo", "ground_station:\n  http_prot: 9000\n");
  EXPECT_THROW(load_params(path), ParamError);
  std::filesystem::remove(path);
}

TEST(GroundStationParamsTest, OperatorLinkAndServerLimitsAreReadAndBounded) {
  const auto ok = write_yaml("link",
                             "ground_station:\n  vehicle_id: uav-7\n  ack_timeout_s: 0.5\n"
                             "  head_deadline_s: 1.5\n  command_threads: 3\n");
  const GroundStationParams p = load_params(ok);
  EXPECT_EQ(p.vehicle_id, "uav-7");
  EXPECT_DOUBLE_EQ(p.ack_timeout_s, 0.5);
  EXPECT_DOUBLE_EQ(p.head_deadline_s, 1.5);
  EXPECT_EQ(p.command_threads, 3);
  std::filesystem::remove(ok);
  // An infinite or missing deadline would let a slow client hold a connection for good.
  for (const char* bad : {"head_deadline_s: .inf", "request_deadline_s: .nan", "ack_timeout_s: 0",
                          "max_header_count: 100000", "vehicle_id: \"\"", "command_threads: 0",
                          "channel_stale_s: .inf", "request_deadline_s: 0.5"}) {
    const auto path = write_yaml("bad_link", std::string("ground_station:\n  ") + bad + "\n");
    EXPECT_THROW(load_params(path), ParamError) << bad;
    std::filesystem::remove(path);
  }
}

TEST(GroundStationParamsTest, FrameWaitAndQueuedConnectionsHaveUpperBounds) {
  const auto ok = write_yaml("bounds_ok",
                             "ground_station:\n  frame_wait_s: 2\n  client_timeout_s: 3\n"
                             "  max_queued_connections: 256\n");
  const GroundStationParams p = load_params(ok);
  EXPECT_DOUBLE_EQ(p.frame_wait_s, 2.0);
  EXPECT_EQ(p.max_queued_connections, 256);
  std::filesystem::remove(ok);
  struct Bad {
    const char* yaml;
    const char* key;
    const char* value;
    const char* problem;
  };
  for (const Bad& bad : {
           Bad{"frame_wait_s: 2.5\n  client_timeout_s: 60", "ground_station.frame_wait_s", "2.5",
               "must be in [0, 2] s"},
           Bad{"frame_wait_s: 30\n  client_timeout_s: 60", "ground_station.frame_wait_s", "30",
               "must be in [0, 2] s"},
           // The answer is written after the wait: past the request's deadline it never is.
           Bad{"frame_wait_s: 1.5\n  head_deadline_s: 1\n  request_deadline_s: 1",
               "ground_station.frame_wait_s", "1.5",
               "must be below client_timeout_s and request_deadline_s"},
           Bad{"max_queued_connections: 257", "ground_station.max_queued_connections", "257",
               "must be in [1, 256]"},
           Bad{"max_queued_connections: 2000000000", "ground_station.max_queued_connections",
               "2000000000", "must be in [1, 256]"},
       }) {
    const auto path =
        write_yaml("bounds_bad", std::string("ground_station:\n  ") + bad.yaml + "\n");
    try {
      load_params(path);
      ADD_FAILURE() << bad.yaml << ": no exception";
    } catch (const ParamError& e) {
      EXPECT_EQ(e.file(), path) << bad.yaml;
      EXPECT_EQ(e.key(), bad.key) << bad.yaml;
      EXPECT_EQ(e.value(), bad.value) << bad.yaml;
      EXPECT_EQ(e.problem(), bad.problem) << bad.yaml;
    }
    std::filesystem::remove(path);
  }
}

}  // namespace
}  // namespace alight::ground_station
