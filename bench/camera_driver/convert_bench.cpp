// Cost of turning one 640x480 V4L2 buffer into the published encoding, per camera format.
//   build/bin/camera_convert_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only
// The frame is a textured scene (gradients, edges, mild sensor noise) so the JPEG size is that
// of a real camera's at quality 90, not of a flat or pure-noise image.

#include <benchmark/benchmark.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "camera_driver/convert.hpp"

namespace {

using namespace alight::camera;

constexpr int kW = 640, kH = 480;

cv::Mat scene_bgr() {
  cv::Mat img(kH, kW, CV_8UC3);
  for (int r = 0; r < kH; ++r)
    for (int c = 0; c < kW; ++c)
      img.at<cv::Vec3b>(r, c) =
          cv::Vec3b(static_cast<uint8_t>(c * 255 / kW), static_cast<uint8_t>(r * 255 / kH),
                    static_cast<uint8_t>((c + r) % 256));
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> x(0, kW - 1), y(0, kH - 1), v(0, 255);
  for (int i = 0; i < 120; ++i)
    cv::rectangle(img, cv::Rect(x(rng), y(rng), 10 + x(rng) % 60, 10 + y(rng) % 60),
                  cv::Scalar(v(rng), v(rng), v(rng)), cv::FILLED);
  cv::Mat noise(kH, kW, CV_8UC3);
  cv::randn(noise, cv::Scalar::all(0), cv::Scalar::all(3));
  img += noise;
  return img;
}

struct Frames {
  std::vector<uint8_t> grey, yuyv, mjpeg;
  Frames() {
    const cv::Mat bgr = scene_bgr();
    cv::Mat gray;
    cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
    grey.assign(gray.datastart, gray.dataend);
    // YUYV: luma from the gray image, chroma from the pair's average (BT.601).
    cv::Mat yuv;
    cv::cvtColor(bgr, yuv, cv::COLOR_BGR2YUV);
    yuyv.resize(kW * kH * 2);
    for (int r = 0; r < kH; ++r)
      for (int c = 0; c < kW; c += 2) {
        const cv::Vec3b a = yuv.at<cv::Vec3b>(r, c), b = yuv.at<cv::Vec3b>(r, c + 1);
        uint8_t* q = &yuyv[(r * kW + c) * 2];
        q[0] = a[0], q[1] = static_cast<uint8_t>((a[1] + b[1]) / 2);
        q[2] = b[0], q[3] = static_cast<uint8_t>((a[2] + b[2]) / 2);
      }
    cv::imencode(".jpg", bgr, mjpeg, {cv::IMWRITE_JPEG_QUALITY, 90});
  }
};
const Frames& frames() {
  static const Frames f;
  return f;
}

void run(benchmark::State& state, PixelFormat format, OutputEncoding enc) {
  const Frames& f = frames();
  const std::vector<uint8_t>& buf = format == PixelFormat::kGrey   ? f.grey
                                    : format == PixelFormat::kYuyv ? f.yuyv
                                                                   : f.mjpeg;
  const int stride =
      format == PixelFormat::kYuyv ? kW * 2 : (format == PixelFormat::kGrey ? kW : 0);
  const RawFrameView view{buf.data(), buf.size(), kW, kH, stride, format};
  // Arg 1: OpenCV on one thread (the CPU cost of a frame); arg 0: OpenCV's default thread pool
  // (what the node does; faster on an idle multi-core machine).
  cv::setNumThreads(state.range(0) == 1 ? 1 : -1);
  cv::Mat out;
  std::string err;
  for (auto _ : state) {
    if (!convert_frame(view, enc, out, &err)) state.SkipWithError(err.c_str());
    benchmark::DoNotOptimize(out.data);
  }
  state.counters["buffer_bytes"] = static_cast<double>(buf.size());
  cv::setNumThreads(-1);
}

void BM_Grey_to_mono8(benchmark::State& s) { run(s, PixelFormat::kGrey, OutputEncoding::kMono8); }
void BM_Yuyv_to_mono8(benchmark::State& s) { run(s, PixelFormat::kYuyv, OutputEncoding::kMono8); }
void BM_Yuyv_to_rgb8(benchmark::State& s) { run(s, PixelFormat::kYuyv, OutputEncoding::kRgb8); }
void BM_Mjpeg_to_mono8(benchmark::State& s) { run(s, PixelFormat::kMjpeg, OutputEncoding::kMono8); }
void BM_Mjpeg_to_rgb8(benchmark::State& s) { run(s, PixelFormat::kMjpeg, OutputEncoding::kRgb8); }

BENCHMARK(BM_Grey_to_mono8)->ArgName("one_thread")->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Yuyv_to_mono8)->ArgName("one_thread")->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Yuyv_to_rgb8)->ArgName("one_thread")->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Mjpeg_to_mono8)->ArgName("one_thread")->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Mjpeg_to_rgb8)->ArgName("one_thread")->Arg(1)->Arg(0)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
