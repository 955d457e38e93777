// The real V4L2 capture code against the scripted kernel device (fake_v4l2.hpp).

#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <cerrno>

#include "camera_driver/v4l2_capture.hpp"
#include "fake_v4l2.hpp"

namespace alight::camera {
namespace {

using testing::FakeFormat;
using testing::FakeV4l2;

CaptureConfig grey_config(const std::string& path = "/dev/video0") {
  CaptureConfig c;
  c.device.path = path;
  c.format = PixelFormat::kGrey;
  c.width = 640;
  c.height = 480;
  c.fps = 30;
  return c;
}

// A frame whose every pixel holds `value`, so a published frame tells which one it was.
std::vector<uint8_t> flat(int w, int h, uint8_t value) {
  return std::vector<uint8_t>(static_cast<size_t>(w) * h, value);
}

struct CaptureTest : ::testing::Test {
  FakeV4l2 io;
  int dev = -1;
  void SetUp() override { dev = io.add_device(FakeV4l2::Device{}); }
};

TEST_F(CaptureTest, StreamsFramesInOrderWithKernelTimestampsAndSequence) {
  V4l2Capture cap(io, grey_config());
  ASSERT_TRUE(cap.open().ok());
  EXPECT_TRUE(io.streaming(dev));
  EXPECT_EQ(cap.format().buffers, 4);
  EXPECT_EQ(io.queued(dev), 4);  // every buffer handed to the driver
  for (int i = 0; i < 10; ++i) {
    ASSERT_TRUE(
        io.emit_frame(dev, 1'000'000 + i * 33'333, flat(640, 480, static_cast<uint8_t>(i))));
    GrabResult g = cap.grab(100);
    ASSERT_EQ(g.status, GrabStatus::kFrame) << g.message;
    EXPECT_EQ(g.frame->sequence, static_cast<uint32_t>(i));
    EXPECT_EQ(g.frame->buffer_mono_us, 1'000'000 + i * 33'333);
    EXPECT_EQ(g.frame->stamp_source, StampSource::kStartOfExposure);
    EXPECT_TRUE(g.frame->monotonic_clock);
    EXPECT_EQ(g.frame->dropped, 0u);
    EXPECT_EQ(g.frame->pixels.at<uint8_t>(240, 320), i);
    EXPECT_EQ(io.queued(dev), 4);  // the buffer went straight back to the driver
  }
  EXPECT_EQ(cap.counters().frames, 10u);
}

TEST_F(CaptureTest, NothingCompletedIsATimeoutAndSpuriousWakeupsAreHarmless) {
  V4l2Capture cap(io, grey_config());
  ASSERT_TRUE(cap.open().ok());
  EXPECT_EQ(cap.grab(10).status, GrabStatus::kTimeout);
  io.spurious_wakeups(dev, 2);  // poll says readable, DQBUF says EAGAIN
  EXPECT_EQ(cap.grab(10).status, GrabStatus::kTimeout);
  EXPECT_EQ(cap.grab(10).status, GrabStatus::kTimeout);
  EXPECT_EQ(cap.counters().empty_wakeups, 2u);
  io.emit_frame(dev, 5000, flat(640, 480, 7));
  EXPECT_EQ(cap.grab(10).status, GrabStatus::kFrame);
}

TEST_F(CaptureTest, DriverChangesTheSizeAndFramesComeInTheNegotiatedSize) {
  FakeV4l2 io2;
  FakeV4l2::Device d;
  d.formats = {FakeFormat{V4L2_PIX_FMT_YUYV, {{320, 240}, {752, 480}}}};
  const int k = io2.add_device(d);
  CaptureConfig c = grey_config();
  c.format = PixelFormat::kYuyv;
  V4l2Capture cap(io2, c);
  ASSERT_TRUE(cap.open().ok());
  EXPECT_EQ(cap.format().width, 752);
  EXPECT_EQ(cap.format().height, 480);
  EXPECT_EQ(cap.format().stride, 752 * 2);
  ASSERT_FALSE(cap.warnings().empty());
  EXPECT_NE(cap.warnings().front().find("752x480"), std::string::npos);
  std::vector<uint8_t> yuyv(752 * 2 * 480);
  for (size_t i = 0; i < yuyv.size(); i += 2) yuyv[i] = 90, yuyv[i + 1] = 128;
  io2.emit_frame(k, 1000, yuyv);
  GrabResult g = cap.grab(10);
  ASSERT_EQ(g.status, GrabStatus::kFrame) << g.message;
  EXPECT_EQ(g.frame->pixels.cols, 752);
  EXPECT_EQ(g.frame->pixels.rows, 480);
  EXPECT_EQ(g.frame->pixels.at<uint8_t>(100, 700), 90);
}

TEST_F(CaptureTest, AFormatTheCameraDoesNotOfferIsRejectedNamingWhatItOffers) {
  CaptureConfig c = grey_config();
  c.format = PixelFormat::kMjpeg;  // the default fake offers GREY only; S_FMT substitutes it
  V4l2Capture cap(io, c);
  const Status s = cap.open();
  EXPECT_EQ(s.error, CaptureError::kFormatRejected);
  EXPECT_NE(s.message.find("offered: GREY"), std::string::npos) << s.message;
  EXPECT_EQ(io.open_descriptors(), 0);
}

TEST_F(CaptureTest, SequenceGapIsCountedAsKernelDrops) {
  V4l2Capture cap(io, grey_config());
  ASSERT_TRUE(cap.open().ok());
  io.emit_frame(dev, 1000, flat(640, 480, 1));
  ASSERT_EQ(cap.grab(10).status, GrabStatus::kFrame);
  io.lose_frames(dev, 3);  // the driver discards three frames (e.g. USB bandwidth)
  io.emit_frame(dev, 134'000, flat(640, 480, 2));
  GrabResult g = cap.grab(10);
  ASSERT_EQ(g.status, GrabStatus::kFrame);
  EXPECT_EQ(g.frame->sequence, 4u);
  EXPECT_EQ(g.frame->dropped, 3u);
  EXPECT_EQ(g.frame->skipped, 0u);
  EXPECT_EQ(cap.counters().dropped, 3u);
}

TEST_F(CaptureTest, FramesLostForWantOfBuffersShowAsDroppedOnTheNextFrame) {
  CaptureConfig c = grey_config();
  c.buffer_count = 2;
  V4l2Capture cap(io, c);
  ASSERT_TRUE(cap.open().ok());
  // Two frames fill both buffers, three more find no buffer (the kernel drops them).
  for (int i = 0; i < 5; ++i)
    io.emit_frame(dev, 1000 + i * 1000, flat(640, 480, static_cast<uint8_t>(i)));
  GrabResult g = cap.grab(10);
  ASSERT_EQ(g.status, GrabStatus::kFrame);
  EXPECT_EQ(g.frame->sequence, 1u);  // the newest completed one
  EXPECT_EQ(g.frame->skipped, 1u);   // sequence 0 was superseded
  EXPECT_EQ(g.frame->dropped, 0u);
  io.emit_frame(dev, 9000, flat(640, 480, 9));  // sequence 5
  g = cap.grab(10);
  ASSERT_EQ(g.status, GrabStatus::kFrame);
  EXPECT_EQ(g.frame->sequence, 5u);
  EXPECT_EQ(g.frame->dropped, 3u);  // 2, 3, 4 never reached a buffer
  EXPECT_EQ(g.frame->pixels.at<uint8_t>(0, 0), 9);
  EXPECT_EQ(cap.counters().dropped, 3u);
  EXPECT_EQ(cap.counters().skipped, 1u);
}

TEST_F(CaptureTest, WhenBehindTheNewestFrameIsReturnedAndOlderOnesNeverLater) {
  V4l2Capture cap(io, grey_config());
  ASSERT_TRUE(cap.open().ok());
  for (int i = 0; i < 3; ++i)
    io.emit_frame(dev, 1000 + i * 33'333, flat(640, 480, static_cast<uint8_t>(10 + i)));
  GrabResult g = cap.grab(10);
  ASSERT_EQ(g.status, GrabStatus::kFrame);
  EXPECT_EQ(g.frame->pixels.at<uint8_t>(0, 0), 12);
  EXPECT_EQ(g.frame->sequence, 2u);
  EXPECT_EQ(g.frame->skipped, 2u);
  EXPECT_EQ(io.queued(dev), 4);  // the skipped buffers were requeued, not leaked
  // Nothing new: the skipped frames must not surface now as if they were new.
  EXPECT_EQ(cap.grab(10).status, GrabStatus::kTimeout);
  io.emit_frame(dev, 200'000, flat(640, 480, 20));
  g = cap.grab(10);
  ASSERT_EQ(g.status, GrabStatus::kFrame);
  EXPECT_EQ(g.frame->pixels.at<uint8_t>(0, 0), 20);
  EXPECT_EQ(g.frame->skipped, 0u);
}

TEST_F(CaptureTest, ABufferStampedBeforeTheLastReturnedFrameIsNeverDeliveredAsNew) {
  V4l2Capture cap(io, grey_config());
  ASSERT_TRUE(cap.open().ok());
  io.emit_frame(dev, 500'000, flat(640, 480, 1));
  ASSERT_EQ(cap.grab(10).status, GrabStatus::kFrame);
  io.emit_frame(dev, 400'000,
                flat(640, 480, 2));  // a stale buffer (e.g. left from before a restart)
  EXPECT_EQ(cap.grab(10).status, GrabStatus::kTimeout);
  EXPECT_EQ(cap.counters().stale, 1u);
  EXPECT_EQ(io.queued(dev), 4);
}

TEST_F(CaptureTest, ErrorFlaggedAndShortBuffersAreBadFramesAndTheStreamGoesOn) {
  V4l2Capture cap(io, grey_config());
  ASSERT_TRUE(cap.open().ok());
  io.emit_frame(dev, 1000, flat(640, 480, 1), /*error=*/true);
  EXPECT_EQ(cap.grab(10).status, GrabStatus::kBadFrame);
  io.emit_frame(dev, 2000, flat(640, 100, 1));  // bytesused far below 640x480
  GrabResult g = cap.grab(10);
  EXPECT_EQ(g.status, GrabStatus::kBadFrame);
  EXPECT_NE(g.message.find("needed"), std::string::npos) << g.message;
  io.emit_frame(dev, 3000, flat(640, 480, 3));
  EXPECT_EQ(cap.grab(10).status, GrabStatus::kFrame);
  EXPECT_EQ(cap.counters().bad_frames, 2u);
  EXPECT_EQ(io.queued(dev), 4);
}

TEST_F(CaptureTest, UnplugIsDeviceLostAndCloseReleasesEverything) {
  V4l2Capture cap(io, grey_config());
  ASSERT_TRUE(cap.open().ok());
  EXPECT_EQ(io.mapped_buffers(), 4);
  io.unplug(dev);
  GrabResult g = cap.grab(10);
  EXPECT_EQ(g.status, GrabStatus::kDeviceLost);
  EXPECT_NE(g.message.find("disconnected"), std::string::npos) << g.message;
  cap.close();
  EXPECT_EQ(io.mapped_buffers(), 0);
  EXPECT_EQ(io.open_descriptors(), 0);
  EXPECT_EQ(cap.open().error, CaptureError::kNotFound);
  io.replug(dev);
  ASSERT_TRUE(cap.open().ok());
  io.emit_frame(dev, 10'000'000, flat(640, 480, 5));
  GrabResult g2 = cap.grab(10);
  ASSERT_EQ(g2.status, GrabStatus::kFrame);
  EXPECT_EQ(g2.frame->sequence, 0u);  // a new stream counts from 0 again
  EXPECT_EQ(g2.frame->dropped, 0u);
}

TEST_F(CaptureTest, OpenErrorsAreClassifiedWithAdvice) {
  struct Case {
    int open_errno, reqbufs_errno;
    CaptureError expected;
    const char* advice;
  };
  for (const Case& c : {Case{EBUSY, 0, CaptureError::kBusy, "another process"},
                        Case{0, EBUSY, CaptureError::kBusy, "another process"},
                        Case{EACCES, 0, CaptureError::kPermissionDenied, "group 'video'"}}) {
    FakeV4l2 io2;
    FakeV4l2::Device d;
    d.open_errno = c.open_errno;
    d.reqbufs_errno = c.reqbufs_errno;
    io2.add_device(d);
    V4l2Capture cap(io2, grey_config());
    const Status s = cap.open();
    EXPECT_EQ(s.error, c.expected) << s.message;
    EXPECT_NE(s.message.find("/dev/video0"), std::string::npos) << s.message;
    EXPECT_NE(s.message.find(c.advice), std::string::npos) << s.message;
    EXPECT_EQ(io2.open_descriptors(), 0);
    EXPECT_EQ(io2.mapped_buffers(), 0);
  }
  V4l2Capture missing(io, grey_config("/dev/video7"));
  const Status s = missing.open();
  EXPECT_EQ(s.error, CaptureError::kNotFound);
  EXPECT_NE(s.message.find("--list"), std::string::npos) << s.message;
}

TEST_F(CaptureTest, AMetadataNodeIsNotACaptureDevice) {
  FakeV4l2 io2;
  FakeV4l2::Device d;
  d.device_caps = V4L2_CAP_META_CAPTURE | V4L2_CAP_STREAMING;
  io2.add_device(d);
  V4l2Capture cap(io2, grey_config());
  EXPECT_EQ(cap.open().error, CaptureError::kNotCapture);
}

TEST_F(CaptureTest, UsbSpecPicksTheCaptureNodeOfTheMatchingCamera) {
  FakeV4l2 io2;
  auto usb_dev = [](const std::string& path, uint32_t caps, const std::string& serial, int addr) {
    FakeV4l2::Device d;
    d.path = path;
    d.device_caps = caps;
    d.node = VideoNode{path, "cam", true, 0x046d, 0x0825, serial, 1, addr};
    return d;
  };
  const uint32_t meta = V4L2_CAP_META_CAPTURE | V4L2_CAP_STREAMING;
  const uint32_t video = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  io2.add_device(usb_dev("/dev/video0", video, "AAA", 4));
  io2.add_device(usb_dev("/dev/video1", meta, "AAA", 4));
  io2.add_device(usb_dev("/dev/video2", meta, "BBB", 5));  // metadata node listed first
  io2.add_device(usb_dev("/dev/video3", video, "BBB", 5));
  CaptureConfig c = grey_config();
  c.device = *parse_device_spec("usb:046d:0825:BBB", nullptr);
  V4l2Capture cap(io2, c);
  ASSERT_TRUE(cap.open().ok());
  EXPECT_EQ(cap.format().path, "/dev/video3");
  EXPECT_EQ(cap.node().usb_address, 5);
  cap.close();
  c.device = *parse_device_spec("usb:046d:0825", nullptr);  // two such cameras: ambiguous
  V4l2Capture amb(io2, c);
  const Status s = amb.open();
  EXPECT_EQ(s.error, CaptureError::kAmbiguous);
  EXPECT_NE(s.message.find("AAA"), std::string::npos) << s.message;
  EXPECT_NE(s.message.find("BBB"), std::string::npos) << s.message;
}

TEST_F(CaptureTest, ExposureAndGainAreSetThroughControls) {
  CaptureConfig c = grey_config();
  c.exposure_us = 8000;
  c.gain = 300;  // above the fake's 255: clamped with a warning
  V4l2Capture cap(io, c);
  ASSERT_TRUE(cap.open().ok());
  const auto ctrls = io.controls(dev);
  EXPECT_EQ(ctrls.at(V4L2_CID_EXPOSURE_AUTO), V4L2_EXPOSURE_MANUAL);
  EXPECT_EQ(ctrls.at(V4L2_CID_EXPOSURE_ABSOLUTE), 80);  // 100 us units
  EXPECT_EQ(cap.exposure_us(), 8000);                   // what frames will say they had
  EXPECT_EQ(ctrls.at(V4L2_CID_GAIN), 255);
  bool clamped = false, no_autogain = false;
  for (const auto& w : cap.warnings()) {
    clamped = clamped || w.find("gain 300") != std::string::npos;
    no_autogain = no_autogain || w.find("autogain") != std::string::npos;
  }
  EXPECT_TRUE(clamped);
  EXPECT_TRUE(no_autogain);
}

// A frame says how long it was exposed only when the camera was set to that: on automatic
// exposure, or without the controls, the vision assumes its own figure.
TEST_F(CaptureTest, ExposureIsKnownOnlyWhenManualExposureWasSet) {
  V4l2Capture automatic(io, grey_config());  // exposure_us -1
  ASSERT_TRUE(automatic.open().ok());
  EXPECT_EQ(automatic.exposure_us(), std::nullopt);
  automatic.close();

  FakeV4l2 io2;
  FakeV4l2::Device d;
  d.has_exposure = false;
  io2.add_device(d);
  CaptureConfig c = grey_config();
  c.exposure_us = 8000;
  V4l2Capture without(io2, c);
  ASSERT_TRUE(without.open().ok());  // still streams, with a warning
  EXPECT_EQ(without.exposure_us(), std::nullopt);

  c.exposure_us = 900'000;  // beyond the fake's 5000 units: clamped, and the clamped value said
  V4l2Capture clamped(io, c);
  ASSERT_TRUE(clamped.open().ok());
  EXPECT_EQ(clamped.exposure_us(), 500'000);
}

TEST_F(CaptureTest, ListsModesOfAnOpenDevice) {
  FakeV4l2 io2;
  FakeV4l2::Device d;
  d.formats = {FakeFormat{V4L2_PIX_FMT_YUYV, {{640, 480}, {320, 240}}},
               FakeFormat{V4L2_PIX_FMT_MJPEG, {{1280, 720}}}};
  io2.add_device(d);
  const int fd = io2.open("/dev/video0", 0);
  const auto modes = enumerate_modes(io2, fd);
  io2.close(fd);
  ASSERT_EQ(modes.size(), 3u);
  EXPECT_EQ(modes[0].fourcc, V4L2_PIX_FMT_YUYV);
  EXPECT_EQ(modes[1].width, 320);
  EXPECT_EQ(modes[2].height, 720);
  ASSERT_EQ(modes[2].fps.size(), 1u);
  EXPECT_DOUBLE_EQ(modes[2].fps[0], 30.0);
}

}  // namespace
}  // namespace alight::camera
