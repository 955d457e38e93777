// Reconnect and stall handling, stepped through simulated time against the scripted device.

#include "camera_driver/supervisor.hpp"

#include <gtest/gtest.h>

#include "camera_driver/frame_label.hpp"
#include "fake_v4l2.hpp"

namespace alight::camera {
namespace {

using testing::FakeV4l2;

bool mentions(const std::vector<std::string>& events, const std::string& word) {
  for (const auto& e : events)
    if (e.find(word) != std::string::npos) return true;
  return false;
}

struct SupervisorTest : ::testing::Test {
  FakeV4l2 io;
  int dev = -1;
  CaptureConfig config;
  SupervisorParams params;
  std::vector<uint8_t> frame = std::vector<uint8_t>(640 * 480, 50);
  void SetUp() override {
    FakeV4l2::Device d;
    d.node = VideoNode{"/dev/video0", "cam", true, 0x1e10, 0x2004, "FF01", 2, 7};
    dev = io.add_device(d);
    config.device = *parse_device_spec("usb:1e10:2004", nullptr);
    params.backoff_initial_s = 0.1;
    params.backoff_max_s = 1.0;
    params.stall_timeout_s = 2.0;
  }
};

TEST_F(SupervisorTest, UnpluggedCameraIsReconnectedWithGrowingBackoffInsteadOfExiting) {
  CameraSupervisor sup(io, config, params);
  int64_t t = 0;
  ASSERT_TRUE(sup.start(t).ok());
  io.emit_frame(dev, 1000, frame);
  ASSERT_TRUE(sup.step(t).frame.has_value());

  io.unplug(dev);
  CameraSupervisor::Step s = sup.step(t);
  EXPECT_FALSE(s.frame);
  EXPECT_TRUE(mentions(s.events, "disconnected")) << s.events.front();
  EXPECT_EQ(sup.state(), CameraSupervisor::State::kReconnecting);
  EXPECT_EQ(io.open_descriptors(), 0);
  EXPECT_EQ(io.mapped_buffers(), 0);

  // Attempts while the cable is out: immediately, then after 0.1, 0.2, 0.4, 0.8, 1.0, 1.0 s.
  std::vector<int64_t> waits;
  for (int i = 0; i < 7; ++i) {
    s = sup.step(t);
    ASSERT_TRUE(mentions(s.events, "reconnect failed"));
    waits.push_back(s.sleep_us);
    // Stepping before the attempt is due only reports the time left.
    const CameraSupervisor::Step early = sup.step(t + s.sleep_us / 2);
    EXPECT_TRUE(early.events.empty());
    EXPECT_EQ(early.sleep_us, s.sleep_us - s.sleep_us / 2);
    t += s.sleep_us;
  }
  EXPECT_EQ(waits,
            (std::vector<int64_t>{100000, 200000, 400000, 800000, 1000000, 1000000, 1000000}));

  io.replug(dev);
  s = sup.step(t);
  EXPECT_TRUE(mentions(s.events, "reconnected"));
  EXPECT_EQ(sup.state(), CameraSupervisor::State::kStreaming);
  EXPECT_EQ(sup.reconnects(), 1u);
  io.emit_frame(dev, 9'000'000, frame);
  s = sup.step(t);
  ASSERT_TRUE(s.frame);
  EXPECT_EQ(s.frame->sequence, 0u);
  EXPECT_EQ(io.open_descriptors(), 1);
  EXPECT_EQ(io.mapped_buffers(), 4);

  // A second loss starts the backoff from the beginning again.
  io.unplug(dev);
  sup.step(t);
  s = sup.step(t);
  EXPECT_EQ(s.sleep_us, 100000);
}

TEST_F(SupervisorTest, StalledUsbCameraIsResetThroughLibusbAndReopened) {
  CameraSupervisor sup(io, config, params);
  int64_t t = 0;
  ASSERT_TRUE(sup.start(t).ok());
  io.emit_frame(dev, 1000, frame);
  ASSERT_TRUE(sup.step(t).frame);
  // The camera stops delivering. Silence up to the stall timeout is tolerated.
  for (t = 100'000; t <= 2'000'000; t += 100'000) {
    const auto s = sup.step(t);
    EXPECT_FALSE(s.frame);
    EXPECT_TRUE(s.events.empty());
  }
  auto s = sup.step(2'100'000);
  EXPECT_TRUE(mentions(s.events, "stalled"));
  EXPECT_EQ(io.resets(), 0);
  s = sup.step(2'100'000);
  EXPECT_EQ(io.resets(), 1);
  EXPECT_TRUE(mentions(s.events, "USB reset"));
  EXPECT_TRUE(mentions(s.events, "reconnected"));
  EXPECT_EQ(sup.usb_resets(), 1u);
  io.emit_frame(dev, 3'000'000, frame);
  EXPECT_TRUE(sup.step(2'200'000).frame);
}

TEST_F(SupervisorTest, APathDeviceIsNotResetOnStallButReopened) {
  FakeV4l2 plain;
  const int d = plain.add_device(FakeV4l2::Device{});
  CaptureConfig c;
  c.device.path = "/dev/video0";
  CameraSupervisor sup(plain, c, params);
  ASSERT_TRUE(sup.start(0).ok());
  auto s = sup.step(2'500'000);
  EXPECT_TRUE(mentions(s.events, "stalled"));
  s = sup.step(2'500'000);
  EXPECT_EQ(plain.resets(), 0);
  EXPECT_EQ(sup.state(), CameraSupervisor::State::kStreaming);
  plain.emit_frame(d, 3'000'000, frame);
  EXPECT_TRUE(sup.step(2'600'000).frame);
}

TEST_F(SupervisorTest, PublishedSequenceKeepsIncreasingAcrossAReconnect) {
  CameraSupervisor sup(io, config, params);
  const int64_t offset = 1'700'000'000'000'000;
  FrameLabeler labeler(offset, /*exposure_us=*/-1);
  ASSERT_TRUE(sup.start(0).ok());
  std::vector<int64_t> seqs, utimes;
  auto take = [&](int64_t t_us) {
    io.emit_frame(dev, t_us, frame);
    auto s = sup.step(t_us);
    ASSERT_TRUE(s.frame);
    const FrameLabel l = labeler.label(*s.frame, sup.reconnects(), t_us);
    seqs.push_back(l.seq);
    utimes.push_back(l.utime);
  };
  take(1'000'000);
  take(1'033'000);
  io.lose_frames(dev, 2);
  take(1'133'000);  // kernel sequence 4: two lost
  io.unplug(dev);
  sup.step(1'200'000);
  io.replug(dev);
  sup.step(1'200'000);
  ASSERT_EQ(sup.state(), CameraSupervisor::State::kStreaming);
  take(1'500'000);  // kernel sequence 0 again
  take(1'533'000);
  EXPECT_EQ(seqs, (std::vector<int64_t>{0, 1, 4, 5, 6}));
  EXPECT_EQ(utimes.front(), offset + 1'000'000);
  EXPECT_EQ(utimes.back(), offset + 1'533'000);
  EXPECT_FALSE(labeler.used_dequeue_time());
}

TEST_F(SupervisorTest, CameraDeliveringOnlyCorruptFramesIsDeclaredStalled) {
  // Regression (issue 14): only a poll timeout counted towards the stall, so a device whose
  // every buffer came back flagged V4L2_BUF_FLAG_ERROR streamed "bad frames" forever and was
  // never reopened. No good frame for stall_timeout_s is a stall, whatever the device says.
  CameraSupervisor sup(io, config, params);
  int64_t t = 0;
  ASSERT_TRUE(sup.start(t).ok());
  io.emit_frame(dev, 1000, frame);
  ASSERT_TRUE(sup.step(t).frame);
  bool stalled = false;
  for (t = 33'000; t <= 3'000'000 && !stalled; t += 33'000) {
    io.emit_frame(dev, t, frame, /*error=*/true);
    const auto s = sup.step(t);
    EXPECT_FALSE(s.frame);
    stalled = mentions(s.events, "stalled");
    if (stalled) {
      EXPECT_GT(t, 2'000'000);  // not before the timeout
      EXPECT_LE(t, 2'000'000 + 33'000);
    }
  }
  EXPECT_TRUE(stalled);
  EXPECT_EQ(sup.state(), CameraSupervisor::State::kReconnecting);
  // Reopened (after a USB reset), it streams again.
  sup.step(t);
  ASSERT_EQ(sup.state(), CameraSupervisor::State::kStreaming);
  EXPECT_EQ(io.resets(), 1);
  io.emit_frame(dev, t + 33'000, frame);
  EXPECT_TRUE(sup.step(t + 33'000).frame);
}

TEST_F(SupervisorTest, FramesStampedLowerAfterAReconnectAreDelivered) {
  // Regression (issue 14): the capture kept the newest timestamp it had returned across a
  // reopen, so after a reconnect whose timestamps restarted lower (a device with its own
  // clock, a USB re-enumeration) every frame was counted "stale" and dropped for good.
  CameraSupervisor sup(io, config, params);
  ASSERT_TRUE(sup.start(0).ok());
  io.emit_frame(dev, 50'000'000, frame);
  ASSERT_TRUE(sup.step(0).frame);
  io.unplug(dev);
  sup.step(100'000);
  io.replug(dev);
  sup.step(100'000);
  ASSERT_EQ(sup.state(), CameraSupervisor::State::kStreaming);
  for (int i = 0; i < 5; ++i) {
    const int64_t t = 200'000 + i * 33'000;
    io.emit_frame(dev, 1'000 + i * 33'000, frame);  // the new stream's clock started near 0
    const auto s = sup.step(t);
    ASSERT_TRUE(s.frame) << "frame " << i << " after the reconnect was dropped";
    EXPECT_EQ(s.frame->buffer_mono_us, 1'000 + i * 33'000);
  }
  EXPECT_EQ(sup.capture().counters().stale, 0u);
  // Within one stream, an older buffer is still never delivered as new.
  io.emit_frame(dev, 500, frame);
  EXPECT_FALSE(sup.step(400'000).frame);
  EXPECT_EQ(sup.capture().counters().stale, 1u);
}

TEST(FrameLabelerTest, MidExposureStampAndDequeueTimeFallback) {
  FrameLabeler labeler(1000, /*exposure_us=*/8000);
  Frame f;
  f.buffer_mono_us = 50'000;
  f.stamp_source = StampSource::kStartOfExposure;
  EXPECT_EQ(labeler.label(f, 0, 99'000).utime, 1000 + 54'000);
  f.monotonic_clock = false;  // e.g. V4L2_BUF_FLAG_TIMESTAMP_COPY from a capture card
  EXPECT_EQ(labeler.label(f, 0, 99'000).utime, 1000 + 99'000);
  EXPECT_TRUE(labeler.used_dequeue_time());
}

TEST(ReconnectBackoffTest, DoublesUpToTheCapAndResets) {
  ReconnectBackoff b(0.25, 2.0);
  EXPECT_EQ(b.next_delay_us(), 250000);
  EXPECT_EQ(b.next_delay_us(), 500000);
  EXPECT_EQ(b.next_delay_us(), 1000000);
  EXPECT_EQ(b.next_delay_us(), 2000000);
  EXPECT_EQ(b.next_delay_us(), 2000000);
  b.reset();
  EXPECT_EQ(b.next_delay_us(), 250000);
}

}  // namespace
}  // namespace alight::camera
