// Flow odometry cost per 640x480 frame on one thread (OpenCV too: cv::setNumThreads(1), as the
// node will run it), on frames rendered beforehand by the simulator: a downward camera at 1.5 m
// flying 0.86 m/s and wobbling up to 40 deg/s over the scenarios' noise floor and over tiles of
// 30 cm (few corners). Half and full resolution, Lucas-Kanade windows, two feature budgets; the
// same flights under a sensor gain that steps by up to 10 % a frame (flicker: the tracking's gain
// compensation at work, its cost the difference from the steady flight); and the fit alone on 150
// correspondences with 30 % outliers. The CPU column is the one to read on a shared machine.
//   build/bin/flow_bench [--benchmark_filter=...]

#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <opencv2/core/utility.hpp>
#include <random>

#include "estimator/flow_odometry.hpp"
#include "sim/renderer.hpp"
#include "sim/scene.hpp"
#include "sim/texture.hpp"

namespace {

using namespace alight;
using namespace alight::estimator;

constexpr double kDeg = M_PI / 180.0;

struct Frame {
  cv::Mat image;
  int64_t utime;
  Matrix3d R_WC;
  Vector3d p_W_C;
};

std::vector<Frame> render_flight(const std::string& floor, int n, bool flicker) {
  sim::TextureSpec t;
  t.kind = floor;
  t.size_px = floor == "tiles" ? 1024 : 2048;
  t.texel_m = floor == "tiles" ? 0.004 : 0.003;
  t.mean = floor == "tiles" ? 150 : 110;
  t.feature_m = floor == "tiles" ? 0.30 : 0.03;
  sim::Scene scene;
  scene.textures.push_back(sim::Texture::make(t, 1));
  const CameraModel cam = CameraModel::firefly_mv_4mm();
  const sim::Renderer renderer(cam);
  std::vector<Frame> frames;
  Matrix3d R_WB = rotation_from_rpy(2 * kDeg, -3 * kDeg, 0.3);
  cv::RNG rng(1);
  std::mt19937_64 gains(2);
  std::uniform_real_distribution<float> jitter(-0.1f, 0.1f);
  for (int k = 0; k < n; ++k) {
    const double t_s = k / 30.0;
    Frame f;
    f.utime = 1'700'000'000'000'000 + static_cast<int64_t>(std::llround(t_s * 1e6));
    f.R_WC = R_WB * R_BC_downward();
    f.p_W_C = Vector3d(0.8 * t_s, 0.3 * t_s, 1.5);
    const float gain = flicker ? 1.f + jitter(gains) : 1.f;
    cv::Mat img = renderer.render(scene, make_transform(f.R_WC, f.p_W_C), gain), fl,
            noise(img.size(), CV_32F);
    img.convertTo(fl, CV_32F);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 2.0);
    cv::Mat(fl + noise).convertTo(f.image, CV_8U);
    frames.push_back(f);
    const Vector3d w = Vector3d(30, 30, 20) * kDeg * std::sin(2 * M_PI * t_s / 1.2) / 30.0;
    R_WB = R_WB * Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
  }
  return frames;
}

const std::vector<Frame>& flight(const std::string& floor, bool flicker) {
  static std::map<std::pair<std::string, bool>, std::vector<Frame>> cache;
  auto it = cache.find({floor, flicker});
  if (it == cache.end())
    it = cache.emplace(std::make_pair(floor, flicker), render_flight(floor, 90, flicker)).first;
  return it->second;
}

void BM_FlowFrame(benchmark::State& state, const std::string& floor, bool flicker) {
  const auto& frames = flight(floor, flicker);
  FlowFrontParams params;
  params.track.downsample = static_cast<int>(state.range(0));
  params.track.max_features = static_cast<int>(state.range(1));
  params.track.min_tracks = params.track.max_features * 5 / 8;
  params.track.window_px = static_cast<int>(state.range(2));
  FlowOdometry flow(params, CameraModel::firefly_mv_4mm());
  size_t k = 0;
  int64_t samples = 0, pairs = 0, inliers = 0;
  int64_t offset = 0;  // the flight replayed later each round, so stamps keep increasing
  for (auto _ : state) {
    if (k == frames.size()) {
      k = 0;
      offset += 10'000'000;
      flow.reset();
    }
    const Frame& f = frames[k];
    const Matrix3d R = k ? Matrix3d(f.R_WC.transpose() * frames[k - 1].R_WC) : Matrix3d::Identity();
    const Vector3d n =
        k ? Vector3d(frames[k - 1].R_WC.transpose() * Vector3d::UnitZ()) : Vector3d(0, 0, -1);
    const FlowResult r = flow.add_frame(f.image, f.utime + offset, R, n);
    benchmark::DoNotOptimize(r.sample);
    if (k) {
      ++pairs;
      if (r.sample) {
        ++samples;
        inliers += r.sample->inliers;
      }
    }
    ++k;
  }
  state.counters["samples_per_pair"] = pairs ? static_cast<double>(samples) / pairs : 0.0;
  state.counters["inliers"] = samples ? static_cast<double>(inliers) / samples : 0.0;
}

void BM_Fit(benchmark::State& state) {
  // 150 correspondences of a floor 1.5 m below, 0.3 px noise, 30 % random outliers.
  const CameraModel cam = CameraModel::firefly_mv_4mm();
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> ux(10, 629), uy(10, 469);
  std::normal_distribution<double> g(0, 0.3);
  const Matrix3d R_WC1 = rotation_from_rpy(0.05, -0.03, 0.4) * R_BC_downward();
  const Matrix3d R_WC2 =
      R_WC1 * Eigen::AngleAxisd(0.02, Vector3d(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  const Vector3d p1(0, 0, 1.5), p2(0.03, 0.01, 1.49);
  std::vector<Vector3d> r1, r2;
  while (r1.size() < 150) {
    const Vector2d px(ux(rng), uy(rng));
    const Vector3d d = R_WC1 * cam.ray(px);
    const Vector3d P = p1 - p1.z() / d.z() * d;
    const auto px2 = cam.project(R_WC2.transpose() * (P - p2));
    if (!px2) continue;
    r1.push_back(cam.ray(px + Vector2d(g(rng), g(rng))));
    r2.push_back(r1.size() % 10 < 3 ? cam.ray(Vector2d(ux(rng), uy(rng)))
                                    : cam.ray(*px2 + Vector2d(g(rng), g(rng))));
  }
  const Matrix3d R = R_WC2.transpose() * R_WC1;
  const Vector3d n = R_WC1.transpose() * Vector3d::UnitZ();
  for (auto _ : state) {
    const FlowFit f = fit_t_over_d(r1, r2, R, n, cam.fx, FlowFitParams{});
    benchmark::DoNotOptimize(f.t_over_d_C1);
  }
}

// Args: downsample, max_features, window_px (the defaults: 1, 160, 15).
BENCHMARK_CAPTURE(BM_FlowFrame, noise, std::string("noise"), false)
    ->Args({1, 160, 15})
    ->Args({1, 160, 11})
    ->Args({1, 160, 21})
    ->Args({0, 160, 15})
    ->Args({0, 160, 21})
    ->Args({1, 300, 15})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FlowFrame, tiles, std::string("tiles"), false)
    ->Args({1, 160, 15})
    ->Args({0, 160, 15})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FlowFrame, noise_flicker, std::string("noise"), true)
    ->Args({1, 160, 15})
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_FlowFrame, tiles_flicker, std::string("tiles"), true)
    ->Args({1, 160, 15})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Fit)->Unit(benchmark::kMicrosecond);

}  // namespace

int main(int argc, char** argv) {
  cv::setNumThreads(1);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
