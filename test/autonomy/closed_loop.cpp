#include "closed_loop.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <stdexcept>

#include "autonomy/convert.hpp"
#include "autonomy/params.hpp"
#include "outer_loop/params.hpp"
#include "outer_loop/position_controller.hpp"
#include "sim/params.hpp"
#include "sim/simulator.hpp"
#include "sim_onboard.hpp"
#include "vision/node/frame_pose_pairing.hpp"

namespace alight::autonomy::test {

namespace {
// Longest wait for a frame's pose, in exposure time of the frames after it (closed_loop.hpp).
constexpr int64_t kMaxPoseWaitUs = 100'000;

// Autonomy's target estimate as the vehicle sees it (relative to its own estimated pose), put
// back in the true frame through the true pose, minus the true target: what the onboard
// estimate's drift does not cancel. Needs a platform or an opening in the scene.
Vector3d estimate_error_rel_W(const sim::Truth& truth, const estimator::State& es,
                              const Vector3d& target_estimate_W) {
  const Matrix3d R_true_est =
      truth.state.q_WB.toRotationMatrix() * es.q_WB.toRotationMatrix().transpose();
  return truth.state.p_W_B + R_true_est * (target_estimate_W - es.p_W_B) -
         (truth.platform ? truth.platform->top_center_W : truth.opening->center_W);
}
}  // namespace

ClosedLoopResult fly_closed_loop(const ClosedLoopConfig& config) {
  const auto root = ParamNode::load_file(config.vehicle_file);
  outer_loop::OuterLoopParams ol_params = outer_loop::load_params(root);
  AutonomyParams au_params = load_params(root);
  au_params.seed = config.seed;
  if (config.detection_max_retries) au_params.detection.max_retries = *config.detection_max_retries;
  if (config.max_feedforward_xy_mps) {
    ol_params.max_feedforward_xy_mps = *config.max_feedforward_xy_mps;
    au_params.moving_platform.max_speed_mps = followed_speed_mps(*config.max_feedforward_xy_mps);
  }
  sim::VehicleParams vehicle = sim::load_vehicle_params(config.vehicle_file);
  if (config.rotor_span_m) {
    // Scale the arms with the span so the rotor discs keep their size relative to the arms.
    vehicle.arm_length_m *= *config.rotor_span_m / vehicle.rotor_tip_span_m;
    vehicle.rotor_tip_span_m = *config.rotor_span_m;
    au_params.ingress.vehicle_span_m = *config.rotor_span_m;
  }
  sim::Scenario scenario = sim::load_scenario(config.scenario_file);
  // The site is the scenario's flying area, as the simulated launch files pass it (--site).
  const SiteArea site{scenario.area_size_m, scenario.area_center_xy_m, scenario.area_height_m};
  fit_to_site(au_params, site, config.scenario_file);
  outer_loop::fit_to_site(ol_params, site, config.scenario_file);
  std::unique_ptr<estimator::test::SimOnboard> onboard;
  // Ingress without motion capture renders the downward camera for the flow besides the
  // forward one for the vision (alight-sim --flow-camera); landing shares its downward frames.
  std::optional<sim::CameraRig> flow_rig;
  if (config.onboard_estimate) {
    if (!config.camera_vision)
      throw std::invalid_argument("fly_closed_loop: onboard_estimate needs real vision");
    scenario.mocap.enabled = false;
    onboard = std::make_unique<estimator::test::SimOnboard>(config.vehicle_file);
    if (config.mission != Mission::kLanding) {
      scenario.flow_camera.enabled = true;
      flow_rig = sim::load_camera_rig(config.vehicle_file, scenario.flow_camera.mount);
    }
  }
  if (config.opening_size_m && scenario.wall)
    scenario.wall->opening_size_m = *config.opening_size_m;
  const CameraMount mount =
      load_camera_mount(root, config.mission == Mission::kLanding ? "downward" : "forward");

  std::optional<sim::CameraRig> rig;
  if (config.camera_vision)
    rig = sim::load_camera_rig(config.vehicle_file,
                               config.mission == Mission::kLanding ? "downward" : "forward");
  sim::Simulator simulator(scenario, vehicle, config.seed, rig, flow_rig);
  // The vision node's frame-to-pose policy (vision/node/frame_pose_pairing.hpp).
  vision::FramePosePairing<sim::CameraFrame> frames(PoseBufferParams{}, kMaxPoseWaitUs);
  outer_loop::PositionController controller(ol_params);
  Autonomy autonomy(au_params);
  OracleVisionParams vp = config.vision;
  vp.mission = config.mission;
  vp.R_BC = mount.R_BC;
  vp.t_B_C = mount.t_B_C;
  vp.seed = config.seed * 7919 + 11;
  OracleVision vision(vp);

  const int64_t t0 = scenario.start_utime;
  const int64_t t_end = t0 + static_cast<int64_t>(config.time_limit_s * 1e6);
  std::optional<PoseSample> pose;
  std::optional<outer_loop::PositionSetpoint> setpoint;
  outer_loop::AttitudeCommand att;
  int64_t now = t0;
  int64_t seq = 0;
  // As alight-autonomy's --auto-go: TAKEOFF in IDLE and GO in HOVER once a second until obeyed
  // (the autonomy refuses them while the onboard estimate is not OK), then never again.
  std::optional<int64_t> takeoff_tried, go_tried;
  bool took_off = false, went = false;
  const auto retry_due = [&](const std::optional<int64_t>& tried) {
    return !tried || now - *tried >= 1'000'000;
  };
  int64_t terminal_since = -1;
  const bool trace = std::getenv("CLOSED_LOOP_TRACE") != nullptr;  // contact trace on stderr
  // The onboard estimate against the truth every 0.1 s on stderr.
  const bool onboard_trace = std::getenv("ONBOARD_TRACE") != nullptr;
  bool event = false;  // a scripted action happened  // first time a terminal phase was seen
  std::optional<EstimateHealth> estimate;  // scripted STATE_ESTIMATE health
  uint32_t estimate_reasons = 0;           // onboard: every reason seen in flight
  bool approach_seen = false;
  bool top_contact_seen = false;     // the first contact with the platform top
  double prev_rel_vz = 0;            // body - top vertical speed at the previous sample
  std::optional<double> prev_along;  // ingress: body from the opening's plane along its normal
  ClosedLoopResult r;

  const auto step_autonomy = [&](Inputs in) {
    if (!took_off && pose && autonomy.phase() == Phase::kIdle && retry_due(takeoff_tried)) {
      in.command = OperatorCommand{now,
                                   ++seq,
                                   "test",
                                   Command::kTakeoff,
                                   Mission::kNone,
                                   Vector3d::Zero(),
                                   CommandAuth::kInternal};
      takeoff_tried = now;
    } else if (!went && autonomy.phase() == Phase::kHover && !in.command && retry_due(go_tried)) {
      in.command = OperatorCommand{now,
                                   ++seq,
                                   "test",
                                   Command::kGo,
                                   config.mission,
                                   Vector3d::Zero(),
                                   CommandAuth::kInternal};
      go_tried = now;
      r.tipped_before_go = simulator.truth().tipped;
    }
    const Output out = autonomy.update(in, now);
    if (takeoff_tried && autonomy.phase() != Phase::kIdle) took_off = true;
    if (go_tried && autonomy.phase() != Phase::kHover) went = true;
    setpoint = out.setpoint;
    r.mission_time_s = out.status.mission_time_s;
    r.reason = out.status.reason;
    if (autonomy.retries() > static_cast<int>(r.retry_reasons.size()))
      r.retry_reasons.push_back(out.status.reason);
  };

  while (now < t_end) {
    const int64_t until = now + 5000;
    const sim::AttitudeCommand cmd{att.utime,          att.roll_rad, att.pitch_rad,
                                   att.yaw_rate_radps, att.thrust_N, att.armed};
    simulator.step(cmd, until);
    for (const auto& m : simulator.take_mocap()) {
      now = std::max(now, m.pose.utime);
      pose = m.pose;
      frames.add_pose(m.pose);
      Inputs in;
      in.pose = m.pose;
      step_autonomy(in);
      att = controller.update(setpoint, pose, now);
    }
    for (const auto& s : simulator.take_imu()) {
      now = std::max(now, s.utime);
      Inputs in;
      in.imu = ImuSample{s.utime, s.accel_B, s.gyro_B};
      // alight-estimator publishes STATE_ESTIMATE and ESTIMATE_POSE on the same IMU sample;
      // autonomy takes the health with the pose's step.
      std::optional<estimator::test::Published> published;
      if (onboard) published = onboard->add_imu(s);
      if (published) {
        pose = published->pose;
        frames.add_pose(published->pose);
        in.pose = published->pose;
        in.estimate = estimate_from_msg(published->estimate, nullptr);
        const sim::Truth truth = simulator.truth();
        if (truth.contact == sim::Contact::kNone && in.estimate) {
          r.estimate_degraded_steps += in.estimate->level == EstimateHealth::Level::kDegraded;
          r.estimate_lost_steps += in.estimate->level == EstimateHealth::Level::kLost;
          estimate_reasons |= in.estimate->reasons;
          const Vector3d e = published->pose.p_W_B - truth.state.p_W_B;
          r.max_pose_error_h_m = std::max(r.max_pose_error_h_m, e.head<2>().norm());
          r.max_pose_error_z_m = std::max(r.max_pose_error_z_m, std::abs(e.z()));
        }
      }
      if (estimate) {
        in.estimate = estimate;
        in.estimate->utime = s.utime;
      }
      step_autonomy(in);
      if (published) att = controller.update(setpoint, pose, now);
    }
    if (onboard) {
      // Range and baro arrive their latency after sampling, behind the IMU samples above.
      for (const auto& s : simulator.take_range()) onboard->add_range(s);
      for (const auto& s : simulator.take_baro()) onboard->add_baro(s);
    }
    now = std::max(now, until);
    // The outer loop also steps on setpoints (the node does), so the pose-lost failsafe runs.
    att = controller.update(setpoint, pose, now);

    const sim::Truth truth = simulator.truth();
    OracleTruth ot;
    ot.vehicle.utime = truth.utime;
    ot.vehicle.p_W_B = truth.state.p_W_B;
    ot.vehicle.q_WB = truth.state.q_WB;
    ot.vehicle.v_W_B = truth.state.v_W_B;
    if (truth.platform) {
      ot.has_platform = true;
      ot.platform_center_W = truth.platform->top_center_W;
      ot.platform_size_m = truth.platform->size_m;
      ot.platform_yaw_rad = truth.platform->yaw_rad;
    }
    if (truth.opening) {
      ot.has_opening = true;
      ot.opening_center_W = truth.opening->center_W;
      ot.opening_size_m = truth.opening->size_m;
      ot.wall_normal_W = truth.opening->wall_normal_W;
      const Vector3d d = truth.state.p_W_B - truth.opening->center_W;
      const double along = d.dot(truth.opening->wall_normal_W);
      const Vector3d t = Vector3d::UnitZ().cross(truth.opening->wall_normal_W).normalized();
      if (std::abs(along) < 0.1) {
        r.crossed_wall = true;
        r.max_lateral_in_wall_m =
            std::max({r.max_lateral_in_wall_m, std::abs(d.dot(t)), std::abs(d.z())});
      }
      // The step that crosses the opening's plane (the normal points out of the wall's face,
      // towards the approaching vehicle).
      if (prev_along && *prev_along > 0 && along <= 0 && !r.crossing_offset_m) {
        r.crossing_offset_m = Vector2d(d.dot(t), d.z());
        if (onboard) {
          const estimator::State es = onboard->state();
          r.pose_error_at_crossing_W = es.p_W_B - truth.state.p_W_B;
        }
      }
      prev_along = along;
    }
    if (onboard && flow_rig) {
      if (auto f = simulator.take_flow_camera()) {
        onboard->add_frame(*f);
        if (config.on_flow_frame) config.on_flow_frame(onboard->onboard());
      }
    }
    if (config.camera_vision) {
      if (auto f = simulator.take_camera()) {
        // Landing: the estimator and the vision share the downward frame.
        if (onboard && !flow_rig) {
          onboard->add_frame(*f);
          if (config.on_flow_frame) config.on_flow_frame(onboard->onboard());
        }
        const int64_t exposure_utime = f->utime;
        frames.add_frame(std::move(*f), exposure_utime);
      }
      while (const auto ready = frames.poll()) {
        const auto m = config.camera_vision(ready->frame, ready->pose);
        if (m && !vision.silent) {
          Inputs in;
          in.target = *m;
          step_autonomy(in);
        }
        if (config.camera_platform && !vision.silent)
          if (auto pm = config.camera_platform()) {
            Inputs in;
            in.platform = *pm;
            step_autonomy(in);
          }
      }
    } else if (auto m = vision.update(ot, until)) {
      Inputs in;
      in.target = *m;
      step_autonomy(in);
    }
    if (config.script) {
      ScriptActions act;
      act.vision_silent = vision.silent;
      act.p_W_true = truth.state.p_W_B;
      act.estimate = estimate;
      config.script(autonomy, (now - t0) * 1e-6, act);
      if (act.estimate.has_value() != estimate.has_value() ||
          (act.estimate && act.estimate->level != estimate->level)) {
        event = true;
      }
      estimate = act.estimate;
      if (act.vision_silent && !vision.silent) event = true;
      vision.silent = act.vision_silent;
      if (act.drop_mocap_for_s) {
        simulator.inject_mocap_dropout(now,
                                       now + static_cast<int64_t>(*act.drop_mocap_for_s * 1e6));
        event = true;
      }
      if (act.command) {
        Inputs in;
        in.command = act.command;
        in.command->utime = now;
        in.command->seq = ++seq;
        step_autonomy(in);
        event = true;
      }
    }
    if (onboard && onboard_trace && truth.utime % 100000 == 0) {
      const estimator::State es = onboard->state();
      double under_m = 0.0;  // true height of what the rangefinder sees (platform top or floor)
      if (truth.platform) {
        const Vector3d d = truth.state.p_W_B - truth.platform->top_center_W;
        const double c = std::cos(truth.platform->yaw_rad), sn = std::sin(truth.platform->yaw_rad);
        if (std::abs(c * d.x() + sn * d.y()) < truth.platform->size_m.x() / 2 &&
            std::abs(-sn * d.x() + c * d.y()) < truth.platform->size_m.y() / 2)
          under_m = truth.platform->top_center_W.z();
      }
      if (truth.opening && scenario.wall) {
        // Over the wall's thickness the beam sees the opening's sill.
        const double into =
            -(truth.state.p_W_B - truth.opening->center_W).dot(truth.opening->wall_normal_W);
        if (into >= 0 && into <= scenario.wall->thickness_m)
          under_m = truth.opening->center_W.z() - 0.5 * truth.opening->size_m.y();
      }
      const Vector3d e = es.p_W_B - truth.state.p_W_B;
      const auto flow_count = [&](estimator::FlowReason why) {
        return onboard->onboard().flow().counts()[static_cast<size_t>(why)];
      };
      std::fprintf(stderr,
                   "ONB %.1f %-15s true %.3f %.3f %.3f err %+.3f %+.3f %+.3f v_err %+.3f %+.3f "
                   "terrain %.3f (true %.3f) sigma_xy %.3f %.3f health %d %s flow fused %lld "
                   "refused %lld second %lld inflated %lld resets %lld on_floor %lld front ok %lld "
                   "few_tracks %lld few_inliers %lld degenerate %lld top %+.3f %+.3f moving %d "
                   "(true %+.3f %+.3f) on_top %lld sd_v %.3f sd_top %.3f sd_tilt %.2f deg\n",
                   (now - t0) * 1e-6, phase_name(autonomy.phase()), truth.state.p_W_B.x(),
                   truth.state.p_W_B.y(), truth.state.p_W_B.z(), e.x(), e.y(), e.z(),
                   es.v_W_B.x() - truth.state.v_W_B.x(), es.v_W_B.y() - truth.state.v_W_B.y(),
                   es.terrain_height_m, under_m, std::sqrt(es.cov_p()(0, 0)),
                   std::sqrt(es.cov_p()(1, 1)), static_cast<int>(es.health),
                   estimator::health_reasons_text(es.health_reasons).c_str(),
                   static_cast<long long>(es.counters.fused(estimator::Sensor::kFlow)),
                   static_cast<long long>(es.counters.rejected(estimator::Sensor::kFlow)),
                   static_cast<long long>(es.counters.flow_second),
                   static_cast<long long>(es.counters.flow_inflated),
                   static_cast<long long>(es.counters.flow_velocity_resets),
                   static_cast<long long>(es.counters.flow_on_floor),
                   static_cast<long long>(flow_count(estimator::FlowReason::kOk)),
                   static_cast<long long>(flow_count(estimator::FlowReason::kTooFewTracks)),
                   static_cast<long long>(flow_count(estimator::FlowReason::kTooFewInliers)),
                   static_cast<long long>(flow_count(estimator::FlowReason::kDegenerate)),
                   es.top_velocity_W.x(), es.top_velocity_W.y(), es.top_moving ? 1 : 0,
                   truth.platform ? truth.platform->v_W.x() : 0.0,
                   truth.platform ? truth.platform->v_W.y() : 0.0,
                   static_cast<long long>(es.counters.flow_top),
                   std::sqrt(es.cov(estimator::idx::kV, estimator::idx::kV)),
                   std::sqrt(es.cov(estimator::idx::kTopV, estimator::idx::kTopV)),
                   std::sqrt(es.cov(estimator::idx::kTheta, estimator::idx::kTheta)) * 180 / M_PI);
    }
    if (event) r.min_z_after_event_m = std::min(r.min_z_after_event_m, truth.state.p_W_B.z());
    const Phase ph = autonomy.phase();
    if (trace &&
        (truth.contact != sim::Contact::kNone || truth.tipped || ph == Phase::kFinalDescent ||
         (ph == Phase::kApproach && truth.platform &&
          truth.state.p_W_B.z() - truth.platform->top_center_W.z() < 0.5)) &&
        truth.utime % 50000 == 0) {
      const Vector3d rpy = rpy_from_rotation(truth.state.q_WB.toRotationMatrix());
      std::fprintf(stderr,
                   "%.3f %s p %.3f %.3f %.3f v %.2f %.2f %.2f rpy %.1f %.1f %.1f thr %.2f contact "
                   "%d armed %d tipped %d wind %.2f %.2f",
                   (now - t0) * 1e-6, phase_name(ph), truth.state.p_W_B.x(), truth.state.p_W_B.y(),
                   truth.state.p_W_B.z(), truth.state.v_W_B.x(), truth.state.v_W_B.y(),
                   truth.state.v_W_B.z(), rpy.x() * 57.3, rpy.y() * 57.3, rpy.z() * 57.3,
                   truth.state.thrust_N, static_cast<int>(truth.contact), truth.state.armed,
                   truth.tipped, truth.wind_W.x(), truth.wind_W.y());
      if (truth.platform)  // the lateral offset from the top's centre [cm]
        std::fprintf(
            stderr, " e %.2f cm",
            100 * (truth.state.p_W_B.head<2>() - truth.platform->top_center_W.head<2>()).norm());
      std::fprintf(stderr, "\n");
    }
    if (onboard && (truth.platform || truth.opening) && ph == Phase::kApproach && !approach_seen) {
      approach_seen = true;
      const estimator::State es = onboard->state();
      r.pose_error_at_approach_W = es.p_W_B - truth.state.p_W_B;
      r.estimate_error_rel_at_approach_W =
          estimate_error_rel_W(truth, es, autonomy.final_estimate());
    }
    if (truth.platform) {
      const double e =
          (truth.state.p_W_B.head<2>() - truth.platform->top_center_W.head<2>()).norm();
      if (ph == Phase::kFinalDescent && r.error_at_final_descent_m < 0)
        r.error_at_final_descent_m = e;
      if (truth.contact == sim::Contact::kPlatformTop && !top_contact_seen) {
        top_contact_seen = true;
        r.contact_rel_vz_mps = prev_rel_vz;
      }
      prev_rel_vz = truth.state.v_W_B.z() - truth.platform->v_W.z();
      if (ph == Phase::kLanded && r.error_at_touchdown_m < 0) {
        const Matrix3d R = truth.state.q_WB.toRotationMatrix();
        const double yaw = std::atan2(R(1, 0), R(0, 0));
        const double d = std::remainder(yaw - truth.platform->yaw_rad, M_PI / 2);
        r.heading_error_at_touchdown_deg = std::abs(d) * 180 / M_PI;
        r.error_at_touchdown_m = e;
        r.p_W_at_touchdown = truth.state.p_W_B;
        if (onboard)
          r.estimate_error_rel_at_touchdown_W =
              estimate_error_rel_W(truth, onboard->state(), autonomy.final_estimate());
      }
      r.platform_yaw_rad = truth.platform->yaw_rad;
    }
    const bool terminal = ph == Phase::kLanded || ph == Phase::kDone || ph == Phase::kKilled ||
                          (ph == Phase::kFailsafe && setpoint && !setpoint->motors_on) ||
                          ph == Phase::kHold;
    if (!terminal) {
      terminal_since = -1;
    } else if (terminal_since < 0) {
      terminal_since = now;
    } else if ((ph == Phase::kLanded && truth.landed) || now - terminal_since > 3'000'000) {
      break;  // settled (the sim's "landed" needs the vehicle at rest)
    }
  }

  const sim::Truth truth = simulator.truth();
  r.phase = autonomy.phase();
  r.landed = truth.landed;
  r.tipped = truth.tipped;
  r.on_platform_top = truth.contact == sim::Contact::kPlatformTop;
  r.collided = truth.collided;
  r.n_collisions = truth.n_collisions;
  r.armed = truth.state.armed;
  r.final_p_W = truth.state.p_W_B;
  r.final_z_m = truth.state.p_W_B.z();
  r.sim_time_s = (now - t0) * 1e-6;
  r.n_measurements = autonomy.estimator().n();
  r.n_rejected = autonomy.estimator().n_rejected();
  r.retries = autonomy.retries();
  r.candidate_looks = autonomy.candidate_looks();
  if (truth.platform) {
    r.touchdown_error_m =
        (truth.state.p_W_B.head<2>() - truth.platform->top_center_W.head<2>()).norm();
    r.estimate_error_W = autonomy.final_estimate() - truth.platform->top_center_W;
    const Vector2d d = truth.state.p_W_B.head<2>() - truth.platform->top_center_W.head<2>();
    const double c = std::cos(truth.platform->yaw_rad), s = std::sin(truth.platform->yaw_rad);
    r.final_in_platform_m = Vector2d(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
    r.platform_size_m = truth.platform->size_m.head<2>();
  } else if (truth.opening) {
    r.estimate_error_W = autonomy.final_estimate() - truth.opening->center_W;
  }
  if (onboard) {
    const estimator::State s = onboard->state();
    r.pose_error_W = s.p_W_B - truth.state.p_W_B;
    r.estimate_reasons = estimate_reasons_text(estimate_reasons);
    r.flow_fused = s.counters.fused(estimator::Sensor::kFlow);
    r.flow_rejected = s.counters.rejected(estimator::Sensor::kFlow);
    r.terrain_resets = static_cast<int>(s.counters.terrain_resets);
    r.flow_on_floor = s.counters.flow_on_floor;
    r.flow_inflated = s.counters.flow_inflated;
    r.flow_velocity_resets = s.counters.flow_velocity_resets;
    const auto& flow_counts = onboard->onboard().flow().counts();
    r.flow_reasons.assign(flow_counts.begin(), flow_counts.end());
    if (truth.platform || truth.opening)
      r.estimate_error_rel_W = estimate_error_rel_W(truth, s, autonomy.final_estimate());
  }
  return r;
}

}  // namespace alight::autonomy::test
