// alight-vision-eval's report on a session without truth (a real camera's): the stream, the
// exposure, the features, the reasons' hints (tools/vision_eval.hpp), and the tool itself over a
// log of a flight without motion capture.
#include "tools/vision_eval.hpp"

#include <gtest/gtest.h>

#include <alight/image_t.hpp>
#include <alight/pose_t.hpp>
#include <cstdio>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "common/build_paths.hpp"
#include "common/channels.hpp"
#include "common/image_msg.hpp"

namespace {

using alight::tools::EvalFrame;
using alight::vision::Reason;

TEST(VisionEvalExposureTest, LevelClippedAndBlackShares) {
  cv::Mat img(48, 48, CV_8UC1, cv::Scalar(0));
  img(cv::Rect(0, 0, 48, 12)).setTo(255);   // a quarter clipped
  img(cv::Rect(0, 12, 48, 12)).setTo(128);  // a quarter mid-grey, half black
  const alight::tools::Exposure e = alight::tools::measure_exposure(img);
  EXPECT_NEAR(e.clipped, 0.25, 0.02);
  EXPECT_NEAR(e.dark, 0.5, 1e-9);
  EXPECT_NEAR(e.level, (255 + 128) / 4.0, 2.0);
}

// 30 Hz with a jitter of 0.4 ms, one interval of three periods (two frames lost) and one stamp
// repeated: the report counts each.
TEST(VisionEvalSummaryTest, StreamGapsRepeatsAndJitter) {
  std::vector<EvalFrame> frames;
  int64_t t = 1'000'000;
  for (int i = 0; i < 60; ++i) {
    EvalFrame f;
    t += 33'333 + (i % 2 ? 400 : -400);
    if (i == 30) t += 2 * 33'333;          // two frames lost
    if (i == 40) t = frames.back().utime;  // the driver's stamp again
    f.utime = t;
    f.log_utime = t + 12'000;  // 12 ms from exposure to the recorder
    frames.push_back(f);
  }
  const alight::tools::EvalSummary s = alight::tools::summarize(frames);
  EXPECT_EQ(s.frames, 60u);
  EXPECT_NEAR(s.interval_ms, 33.3, 0.5);
  EXPECT_EQ(s.gaps, 1);
  EXPECT_EQ(s.missing_frames, 2);
  EXPECT_EQ(s.repeated_stamps, 1);
  EXPECT_NEAR(s.jitter_p99_ms, 0.8, 0.15);  // adjacent intervals differ by 0.8 ms
  EXPECT_NEAR(s.delay_ms.p50, 12.0, 1e-9);
  EXPECT_EQ(s.delay_ms.n, 60u);
}

TEST(VisionEvalSummaryTest, ExposureFeaturesPoseAndReasonsMostFrequentFirst) {
  std::vector<EvalFrame> frames;
  for (int i = 0; i < 20; ++i) {
    EvalFrame f;
    f.utime = 1'000'000 + i * 33'333;
    f.exposure.level = 100 + i;
    f.exposure.clipped = i < 3 ? 0.3 : 0.0;  // three frames over-exposed
    f.exposure.dark = i >= 18 ? 0.7 : 0.0;   // two under-exposed
    f.n_features = 100 + 10 * i;
    f.n_matches = 50 + 5 * i;
    f.has_pose = i != 0;
    f.reason = i < 10 ? Reason::kOk : (i < 16 ? Reason::kExposureChange : Reason::kTopTilted);
    f.n_inliers = 40;
    frames.push_back(f);
  }
  const alight::tools::EvalSummary s = alight::tools::summarize(frames);
  EXPECT_EQ(s.over_exposed, 3);
  EXPECT_EQ(s.under_exposed, 2);
  EXPECT_EQ(s.without_pose, 1);
  EXPECT_EQ(s.exposure_ms.n, 0u) << "the driver never said";
  EXPECT_EQ(s.features.p50, 200);
  EXPECT_EQ(s.features.max, 290);
  EXPECT_EQ(s.inliers.n, 10u) << "inliers over the found frames only";
  ASSERT_EQ(s.reasons.size(), 3u);
  EXPECT_EQ(s.reasons[0], std::make_pair(Reason::kOk, 10));
  EXPECT_EQ(s.reasons[1], std::make_pair(Reason::kExposureChange, 6));
  EXPECT_EQ(s.reasons[2], std::make_pair(Reason::kTopTilted, 4));

  const std::string text = alight::tools::format_summary(s);
  EXPECT_NE(text.find("exposure_ms (driver): not in the frames' metadata"), std::string::npos);
  EXPECT_NE(text.find("3 over-exposed"), std::string::npos) << text;
  EXPECT_NE(text.find("2 under-exposed"), std::string::npos) << text;
  // The camera's own reason comes with what to check; a geometric gate refers to its doc.
  EXPECT_NE(text.find(alight::tools::hint(Reason::kExposureChange)), std::string::npos) << text;
  EXPECT_EQ(alight::tools::hint(Reason::kTopTilted), nullptr);
}

TEST(VisionEvalSummaryTest, NoFramesIsAnEmptyReport) {
  EXPECT_EQ(alight::tools::format_summary(alight::tools::summarize({})), "frames: 0\n");
}

// The tool over a log as a flight without motion capture records it: frames from the camera with
// its exposure time, poses on ESTIMATE_POSE, no SIM_TRUTH. It takes the estimate's poses, says
// there is no truth, and reports the stream and the driver's exposure; without any pose channel
// every frame is kNoPose, with the hint to check the channel and the clocks.
class VisionEvalToolTest : public ::testing::Test {
 protected:
  std::string write_log(bool with_poses) {
    const std::string path = (std::filesystem::temp_directory_path() /
                              ("alight_vision_eval_test_" + std::to_string(with_poses) + ".lcmlog"))
                                 .string();
    lcm::LogFile log(path, "w");
    EXPECT_TRUE(log.good());
    cv::Mat texture(480, 640, CV_8UC1);
    cv::RNG rng(7);
    rng.fill(texture, cv::RNG::UNIFORM, 0, 256);
    cv::GaussianBlur(texture, texture, cv::Size(0, 0), 2.0);
    int64_t event = 0;
    const auto write = [&](const std::string& channel, const auto& msg, int64_t t) {
      std::vector<uint8_t> buf(static_cast<size_t>(msg.getEncodedSize()));
      msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
      lcm::LogEvent ev;
      ev.eventnum = event++;
      ev.timestamp = t;
      ev.channel = channel;
      ev.datalen = static_cast<int32_t>(buf.size());
      ev.data = buf.data();
      log.writeEvent(&ev);
    };
    const int64_t t0 = 1'700'000'000'000'000;
    for (int i = 0; i <= 300; ++i) {  // 100 Hz poses over 3 s, a camera at 30 Hz
      const int64_t t = t0 + i * 10'000;
      if (with_poses) {
        alight::pose_t pose{};
        pose.utime = t;
        pose.seq = i;
        pose.pos[0] = 0.2 * i / 100.0;
        pose.pos[2] = 1.6;
        pose.orientation[0] = 1.0;
        write(alight::channels::kEstimatePose, pose, t + 2'000);
      }
      if (i % 3 == 0 && i > 0 && i < 300) {
        alight::image_t img = alight::image_to_msg(texture, t, i / 3);
        alight::set_exposure_metadata(img, 0.004);
        write(alight::channels::kCamera, img, t + 15'000);
      }
    }
    return path;
  }

  static std::string run(const std::string& args, int* status) {
    const std::string cmd =
        std::string(alight::build::binary_dir()) + "/bin/alight-vision-eval " + args + " 2>&1";
    FILE* p = popen(cmd.c_str(), "r");
    std::string out;
    char buf[512];
    while (p && std::fgets(buf, sizeof buf, p)) out += buf;
    *status = p ? pclose(p) : -1;
    return out;
  }

  /// The tool's output over a written log (it must exit 0).
  std::string evaluate(bool with_poses) {
    const std::string log = write_log(with_poses);
    const std::string config =
        std::string(alight::build::source_dir()) + "/config/vehicles/pelican.yaml";
    int status = 0;
    const std::string out = run(log + " --config " + config + " --mission landing", &status);
    EXPECT_EQ(status, 0) << out;
    std::filesystem::remove(log);
    return out;
  }
};

TEST_F(VisionEvalToolTest, AFlightWithoutMotionCaptureOrTruth) {
  const std::string out = evaluate(true);
  EXPECT_NE(out.find("poses: ESTIMATE_POSE (301); truth: none"), std::string::npos) << out;
  EXPECT_NE(out.find("frames: 99"), std::string::npos) << out;
  EXPECT_NE(out.find("stream: 33.3 Hz"), std::string::npos) << out;
  EXPECT_NE(out.find("0 gaps (0 frames missing), 0 repeated"), std::string::npos) << out;
  EXPECT_NE(out.find("delay_ms (exposure to recorder): p10 15.0 p50 15.0"), std::string::npos)
      << out;
  EXPECT_NE(out.find("exposure_ms (driver): p10 4.00 p50 4.00"), std::string::npos) << out;
  EXPECT_NE(out.find("frames without a pose: 0"), std::string::npos) << out;
  EXPECT_EQ(out.find("waypoint_error_m"), std::string::npos) << "no truth, no errors";
}

TEST_F(VisionEvalToolTest, APoseChannelMissingIsSaidWithWhatToCheck) {
  const std::string out = evaluate(false);
  EXPECT_NE(out.find("poses: MOCAP_POSE (0)"), std::string::npos) << out;
  EXPECT_NE(out.find("frames without a pose: 99"), std::string::npos) << out;
  EXPECT_NE(out.find(alight::tools::hint(Reason::kNoPose)), std::string::npos) << out;
}

}  // namespace
