// The alight-camera and alight-calibrate binaries: exit codes and messages, --list on a machine
// without cameras, an image folder published over LCM, and a calibration written to YAML.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <alight/image_t.hpp>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <opencv2/imgcodecs.hpp>

#include "common/build_paths.hpp"
#include "common/camera_model.hpp"
#include "common/image_msg.hpp"
#include "common/node.hpp"
#include "render_chessboard.hpp"

namespace alight::camera {
namespace {

namespace fs = std::filesystem;
const std::string kBin = std::string(alight::build::binary_dir()) + "/bin/";
const std::string kUrl = "udpm://239.255.76.67:7791?ttl=0";

struct ProcessResult {
  int code = -1;
  std::string output;  // stdout and stderr
};

ProcessResult run(const std::string& args) {
  ProcessResult r;
  FILE* p = popen((args + " 2>&1").c_str(), "r");
  char buf[512];
  while (p && fgets(buf, sizeof(buf), p)) r.output += buf;
  const int status = p ? pclose(p) : -1;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string tmp_dir(const std::string& name) {
  const std::string d = std::string(alight::build::binary_dir()) + "/test_tmp/camera_node/" + name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(CameraNodeTest, ListWorksWithoutCameras) {
  const ProcessResult r = run(kBin + "alight-camera --list");
  EXPECT_EQ(r.code, 0) << r.output;
  bool usb_video = false;  // a machine with a USB camera lists it instead
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/sys/class/video4linux", ec)) {
    (void)e;
    usb_video = true;
  }
  if (!usb_video) {
    EXPECT_NE(r.output.find("no USB cameras found"), std::string::npos) << r.output;
  }
}

TEST(CameraNodeTest, MissingDeviceExitsWithCode3AndSaysWhatToCheck) {
  const ProcessResult r = run(kBin + "alight-camera --device /dev/video_alight_missing");
  EXPECT_EQ(r.code, 3) << r.output;
  EXPECT_NE(r.output.find("/dev/video_alight_missing: no such device"), std::string::npos)
      << r.output;
  const ProcessResult u = run(kBin + "alight-camera --device usb:dead:beef");
  EXPECT_EQ(u.code, 3) << u.output;
  EXPECT_NE(u.output.find("usb:dead:beef"), std::string::npos) << u.output;
}

TEST(CameraNodeTest, NotAVideoDeviceExitsWithCode6) {
  const ProcessResult r = run(kBin + "alight-camera --device /dev/null");
  EXPECT_EQ(r.code, 6) << r.output;
  EXPECT_NE(r.output.find("not a V4L2 device"), std::string::npos) << r.output;
}

TEST(CameraNodeTest, PermissionDeniedExitsWithCode5) {
  const std::string dir = tmp_dir("perm");
  const std::string node = dir + "/video9";
  std::ofstream(node) << "x";
  fs::permissions(node, fs::perms::none);
  // Root opens any file: then run the node as user nobody, when setpriv can.
  std::string prefix;
  if (geteuid() == 0) {
    if (run("setpriv --reuid=65534 --regid=65534 --clear-groups true").code != 0)
      GTEST_SKIP() << "running as root without setpriv";
    prefix = "setpriv --reuid=65534 --regid=65534 --clear-groups ";
  }
  const ProcessResult r = run(prefix + kBin + "alight-camera --device " + node);
  if (r.output.find("ermission denied") == std::string::npos && r.code == 126)
    GTEST_SKIP() << "user nobody cannot execute the build tree: " << r.output;
  EXPECT_EQ(r.code, 5) << r.output;
  EXPECT_NE(r.output.find("permission denied"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("group 'video'"), std::string::npos) << r.output;
}

TEST(CameraNodeTest, BadConfigurationExitsWithCode2NamingTheKey) {
  const std::string dir = tmp_dir("badcfg");
  std::ofstream(dir + "/cam.yaml") << "pixel_format: NV12\n";
  const ProcessResult r = run(kBin + "alight-camera --config " + dir + "/cam.yaml");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("pixel_format = NV12"), std::string::npos) << r.output;
  const ProcessResult s = run(kBin + "alight-camera --source tape:x");
  EXPECT_EQ(s.code, 2) << s.output;
  const ProcessResult f = run(kBin + "alight-camera --source folder:" + dir + "/nothing_here");
  EXPECT_EQ(f.code, 3) << f.output;
}

TEST(CameraNodeTest, ImageFolderIsPublishedInOrderWithStampsAndMetadata) {
  const std::string dir = tmp_dir("folder");
  const int n = 6;
  for (int i = 0; i < n; ++i)
    cv::imwrite(dir + "/frame_" + std::to_string(i) + ".png",
                cv::Mat(48, 64, CV_8UC1, cv::Scalar(20 * i + 10)));
  std::ofstream(dir + "/notes.txt") << "not an image";

  Node rx(kUrl, "camera_node_test");
  std::vector<image_t> got;
  rx.on<image_t>("CAMERA_TEST", [&](const image_t& m) { got.push_back(m); });
  const std::string cfg = dir + "/cam.yaml";
  std::ofstream(cfg) << "channel: CAMERA_TEST\ncamera_info: " << alight::build::source_dir()
                     << "/config/cameras/firefly_mv_4mm.yaml\n";
  const int64_t start = wall_utime();
  auto proc = std::async(std::launch::async, [&] {
    return run(kBin + "alight-camera --config " + cfg + " --lcm-url '" + kUrl +
               "' --source folder:" + dir + " --rate 20");
  });
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (static_cast<int>(got.size()) < n && std::chrono::steady_clock::now() < deadline) {
    rx.spin_once(50);
    if (proc.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
      rx.spin_once(200);  // what is still in flight
      break;
    }
  }
  const ProcessResult r = proc.get();
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("is calibrated for 640x480 but frames are 64x48"), std::string::npos)
      << r.output;
  // Normally all six arrive 50 ms apart. A machine so loaded that the node falls a whole period
  // behind makes it skip to the newest due frame: then every frame still tells which image it
  // is ("seq") and how many were skipped before it ("skipped").
  ASSERT_GE(got.size(), 2u) << r.output;
  EXPECT_EQ(metadata_int(got.front(), "seq"), 0);
  for (size_t i = 0; i < got.size(); ++i) {
    const image_t& m = got[i];
    const int64_t seq = metadata_int(m, "seq").value_or(-1);
    ASSERT_GE(seq, 0);
    EXPECT_EQ(m.pixelformat, image_t::PIXEL_FORMAT_GRAY);
    EXPECT_EQ(m.width, 64);
    EXPECT_EQ(metadata_int(m, "dropped"), 0);
    EXPECT_EQ(metadata_int(m, "skipped"), seq - static_cast<int64_t>(i));
    ASSERT_EQ(m.data.size(), 64u * 48u);
    EXPECT_EQ(m.data[100], 20 * seq + 10);
    EXPECT_GE(m.utime, start);
    EXPECT_LE(m.utime, wall_utime());
    if (i > 0) {
      EXPECT_GT(seq, metadata_int(got[i - 1], "seq").value_or(-1));
      EXPECT_GT(m.utime, got[i - 1].utime);
    }
  }
  // Played at 20 Hz: frame k is stamped no earlier than its due time k * 50 ms and, unless
  // skipped, less than 50 ms after it.
  const int64_t span_seq = metadata_int(got.back(), "seq").value_or(0);
  EXPECT_GE(got.back().utime - got.front().utime, 50000 * (span_seq - 1));
}

TEST(CalibrateNodeTest, WritesCameraInfoFromAFolderOfBoardImages) {
  const std::string dir = tmp_dir("calib");
  const cv::Matx33d K(666.0, 0, 322.0, 0, 660.0, 241.0, 0, 0, 1);
  ChessboardParams board;
  board.inner_cols = 8;
  board.inner_rows = 5;
  board.square_m = 0.03;
  int i = 0;
  for (const auto& pose : testing::calibration_poses())
    cv::imwrite(dir + "/view_" + std::to_string(10 + i++) + ".png",
                testing::render_chessboard(K, board, pose, cv::Size(640, 480)));
  const std::string out = dir + "/out/rendered.yaml";
  fs::create_directories(dir + "/out");
  const ProcessResult r =
      run(kBin + "alight-calibrate --images " + dir + " --board 8x5 --square 0.03 --output " + out);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("RMS reprojection error"), std::string::npos) << r.output;
  const CameraModel cam = load_camera_info(out);
  EXPECT_EQ(cam.name, "rendered");
  EXPECT_NEAR(cam.fx, 666.0, 0.005 * 666.0);
  EXPECT_NEAR(cam.fy, 660.0, 0.005 * 660.0);
  EXPECT_NEAR(cam.cx, 322.0, 0.005 * 322.0);
  EXPECT_NEAR(cam.cy, 241.0, 0.005 * 241.0);

  const ProcessResult bad =
      run(kBin + "alight-calibrate --images " + dir + " --board 9x6 --output " + out);
  EXPECT_EQ(bad.code, 1) << bad.output;
  EXPECT_NE(bad.output.find("found in 0 of 12"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace alight::camera
