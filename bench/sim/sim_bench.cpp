// Render time per 640x480 frame (one thread, and all cores) and the simulator's real-time
// factor alone (1 kHz physics, mocap, IMU and 30 Hz rendering, no LCM).
//   build/bin/sim_bench [--benchmark_filter=...]

#include <benchmark/benchmark.h>

#include <opencv2/core/utility.hpp>

#include "common/build_paths.hpp"
#include "sim/params.hpp"
#include "sim/renderer.hpp"
#include "sim/simulator.hpp"

namespace {

using namespace alight;
using namespace alight::sim;

std::string config(const std::string& rel) {
  return std::string(alight::build::source_dir()) + "/config/" + rel;
}

// A view typical of each mission: 1.5 m above the platform area, 1.5 m in front of the wall.
Isometry3d typical_view(const Scene& scene, const std::string& name, double t) {
  const double wobble = 0.05 * std::sin(t);
  if (name.rfind("ingress", 0) == 0)
    return make_transform(rotation_from_rpy(wobble, 0.02, 0.1 + wobble) * R_BC_forward(),
                          Vector3d(1.5, 0.1 + 0.1 * t, 1.2));
  const Vector3d c = scene.platform ? scene.platform->top_center_W : Vector3d::Zero();
  return make_transform(rotation_from_rpy(wobble, -0.03, 0.3) * R_BC_downward(),
                        Vector3d(c.x() + 0.2 + 0.01 * t, c.y() + 0.1, 1.5));
}

void BM_Render(benchmark::State& state, const std::string& name, int threads, int supersample) {
  const Scenario sc = load_scenario(config("scenarios/" + name + ".yaml"));
  const Scene scene = build_scene(sc, 1);
  Renderer renderer(CameraModel::firefly_mv_4mm(), supersample);
  renderer.set_threads(threads);
  double t = 0;
  for (auto _ : state) {
    cv::Mat img = renderer.render(scene, typical_view(scene, name, t));
    benchmark::DoNotOptimize(img.data);
    t += 0.01;
  }
}

void BM_RealTimeFactor(benchmark::State& state, const std::string& name, bool camera) {
  Scenario sc = load_scenario(config("scenarios/" + name + ".yaml"));
  sc.camera.enabled = camera;
  const VehicleParams v = load_vehicle_params(config("vehicles/starmac.yaml"));
  const CameraRig rig = load_camera_rig(config("vehicles/starmac.yaml"), sc.camera.mount);
  Simulator sim(sc, v, 1, rig);
  VehicleState s = sim.state();
  s.p_W_B.z() = 1.5;
  s.armed = true;
  s.thrust_N = v.hover_thrust_N();
  sim.set_state(s);
  AttitudeCommand cmd;
  cmd.armed = true;
  cmd.thrust_N = v.hover_thrust_N();
  int64_t sim_us = 0;
  for (auto _ : state) {
    // One second of sim time in 5 ms chunks, as a node or closed-loop test would step it.
    for (int i = 0; i < 200; ++i) {
      cmd.roll_rad = 0.02 * std::sin(sim_us * 1e-6);
      sim.step(cmd, sim.now_utime() + 5000);
      sim_us += 5000;
      benchmark::DoNotOptimize(sim.take_mocap());
      benchmark::DoNotOptimize(sim.take_imu());
      auto f = sim.take_camera();
      benchmark::DoNotOptimize(f);
    }
  }
  state.counters["real_time_factor"] =
      benchmark::Counter(static_cast<double>(sim_us) * 1e-6, benchmark::Counter::kIsRate);
}

}  // namespace

int main(int argc, char** argv) {
  const int cores = std::max(1, cv::getNumberOfCPUs());
  for (const std::string name :
       {"landing_a", "landing_c", "landing_none", "ingress", "ingress_solid"}) {
    benchmark::RegisterBenchmark(("render_1core/" + name).c_str(), BM_Render, name, 1, 1)
        ->Unit(benchmark::kMillisecond)
        ->MeasureProcessCPUTime()
        ->UseRealTime();
  }
  for (const std::string name : {"landing_a", "ingress"}) {
    benchmark::RegisterBenchmark(("render_allcores/" + name).c_str(), BM_Render, name, cores, 1)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
    benchmark::RegisterBenchmark(("render_1core_supersample2/" + name).c_str(), BM_Render, name, 1,
                                 2)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
    benchmark::RegisterBenchmark(("realtime_factor_with_camera/" + name).c_str(), BM_RealTimeFactor,
                                 name, true)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
    benchmark::RegisterBenchmark(("realtime_factor_no_camera/" + name).c_str(), BM_RealTimeFactor,
                                 name, false)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
  }
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
