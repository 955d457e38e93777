// Drift of the onboard estimator flying the simulator on its own estimate: the
// simulator (config/scenarios/estimator_drift.yaml: textured floor, no motion capture), the
// outer loop fed the estimate's pose (ESTIMATE_POSE) and position setpoints, and the estimator as
// alight-estimator runs it (test/estimator/sim_onboard.hpp: the vehicle file's parameters, the
// downward camera's frames through the flow front end). No autonomy, no vision. Per seed:
//  (a) hover: take off to 1.5 m, hold the start for 60 s;
//  (b) square: take off, fly a 10 m square at 1 m/s (1 s ramps, a second's pause at each
//      corner: 40 m) back to the start, hold 2 s.
// The error of the estimate against the truth at the end (both start at the same point:
// horizontal, vertical, heading) and the filter's own 1-sigma, then median and max over the
// seeds; the estimator's CPU time per IMU sample, range and baro reading and camera frame
// (thread CPU time of the one thread that runs it, the clock's own cost taken off); the flow
// front end's error against the simulator's camera poses.
// DRIFT_TRACE=1: the estimate's error, attitude and biases every 0.5 s on stderr;
// DRIFT_TRACE_FLOW=1: each flow sample against the truth.
//
//   build/bin/estimator_sim_drift [--seeds 10] [--first-seed 1] [--jobs 2] [--only hover|square]
//       [--vehicle config/vehicles/pelican.yaml] [--scenario config/scenarios/estimator_drift.yaml]

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <opencv2/core.hpp>
#include <string>
#include <thread>
#include <vector>

#include "common/build_paths.hpp"
#include "common/params.hpp"
#include "outer_loop/params.hpp"
#include "outer_loop/position_controller.hpp"
#include "sim/params.hpp"
#include "sim/simulator.hpp"
#include "sim_onboard.hpp"
#include "support/stats.hpp"

using namespace alight;

namespace {

using alight::test::quantile;

constexpr double kHeightM = 1.5;
constexpr double kRestS = 1.5;   // on the floor: the estimator's static alignment (1 s)
constexpr double kClimbS = 3.0;  // to kHeightM
constexpr double kSettleS = 2.0;

/// A position reference: where and how fast at time t after the climb.
struct Reference {
  Vector3d p_W, v_W;
};

// Along a straight leg of length L at speed v with ramps of ramp_s: distance covered at s.
double along(double s, double L, double v, double ramp_s, double* speed) {
  const double a = v / ramp_s;
  const double d_ramp = 0.5 * a * ramp_s * ramp_s;
  const double cruise_s = (L - 2 * d_ramp) / v;
  const double total_s = 2 * ramp_s + cruise_s;
  s = std::clamp(s, 0.0, total_s);
  if (s < ramp_s) {
    *speed = a * s;
    return 0.5 * a * s * s;
  }
  if (s < ramp_s + cruise_s) {
    *speed = v;
    return d_ramp + v * (s - ramp_s);
  }
  const double r = total_s - s;
  *speed = a * r;
  return L - 0.5 * a * r * r;
}

struct Square {
  double side_m = 10, speed_mps = 1, ramp_s = 1, pause_s = 1;
  double leg_s() const { return 2 * ramp_s + (side_m - speed_mps * ramp_s) / speed_mps; }
  double duration_s() const { return 4 * (leg_s() + pause_s); }
  Reference at(double t) const {
    static const Vector3d corners[5] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 0}};
    const int leg = std::min(3, static_cast<int>(t / (leg_s() + pause_s)));
    const double s = std::max(0.0, t - leg * (leg_s() + pause_s));
    double speed = 0;
    const double d = along(s, side_m, speed_mps, ramp_s, &speed);
    const Vector3d dir = corners[leg + 1] - corners[leg];
    const Vector3d start = side_m * corners[leg];
    Reference r;
    r.p_W = start + d * dir + Vector3d(0, 0, kHeightM);
    r.v_W = speed * dir;
    if (t >= duration_s()) r = {Vector3d(0, 0, kHeightM), Vector3d::Zero()};
    return r;
  }
};

struct Result {
  double horizontal_m = 0, vertical_m = 0, heading_deg = 0, sigma_h_m = 0, sigma_z_m = 0;
  double hold_start_h_m = 0;  ///< horizontal error when the hover / square began
  double max_h_m = 0;         ///< largest horizontal error in the flight
  double distance_m = 0;      ///< flown (truth), after the climb
  bool health_ok = false;
  int64_t flow_fused = 0, flow_rejected = 0, frames = 0;
  /// The front end against the truth, as velocity (t/d error x height / interval), per
  /// horizontal axis of the camera: error's mean and RMS, and the sigma it reported [mm/s].
  double flow_mean_mmps = 0, flow_rms_mmps = 0, flow_sigma_mmps = 0;
  int n_flow = 0;
  estimator::test::OnboardCost cost;
};

Result fly(const std::string& vehicle_file, const std::string& scenario_file, uint64_t seed,
           bool square) {
  const ParamNode root = ParamNode::load_file(vehicle_file);
  outer_loop::PositionController controller(outer_loop::load_params(root));
  sim::Scenario scenario = sim::load_scenario(scenario_file);
  scenario.mocap.enabled = false;
  sim::Simulator simulator(scenario, sim::load_vehicle_params(vehicle_file), seed,
                           sim::load_camera_rig(vehicle_file, "downward"));
  estimator::test::SimOnboard onboard(vehicle_file, true);

  const Vector3d start = simulator.truth().state.p_W_B;
  const Square sq;
  const double task_s = square ? sq.duration_s() + kSettleS : 60.0;
  const double t_task0 = kRestS + kClimbS + kSettleS;
  const int64_t t0 = scenario.start_utime;
  const int64_t t_end = t0 + static_cast<int64_t>((t_task0 + task_s) * 1e6);

  std::optional<PoseSample> pose;
  outer_loop::AttitudeCommand att;
  Result res;
  bool task_started = false;
  Vector3d last_true = start;
  const bool trace = std::getenv("DRIFT_TRACE") != nullptr;  // the error every 0.5 s on stderr
  const bool trace_flow = std::getenv("DRIFT_TRACE_FLOW") != nullptr;  // each flow sample's error
  struct CameraPose {
    int64_t utime;
    Isometry3d X_WC;
  };
  std::optional<CameraPose> prev_frame;
  for (int64_t now = t0; now < t_end;) {
    const int64_t until = now + 5000;
    simulator.step(
        {att.utime, att.roll_rad, att.pitch_rad, att.yaw_rate_radps, att.thrust_N, att.armed},
        until);
    const double t = (until - t0) * 1e-6;
    outer_loop::PositionSetpoint sp;
    sp.utime = until;
    sp.motors_on = t >= kRestS;
    const double climb = std::clamp((t - kRestS) / kClimbS, 0.0, 1.0);
    sp.p_W = start + Vector3d(0, 0, climb * (kHeightM - start.z()));
    if (climb > 0 && climb < 1) sp.v_W.z() = (kHeightM - start.z()) / kClimbS;
    if (square && t >= t_task0) {
      const Reference r = sq.at(t - t_task0);
      sp.p_W = Vector3d(start.x(), start.y(), 0) + r.p_W;
      sp.v_W = r.v_W;
    }
    for (const auto& s : simulator.take_imu()) {
      if (const auto published = onboard.add_imu(s)) {
        pose = published->pose;
        att = controller.update(sp, pose, s.utime);
      }
    }
    for (const auto& s : simulator.take_range()) onboard.add_range(s);
    for (const auto& s : simulator.take_baro()) onboard.add_baro(s);
    if (auto f = simulator.take_camera()) {
      onboard.add_frame(*f);
      // The flow sample against the truth: the camera's true motion between the frames over its
      // true height (the floor is z = 0).
      const auto& sample = onboard.onboard().last_frame().sample;
      if (sample && prev_frame && prev_frame->utime == sample->utime_from &&
          f->utime == sample->utime_to) {
        const Isometry3d& X1 = prev_frame->X_WC;
        const Vector3d t_true = X1.linear().transpose() *
                                (f->X_WC.translation() - X1.translation()) / X1.translation().z();
        const Vector3d e = sample->t_over_d_C1 - t_true;
        const double dt = (sample->utime_to - sample->utime_from) * 1e-6;
        const double to_mmps = 1e3 * X1.translation().z() / dt;
        for (int k = 0; k < 2; ++k) {
          res.flow_mean_mmps += e[k] * to_mmps;
          res.flow_rms_mmps += e[k] * e[k] * to_mmps * to_mmps;
          res.flow_sigma_mmps += std::sqrt(sample->cov(k, k)) * to_mmps;
          ++res.n_flow;
        }
        if (trace_flow) {
          const Vector3d pe = onboard.state().p_W_B - simulator.truth().state.p_W_B;
          const Vector3d ve = onboard.state().v_W_B - simulator.truth().state.v_W_B;
          std::fprintf(stderr, "STATE %.3f perr %+.4f %+.4f verr %+.4f %+.4f outcome %s\n",
                       (f->utime - t0) * 1e-6, pe.x(), pe.y(), ve.x(), ve.y(),
                       estimator::to_string(onboard.onboard().last_frame().fused));
          std::fprintf(stderr,
                       "FLOW %.3f td_err %+.5f %+.5f %+.5f (v_err mm/s %+.1f %+.1f %+.1f) sigma "
                       "%.5f inliers %d\n",
                       (f->utime - t0) * 1e-6, e.x(), e.y(), e.z(), e.x() * to_mmps,
                       e.y() * to_mmps, e.z() * to_mmps, std::sqrt(sample->cov(0, 0)),
                       sample->inliers);
        }
      }
      prev_frame = CameraPose{f->utime, f->X_WC};
    }
    now = until;
    att = controller.update(sp, pose, now);

    const sim::Truth truth = simulator.truth();
    const estimator::State es = onboard.state();
    if (!es.initialised) continue;
    const Vector3d e = es.p_W_B - truth.state.p_W_B;
    if (t >= t_task0 && !task_started) {
      task_started = true;
      res.hold_start_h_m = e.head<2>().norm();
    }
    if (task_started) res.distance_m += (truth.state.p_W_B - last_true).head<2>().norm();
    last_true = truth.state.p_W_B;
    res.max_h_m = std::max(res.max_h_m, e.head<2>().norm());
    if (trace && (until - t0) % 500000 == 0) {
      std::fprintf(
          stderr,
          "%6.1f true %7.3f %7.3f %6.3f v %6.3f %6.3f err %+.4f %+.4f %+.4f verr %+.4f %+.4f\n", t,
          truth.state.p_W_B.x(), truth.state.p_W_B.y(), truth.state.p_W_B.z(),
          truth.state.v_W_B.x(), truth.state.v_W_B.y(), e.x(), e.y(), e.z(),
          es.v_W_B.x() - truth.state.v_W_B.x(), es.v_W_B.y() - truth.state.v_W_B.y());
      // Attitude error in world (small angles) and the biases.
      const Eigen::AngleAxisd aa(truth.state.q_WB.toRotationMatrix().transpose() *
                                 es.q_WB.toRotationMatrix());
      const Vector3d th = truth.state.q_WB.toRotationMatrix() * aa.axis() * aa.angle() * 180 / M_PI;
      std::fprintf(
          stderr,
          "       att_err_W deg %+.3f %+.3f %+.3f  ba %+.4f %+.4f %+.4f  bg %+.5f %+.5f %+.5f\n",
          th.x(), th.y(), th.z(), es.accel_bias_B.x(), es.accel_bias_B.y(), es.accel_bias_B.z(),
          es.gyro_bias_B.x(), es.gyro_bias_B.y(), es.gyro_bias_B.z());
    }
  }
  const sim::Truth truth = simulator.truth();
  const estimator::State s = onboard.state();
  const Vector3d e = s.p_W_B - truth.state.p_W_B;
  res.horizontal_m = e.head<2>().norm();
  res.vertical_m = std::abs(e.z());
  res.heading_deg = std::abs(wrap_angle(yaw_of(s.q_WB.toRotationMatrix()) -
                                        yaw_of(truth.state.q_WB.toRotationMatrix()))) *
                    180 / M_PI;
  res.sigma_h_m = std::sqrt(s.cov(0, 0) + s.cov(1, 1));
  res.sigma_z_m = std::sqrt(s.cov(2, 2));
  res.health_ok = s.health == estimator::Health::kOk;
  res.flow_fused = s.counters.fused(estimator::Sensor::kFlow);
  res.flow_rejected = s.counters.rejected(estimator::Sensor::kFlow);
  res.cost = onboard.cost();
  if (res.n_flow > 0) {
    res.flow_mean_mmps /= res.n_flow;
    res.flow_rms_mmps = std::sqrt(res.flow_rms_mmps / res.n_flow);
    res.flow_sigma_mmps /= res.n_flow;
  }
  return res;
}

void report(const char* name, const std::vector<Result>& rs) {
  std::vector<double> h, z, yaw, sh, sz, mh, dist, pct, flow_rms, flow_mean, flow_sigma;
  int ok = 0;
  estimator::test::OnboardCost c;
  std::vector<double> frame_us;
  for (const auto& r : rs) {
    h.push_back(100 * r.horizontal_m), z.push_back(100 * r.vertical_m);
    yaw.push_back(r.heading_deg), sh.push_back(100 * r.sigma_h_m), sz.push_back(100 * r.sigma_z_m);
    mh.push_back(100 * r.max_h_m), dist.push_back(r.distance_m);
    pct.push_back(r.distance_m > 1 ? 100 * r.horizontal_m / r.distance_m : 0);
    ok += r.health_ok;
    flow_rms.push_back(r.flow_rms_mmps), flow_mean.push_back(std::abs(r.flow_mean_mmps));
    flow_sigma.push_back(r.flow_sigma_mmps);
    c.imu_ns += r.cost.imu_ns, c.n_imu += r.cost.n_imu;
    c.range_ns += r.cost.range_ns, c.n_range += r.cost.n_range;
    c.baro_ns += r.cost.baro_ns, c.n_baro += r.cost.n_baro;
    c.frame_ns += r.cost.frame_ns, c.n_frames += r.cost.n_frames;
    c.max_imu_ns = std::max(c.max_imu_ns, r.cost.max_imu_ns);
    for (int32_t us : r.cost.frame_us) frame_us.push_back(us);
  }
  std::printf(
      "%s (%zu seeds): final error horizontal p50 %.2f max %.2f cm (filter 1-sigma p50 %.1f cm), "
      "largest in flight p50 %.2f max %.2f cm; vertical p50 %.2f max %.2f cm (sigma %.1f cm); "
      "heading p50 %.2f max %.2f deg; distance flown p50 %.1f m, final horizontal error / "
      "distance p50 %.2f max %.2f %%; health OK at the end %d\n",
      name, rs.size(), quantile(h, 0.5), quantile(h, 1), quantile(sh, 0.5), quantile(mh, 0.5),
      quantile(mh, 1), quantile(z, 0.5), quantile(z, 1), quantile(sz, 0.5), quantile(yaw, 0.5),
      quantile(yaw, 1), quantile(dist, 0.5), quantile(pct, 0.5), quantile(pct, 1), ok);
  std::printf(
      "  flow front end against the truth (per horizontal camera axis, as velocity): RMS error "
      "p50 %.2f max %.2f mm/s, |mean| p50 %.2f max %.2f mm/s, its own sigma p50 %.2f mm/s\n",
      quantile(flow_rms, 0.5), quantile(flow_rms, 1), quantile(flow_mean, 0.5),
      quantile(flow_mean, 1), quantile(flow_sigma, 0.5));
  const auto per = [](int64_t ns, int64_t n) { return n ? 1e-3 * ns / n : 0.0; };
  std::printf(
      "  estimator CPU (one thread): per IMU sample %.1f us (max %.0f us), per range reading %.1f "
      "us, per baro reading %.1f us, per camera frame %.2f ms (p50 %.2f p99 %.2f max %.2f ms, "
      "front end and the flow sample's late fusion); %.1f ms per second of flight\n",
      per(c.imu_ns, c.n_imu), 1e-3 * c.max_imu_ns, per(c.range_ns, c.n_range),
      per(c.baro_ns, c.n_baro), 1e-3 * per(c.frame_ns, c.n_frames), 1e-3 * quantile(frame_us, 0.5),
      1e-3 * quantile(frame_us, 0.99), 1e-3 * quantile(frame_us, 1),
      c.n_imu ? 1e-6 * (c.imu_ns + c.range_ns + c.baro_ns + c.frame_ns) / (c.n_imu / 200.0) : 0.0);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"onboard estimator drift, flying the simulator on the estimate"};
  int seeds = 10, first = 1, jobs = 1;
  std::string only;
  std::string vehicle = std::string(alight::build::source_dir()) + "/config/vehicles/pelican.yaml";
  std::string scenario =
      std::string(alight::build::source_dir()) + "/config/scenarios/estimator_drift.yaml";
  app.add_option("--seeds", seeds, "flights per case")->check(CLI::Range(1, 1000));
  app.add_option("--first-seed", first, "seed of the first flight");
  app.add_option("--jobs", jobs, "flights at once (threads)")->check(CLI::Range(1, 64));
  app.add_option("--only", only, "hover or square")->check(CLI::IsMember({"hover", "square"}));
  app.add_option("--vehicle", vehicle, "vehicle file");
  app.add_option("--scenario", scenario, "scenario file (a floor big enough for the square)");
  CLI11_PARSE(app, argc, argv);
  cv::setNumThreads(1);

  for (const bool square : {false, true}) {
    if (!only.empty() && (only == "square") != square) continue;
    std::vector<Result> results(seeds);
    std::atomic<int> next{0};
    std::mutex out;
    const auto worker = [&] {
      for (int i = next++; i < seeds; i = next++) {
        results[i] = fly(vehicle, scenario, static_cast<uint64_t>(first + i), square);
        const Result& r = results[i];
        std::lock_guard<std::mutex> lock(out);
        std::printf(
            "%s seed %d: error horizontal %.2f cm (at the start of the task %.2f, largest %.2f), "
            "vertical %.2f cm, heading %.2f deg, sigma %.1f cm; flown %.1f m; flow fused %lld "
            "refused %lld; health %s\n",
            square ? "square" : "hover", first + i, 100 * r.horizontal_m, 100 * r.hold_start_h_m,
            100 * r.max_h_m, 100 * r.vertical_m, r.heading_deg, 100 * r.sigma_h_m, r.distance_m,
            static_cast<long long>(r.flow_fused), static_cast<long long>(r.flow_rejected),
            r.health_ok ? "OK" : "not OK");
        std::fflush(stdout);
      }
    };
    std::vector<std::thread> threads;
    for (int j = 0; j < jobs; ++j) threads.emplace_back(worker);
    for (auto& t : threads) t.join();
    report(square ? "square 10 m at 1 m/s" : "hover 60 s at 1.5 m", results);
  }
  return 0;
}
