// Timestamps, device specs, parameters, pacing of stored sources and the --list text.

#include <gtest/gtest.h>
#include <sys/time.h>

#include <filesystem>
#include <fstream>
#include <opencv2/videoio.hpp>

#include "camera_driver/device_list.hpp"
#include "camera_driver/device_select.hpp"
#include "camera_driver/params.hpp"
#include "camera_driver/stored_source.hpp"
#include "camera_driver/timestamp.hpp"
#include "common/build_paths.hpp"
#include "common/params.hpp"
#include "fake_v4l2.hpp"

namespace alight::camera {
namespace {

TEST(TimestampTest, OffsetComesFromTheNarrowestBracketAtItsMidpoint) {
  const std::vector<ClockSample> samples = {
      {1000, 5'000'000'000'100, 1300},  // preempted: 300 us bracket
      {2000, 5'000'000'001'010, 2020},  // 20 us bracket: unix read at mono 2010
      {3000, 5'000'000'002'500, 3100},
  };
  EXPECT_EQ(clock_offset_us(samples), 5'000'000'001'010 - 2010);
}

TEST(TimestampTest, BufferTimeMovesToMidExposureAndKeepsFrameIntervals) {
  timeval tv{};
  tv.tv_sec = 12;
  tv.tv_usec = 345678;
  EXPECT_EQ(timeval_us(tv), 12'345'678);
  const int64_t offset = 1'700'000'000'000'000;
  EXPECT_EQ(exposure_utime(12'345'678, offset, StampSource::kStartOfExposure, 10'000),
            offset + 12'350'678);
  EXPECT_EQ(exposure_utime(12'345'678, offset, StampSource::kEndOfFrame, 10'000),
            offset + 12'340'678);
  EXPECT_EQ(exposure_utime(12'345'678, offset, StampSource::kEndOfFrame, -1), offset + 12'345'678);
  // A fixed offset: the Unix interval between two frames is exactly the kernel's.
  EXPECT_EQ(exposure_utime(2'016'667, offset, StampSource::kStartOfExposure, 8000) -
                exposure_utime(2'000'000, offset, StampSource::kStartOfExposure, 8000),
            16'667);
  EXPECT_EQ(stamp_source_from_flags(V4L2_BUF_FLAG_TSTAMP_SRC_SOE), StampSource::kStartOfExposure);
  EXPECT_EQ(stamp_source_from_flags(V4L2_BUF_FLAG_TSTAMP_SRC_EOF), StampSource::kEndOfFrame);
}

TEST(DeviceSpecTest, ParsesPathsAndUsbIdentities) {
  std::string err;
  auto p = parse_device_spec("/dev/video2", &err);
  ASSERT_TRUE(p);
  EXPECT_FALSE(p->usb);
  EXPECT_EQ(p->path, "/dev/video2");
  auto u = parse_device_spec("usb:1E10:2004:0123abc", &err);
  ASSERT_TRUE(u);
  EXPECT_TRUE(u->usb);
  EXPECT_EQ(u->vendor_id, 0x1e10);
  EXPECT_EQ(u->product_id, 0x2004);
  EXPECT_EQ(u->serial, "0123abc");
  EXPECT_EQ(u->text(), "usb:1e10:2004:0123abc");
  EXPECT_TRUE(parse_device_spec("usb:046d:0825", &err)->serial.empty());
  for (const char* bad : {"video0", "usb:1e10", "usb:xyz:2004", "usb:12345:1", ""}) {
    EXPECT_FALSE(parse_device_spec(bad, &err)) << bad;
    EXPECT_NE(err.find("usb:VENDOR:PRODUCT"), std::string::npos);
  }
}

TEST(DeviceSpecTest, UnknownUsbCameraIsNotFound) {
  const std::vector<VideoNode> nodes = {{"/dev/video0", "x", true, 0x046d, 0x0825, "A", 1, 2}};
  const Candidates c = candidate_nodes(*parse_device_spec("usb:1e10:2004", nullptr), nodes);
  EXPECT_TRUE(c.nodes.empty());
  EXPECT_NE(c.error.find("no V4L2 device"), std::string::npos);
  const Candidates wrong_serial =
      candidate_nodes(*parse_device_spec("usb:046d:0825:B", nullptr), nodes);
  EXPECT_TRUE(wrong_serial.nodes.empty());
}

// One folder per test: CTest runs the cases of this file in parallel, and a shared cam.yaml let
// one case read the file another was writing (a CI failure of ErrorsNameFileKeyAndValue).
struct ParamsTest : ::testing::Test {
  std::string dir = std::string(alight::build::binary_dir()) + "/test_tmp/camera_params/" +
                    ::testing::UnitTest::GetInstance()->current_test_info()->name();
  std::string write(const std::string& text) {
    std::filesystem::create_directories(dir);
    const std::string path = dir + "/cam.yaml";
    std::ofstream(path) << text;
    return path;
  }
};

TEST_F(ParamsTest, ShippedExampleConfigsLoad) {
  for (const char* f : {"usb_mono_640x480.yaml", "uvc_webcam_yuyv.yaml"}) {
    const std::string path = std::string(alight::build::source_dir()) + "/config/cameras/" + f;
    const CameraParams p = load_params(path);
    EXPECT_TRUE(std::filesystem::exists(p.camera_info)) << p.camera_info;
    const CaptureConfig c = capture_config(p);
    EXPECT_EQ(c.width, 640);
  }
}

TEST_F(ParamsTest, ReadsEveryFieldAndResolvesCameraInfoNextToTheFile) {
  const CameraParams p = load_params(
      write("device: usb:1e10:2004:FF01\npixel_format: MJPEG\noutput_encoding: rgb8\nwidth: 1280\n"
            "height: 720\nfps: 15\nexposure_us: 5000\ngain: 12\nbuffer_count: 6\n"
            "camera_info: intrinsics.yaml\nchannel: CAMERA_FWD\nbackoff_initial_s: 0.5\n"
            "backoff_max_s: 4\nstall_timeout_s: 3\nusb_reset_on_stall: false\n"));
  EXPECT_EQ(p.camera_info, dir + "/intrinsics.yaml");
  EXPECT_EQ(p.channel, "CAMERA_FWD");
  const CaptureConfig c = capture_config(p);
  EXPECT_TRUE(c.device.usb);
  EXPECT_EQ(c.device.serial, "FF01");
  EXPECT_EQ(c.format, PixelFormat::kMjpeg);
  EXPECT_EQ(c.encoding, OutputEncoding::kRgb8);
  EXPECT_EQ(c.fps, 15.0);
  EXPECT_EQ(c.exposure_us, 5000);
  EXPECT_EQ(c.gain, 12);
  EXPECT_EQ(c.buffer_count, 6);
  const SupervisorParams s = supervisor_params(p);
  EXPECT_EQ(s.backoff_initial_s, 0.5);
  EXPECT_FALSE(s.usb_reset_on_stall);
}

TEST_F(ParamsTest, ErrorsNameFileKeyAndValue) {
  struct Case {
    const char* yaml;
    const char* key;
  };
  for (const Case& c :
       {Case{"pixel_format: NV12\n", "pixel_format"}, Case{"device: video0\n", "device"},
        Case{"fps: 0\n", "fps"}, Case{"pixel_format: YUYV\nwidth: 641\n", "width"},
        Case{"buffer_count: 1\n", "buffer_count"}, Case{"exposure_us: 0\n", "exposure_us"},
        Case{"backoff_max_s: 0.01\n", "backoff_max_s"}, Case{"widht: 640\n", "widht"},
        Case{"width: wide\n", "width"}}) {
    const std::string path = write(c.yaml);
    try {
      load_params(path);
      ADD_FAILURE() << "accepted: " << c.yaml;
    } catch (const ParamError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_EQ(e.key(), c.key) << e.what();
    }
  }
}

TEST_F(ParamsTest, InfiniteOrHugeTimeoutsAreRefusedNamingFileKeyAndValue) {
  // Regression (issue 14): `stall_timeout_s: .inf` loaded and switched stall detection off;
  // `backoff_max_s: 1e9` let a lost camera wait 30 years between attempts.
  struct Case {
    const char* yaml;
    const char* key;
    const char* value;
  };
  for (const Case& c :
       {Case{"stall_timeout_s: .inf\n", "stall_timeout_s", "inf"},
        Case{"stall_timeout_s: 61\n", "stall_timeout_s", "61"},
        Case{"backoff_max_s: 1e9\n", "backoff_max_s", "1e+09"},
        Case{"backoff_initial_s: .inf\nbackoff_max_s: .inf\n", "backoff_initial_s", "inf"},
        Case{"backoff_initial_s: .nan\n", "backoff_initial_s", "nan"}}) {
    const std::string path = write(c.yaml);
    try {
      load_params(path);
      ADD_FAILURE() << "accepted: " << c.yaml;
    } catch (const ParamError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_EQ(e.key(), c.key) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.value), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(load_params(write("stall_timeout_s: 60\nbackoff_max_s: 60\n")).stall_timeout_s, 60.0);
}

TEST(FramePacerTest, PlaysAtItsRateAndSkipsToTheNewestWhenBehind) {
  FramePacer pacer(10.0, 1'000'000);  // 100 ms period from t = 1 s
  auto p = pacer.plan(1'000'000);
  EXPECT_EQ(p.skip, 0);
  EXPECT_EQ(p.wait_us, 0);
  p = pacer.plan(1'030'000);  // frame 1 due at 1.1 s
  EXPECT_EQ(p.skip, 0);
  EXPECT_EQ(p.wait_us, 70'000);
  p = pacer.plan(1'450'000);  // frames 2 and 3 are late; 4 is the newest due
  EXPECT_EQ(p.skip, 2);
  EXPECT_EQ(p.wait_us, 0);
  EXPECT_EQ(pacer.index(), 5);
  p = pacer.plan(1'460'000);
  EXPECT_EQ(p.wait_us, 40'000);
}

TEST(StoredSourceTest, VideoFileFramesComeBackInOrderAtTheFilesRate) {
  const std::string dir = std::string(alight::build::binary_dir()) + "/test_tmp/camera_stored";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/clip.avi";
  {
    cv::VideoWriter w(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25.0, cv::Size(64, 48));
    ASSERT_TRUE(w.isOpened());
    for (int i = 0; i < 5; ++i) w.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar::all(40 * i + 20)));
  }
  std::string err;
  const auto spec = parse_source("file:" + path, &err);
  ASSERT_TRUE(spec) << err;
  auto src = StoredSource::open(*spec, OutputEncoding::kMono8, &err);
  ASSERT_TRUE(src) << err;
  EXPECT_DOUBLE_EQ(src->fps(), 25.0);
  EXPECT_EQ(src->frame_count(), 5);
  for (int i = 0; i < 5; ++i) {
    if (i == 2) {
      ASSERT_TRUE(src->skip());
      continue;
    }
    const auto f = src->next(&err);
    ASSERT_TRUE(f) << i;
    EXPECT_EQ(f->type(), CV_8UC1);
    EXPECT_NEAR(f->at<uint8_t>(24, 32), 40 * i + 20, 3) << i;  // JPEG quantisation
  }
  EXPECT_FALSE(src->next(&err));
  EXPECT_TRUE(err.empty());
  ASSERT_TRUE(src->rewind());
  EXPECT_NEAR(src->next(&err)->at<uint8_t>(0, 0), 20, 3);
  EXPECT_FALSE(StoredSource::open(SourceSpec{SourceSpec::Kind::kVideoFile, dir + "/none.avi"},
                                  OutputEncoding::kMono8, &err));
  EXPECT_NE(err.find("no such video file"), std::string::npos);
}

TEST(DeviceListTest, SaysSoWhenThereIsNoCamera) {
  testing::FakeV4l2 io;
  EXPECT_EQ(list_cameras(io), "no USB cameras found\n");
}

TEST(DeviceListTest, ShowsIdentityNodeAndModes) {
  testing::FakeV4l2 io;
  testing::FakeV4l2::Device d;
  d.card = "Mono Cam";
  d.formats = {testing::FakeFormat{V4L2_PIX_FMT_GREY, {{640, 480}, {320, 240}}}};
  d.fps = 60;
  d.node = VideoNode{"/dev/video0", "Mono Cam", true, 0x1e10, 0x2004, "0042", 3, 9};
  io.add_device(d);
  const std::string text = list_cameras(io);
  EXPECT_NE(text.find("1e10:2004:0042"), std::string::npos) << text;
  EXPECT_NE(text.find("/dev/video0"), std::string::npos) << text;
  EXPECT_NE(text.find("GREY 640x480 @ 60 fps"), std::string::npos) << text;
  EXPECT_NE(text.find("GREY 320x240"), std::string::npos) << text;
  EXPECT_EQ(io.open_descriptors(), 0);
}

}  // namespace
}  // namespace alight::camera
