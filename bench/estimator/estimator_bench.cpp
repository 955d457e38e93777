// CPU cost of the onboard estimator, Google Benchmark:
//  - ImuSample: one add_imu in steady state (propagation of the 17-dim error state, checkpoint,
//    pruning of the 0.5 s history), no measurement in the interval;
//  - FlowFuse: the flow update alone (model, Jacobians, gate, Kalman update with one clone);
//  - FlowUpdateDelayed: one add_flow arriving 50 ms after its second exposure (clone at the
//    first, replay of about 17 IMU intervals from the checkpoint before it, update);
//  - FlightPerImuSample: a whole synthetic flight (200 Hz IMU, 50 Hz range, 25 Hz baro, 30 Hz
//    flow, all delayed), reported per IMU sample.
//   build/bin/estimator_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only

#include <benchmark/benchmark.h>

#include "synthetic.hpp"

using namespace alight;
using namespace alight::estimator;

namespace {

EstimatorParams hover_params() {
  EstimatorParams p;
  p.init.p_W_B_m = Vector3d(0, 0, 1.5);
  return p;
}

/// An estimator that has flown `seconds` of a hover with every sensor.
Estimator hovering(double seconds, const test::Flight& f, const EstimatorParams& p) {
  Estimator est(p);
  for (const auto& in : f.inputs)
    if (in.arrival_utime <= test::kStartUtime + static_cast<int64_t>(seconds * 1e6))
      test::feed(est, in);
  return est;
}

void BM_ImuSample(benchmark::State& state) {
  const EstimatorParams p = hover_params();
  const test::Flight f = test::simulate(test::hover(1.5, 1.5), 3.0, {}, p, 1);
  Estimator est = hovering(3.0, f, p);
  int64_t t = est.state().utime;
  const ImuSample still{0, Vector3d(0, 0, p.gravity_mps2), Vector3d::Zero()};
  for (auto _ : state) {
    ImuSample s = still;
    s.utime = t += 5000;
    benchmark::DoNotOptimize(est.add_imu(s));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ImuSample);

void BM_FlowFuse(benchmark::State& state) {
  const EstimatorParams p = hover_params();
  FilterState s0;
  s0.x.p_W_B = Vector3d(0, 0, 1.5);
  s0.P = Cov::Identity(idx::kCore, idx::kCore) * 1e-3;
  add_clone(s0, 1);
  const Matrix3d R_BC = p.flow.R_BC();
  MeasCov R = MeasCov::Identity(3, 3) * 1e-5;
  for (auto _ : state) {
    FilterState s = s0;
    const FlowModel m = flow_model(s.x, s.clones[0], R_BC, p.flow.t_B_C_m);
    MeasJac H = MeasJac::Zero(3, s.dim());
    H.leftCols<idx::kCore>() = m.H_core;
    H.rightCols<kCloneDim>() = m.H_clone;
    MeasVec r = Vector3d(1e-3, -2e-3, 0.5e-3) - m.t_over_d;
    benchmark::DoNotOptimize(fuse(s, r, H, R, 16.27));
    remove_clone(s, 0);
    benchmark::DoNotOptimize(s.P.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_FlowFuse);

void BM_FlowUpdateDelayed(benchmark::State& state) {
  const EstimatorParams p = hover_params();
  test::SensorConfig cfg;
  cfg.flow = false;
  const test::Flight f = test::simulate(test::hover(1.5, 1.5), 3.0, cfg, p, 1);
  const Estimator base = hovering(3.0, f, p);
  const int64_t now = base.state().utime;
  FlowSample flow;
  flow.utime_to = now - 50'000;
  flow.utime_from = flow.utime_to - 33'333;
  flow.cov = Matrix3d::Identity() * 9e-6;
  flow.inliers = 100;
  for (auto _ : state) {
    state.PauseTiming();
    Estimator est = base;
    state.ResumeTiming();
    benchmark::DoNotOptimize(est.add_flow(flow));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_FlowUpdateDelayed);

void BM_FlightPerImuSample(benchmark::State& state) {
  const EstimatorParams p = hover_params();
  const test::Flight f = test::simulate(test::figure(1.5, 1.5, 1.5), 10.0, {}, p, 1);
  int64_t imu = 0;
  for (const auto& in : f.inputs) imu += in.kind == test::Kind::kImu;
  for (auto _ : state) {
    Estimator est(p);
    for (const auto& in : f.inputs) test::feed(est, in);
    benchmark::DoNotOptimize(est.state().p_W_B.data());
  }
  state.SetItemsProcessed(state.iterations() * imu);
}
BENCHMARK(BM_FlightPerImuSample)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
