#include "sim/simulator.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "common/params.hpp"

namespace alight::sim {

namespace {
// Independent streams per purpose, so e.g. rendering or not never changes the mocap noise.
uint64_t substream(uint64_t seed, uint64_t k) {
  uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (k + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

PoseBufferParams history_params() {
  PoseBufferParams p;
  p.history_s = 0.5;
  p.max_gap_s = 0.05;
  return p;
}

// Rows rendered from one pose under a rolling shutter: 0.32 ms of readout at 40 us per row, a
// tenth of a pixel of motion at 1 m/s from 1.5 m and an eighth of a 250 Hz vibration's period.
constexpr int kRowsPerBand = 8;

// From row 0's exposure to the last row's [us]; 0 for a global shutter.
int64_t readout_us(const CameraParams& c, int rows) {
  return c.effects.rolling_shutter ? std::llround(c.effects.line_delay_s * 1e6 * (rows - 1)) : 0;
}

PoseSample to_pose(const VehicleState& s, int64_t utime) {
  PoseSample p;
  p.utime = utime;
  p.p_W_B = s.p_W_B;
  p.q_WB = s.q_WB;
  p.v_W_B = s.v_W_B;
  p.omega_B = s.omega_B;
  return p;
}
}  // namespace

Scene simulated_scene(const Scenario& scenario, uint64_t seed) {
  return build_scene(scenario, substream(seed, 0));
}

Simulator::Simulator(const Scenario& scenario, const VehicleParams& vehicle, uint64_t seed,
                     std::optional<CameraRig> camera, std::optional<CameraRig> flow_camera)
    : scenario_(scenario),
      vehicle_(vehicle),
      scene_(std::make_unique<Scene>(simulated_scene(scenario, seed))),
      dynamics_(std::make_unique<Dynamics>(vehicle, *scene_)),
      now_utime_(scenario.start_utime),
      start_utime_(scenario.start_utime),
      dt_us_(std::max<int64_t>(1, std::llround(scenario.physics_dt_s * 1e6))),
      wind_rng_(substream(seed, 1)),
      mocap_(scenario.mocap, scenario.start_utime, substream(seed, 2)),
      imu_(scenario.imu, scenario.start_utime, substream(seed, 3)),
      rangefinder_(scenario.rangefinder, scenario.start_utime, substream(seed, 5)),
      baro_(scenario.baro, scenario.start_utime, substream(seed, 6)),
      history_(history_params()) {
  const double rotor_radius_m = 0.5 * vehicle.rotor_tip_span_m;
  if (scenario.platform && scenario.randomize.start_clearance_m < rotor_radius_m &&
      (scenario.randomize.platform_xy_m > 0 || scenario.randomize.platform_yaw_deg > 0))
    throw ParamError(scenario.file, "randomize.start_clearance_m",
                     std::to_string(scenario.randomize.start_clearance_m),
                     "must be at least the rotor-tip radius of vehicle " + vehicle.name + " (" +
                         std::to_string(rotor_radius_m) +
                         " m): a seeded platform could stand "
                         "under its rotors at the start");
  if (scenario.platform && scenario.platform->moving && scene_->platform_box >= 0) {
    // Its own stream (the sea state's draws), so a moving platform changes no other draw.
    platform_motion_.emplace(scenario.platform->motion, scene_->platform->top_center_W,
                             scene_->platform->yaw_rad, substream(seed, 8));
    place_platform(now_utime_);
  }
  const Vector3d& p0 = scenario.start_position_m;
  state_.p_W_B = Vector3d(p0.x(), p0.y(), p0.z() > 0 ? p0.z() : dynamics_->resting_height(0.0));
  state_.q_WB = Quaterniond(rotation_from_rpy(0, 0, scenario.start_yaw_deg * M_PI / 180.0));
  state_.yaw_des_rad = scenario.start_yaw_deg * M_PI / 180.0;
  if (scenario.wind.gust_sigma_mps > 0) {
    std::normal_distribution<double> n(0.0, scenario.wind.gust_sigma_mps);
    gust_W_ = Vector3d(n(wind_rng_), n(wind_rng_), 0.3 * n(wind_rng_));
  }
  last_command_utime_ = now_utime_;
  history_.add(to_pose(state_, now_utime_));
  if (scenario.mocap.enabled) mocap_.update(now_utime_, to_pose(state_, now_utime_));
  camera_.params = scenario.camera;
  camera_.rig = std::move(camera);
  camera_.rng.seed(substream(seed, 4));
  start_camera(camera_);
  flow_camera_.params = scenario.flow_camera;
  flow_camera_.rig = std::move(flow_camera);
  flow_camera_.rng.seed(substream(seed, 7));
  start_camera(flow_camera_);
  // The camera effects' streams: new ones, so the streams above stay as they were.
  camera_.fx_rng.seed(substream(seed, 8));
  flow_camera_.fx_rng.seed(substream(seed, 9));
  vibration_ = Vibration(scenario.vibration, substream(seed, 10));
}

void Simulator::start_camera(CameraStream& c) {
  if (!c.rig || !c.params.enabled) return;
  const CameraEffects& fx = c.params.effects;
  c.rig->model = with_lens(c.rig->model, fx);
  c.renderer = std::make_unique<Renderer>(c.rig->model, c.params.supersample);
  if (fx.exposure_steps) c.exposure_steps = ExposureSteps(fx, c.params.rate_hz);
  if (fx.vignetting) c.vignette = vignetting_map(c.rig->model, fx.vignetting_corner);
  c.auto_gain = AutoGain(c.params);
  c.period_us = std::llround(1e6 / c.params.rate_hz);
  c.next_frame_utime = now_utime_ + c.period_us;
  // A table of unit normal noise, read at a random offset per frame: per-pixel Gaussian draws
  // would cost more than the rendering.
  const size_t n = static_cast<size_t>(c.rig->model.width) * c.rig->model.height;
  c.noise.resize(2 * n);
  std::normal_distribution<float> g(0.f, 1.f);
  for (auto& v : c.noise) v = g(c.rng);
}

void Simulator::place_platform(int64_t utime) {
  if (!platform_motion_) return;
  const PlatformPose P = platform_motion_->at(motion_time_s(utime));
  Box& b = scene_->boxes[static_cast<size_t>(scene_->platform_box)];
  b.set_rotation(P.R_WO);
  b.center_W = P.top_center_W - P.R_WO.col(2) * b.half_size_m.z();
  b.moving = true;
  b.omega_W = P.omega_W;
  b.v_W = P.velocity_at(b.center_W);
  PlatformTruth& t = *scene_->platform;
  t.top_center_W = P.top_center_W;
  t.yaw_rad = P.yaw_rad;
  t.moving = true;
  t.roll_rad = P.roll_rad;
  t.pitch_rad = P.pitch_rad;
  t.v_W = P.v_W;
  t.omega_W = P.omega_W;
}

void Simulator::set_state(const VehicleState& state) {
  state_ = state;
  history_ = PoseBuffer(history_params());
  history_.add(to_pose(state_, now_utime_));
  rest_s_ = 0.0;
}

void Simulator::set_render_threads(int n) {
  render_threads_ = std::max(1, n);
  if (camera_.renderer) camera_.renderer->set_threads(render_threads_);
  if (flow_camera_.renderer) flow_camera_.renderer->set_threads(render_threads_);
}

void Simulator::inject_mocap_dropout(int64_t from_utime, int64_t to_utime) {
  mocap_.add_dropout(from_utime, to_utime);
}

void Simulator::step(const AttitudeCommand& cmd, int64_t until_utime) {
  cmd_ = cmd;
  while (now_utime_ + dt_us_ <= until_utime) {
    last_command_utime_ = now_utime_;
    physics_step();
  }
}

void Simulator::command(const AttitudeCommand& cmd) {
  last_command_utime_ = now_utime_;
  const bool in_the_air = last_.contact == Contact::kNone || last_.contact == Contact::kWall;
  if (!cmd.armed && !cmd.forced && state_.armed && cmd_.armed && in_the_air) {
    ++disarms_refused_;
    return;
  }
  cmd_ = cmd;
}

AttitudeCommand Simulator::autopilot_command() {
  const VehicleParams& V = vehicle_;
  const double silent_s = static_cast<double>(now_utime_ - last_command_utime_) * 1e-6;
  if (silent_s <= V.cmd_loss_timeout_s) {
    cmd_lost_since_.reset();
    cmd_loss_rest_since_.reset();
    // Disarmed by the failsafe, it arms again only after a disarmed command (as an autopilot
    // needs an explicit arm after a failsafe landing), not on the first armed one that arrives.
    if (cmd_loss_disarmed_ && cmd_.armed) return AttitudeCommand{cmd_.utime};
    cmd_loss_disarmed_ = false;
    return cmd_;
  }
  if (!cmd_lost_since_) {
    // Only a flying vehicle needs the failsafe: disarmed stays disarmed.
    if (!cmd_.armed) return cmd_;
    cmd_lost_since_ = now_utime_;
  }
  AttitudeCommand fs;
  fs.utime = cmd_.utime;
  fs.armed = !cmd_loss_disarmed_;
  if (cmd_loss_disarmed_) return fs;
  const double t_s = static_cast<double>(now_utime_ - *cmd_lost_since_) * 1e-6;
  const bool descending = t_s >= V.cmd_loss_level_s;
  // Vertical speed loop on the autopilot's own estimate (here: the true velocity).
  constexpr double kVz_per_s = 5.0, kMaxAccel_mps2 = 3.0;
  const double vz_des = descending ? -V.cmd_loss_descent_mps : 0.0;
  const double a_z =
      std::clamp(kVz_per_s * (vz_des - state_.v_W_B.z()), -kMaxAccel_mps2, kMaxAccel_mps2);
  const double cos_tilt = std::max(0.5, state_.q_WB.toRotationMatrix()(2, 2));
  fs.thrust_N = std::clamp(V.mass_kg * (9.81 + a_z) / cos_tilt, 0.0, V.max_thrust_N);
  // Resting on the ground while descending: disarm (the autopilot's land detector).
  const bool resting =
      descending && last_.contact != Contact::kNone && std::abs(state_.v_W_B.z()) < 0.1;
  if (!resting) {
    cmd_loss_rest_since_.reset();
  } else if (!cmd_loss_rest_since_) {
    cmd_loss_rest_since_ = now_utime_;
  } else if (static_cast<double>(now_utime_ - *cmd_loss_rest_since_) * 1e-6 >=
             V.cmd_loss_disarm_after_s) {
    cmd_loss_disarmed_ = true;
    fs.armed = false;
    fs.thrust_N = 0.0;
  }
  return fs;
}

void Simulator::advance_to(int64_t until_utime) {
  while (now_utime_ + dt_us_ <= until_utime) physics_step();
}

void Simulator::physics_step() {
  const double dt = dt_us_ * 1e-6;
  // Gusts: first-order Gauss-Markov per axis (the vertical weaker), steady mean added.
  const WindParams& w = scenario_.wind;
  if (w.gust_sigma_mps > 0) {
    std::normal_distribution<double> n(0.0, 1.0);
    const double a = std::exp(-dt / w.gust_tau_s);
    const double b = w.gust_sigma_mps * std::sqrt(1 - a * a);
    const double nx = n(wind_rng_), ny = n(wind_rng_), nz = n(wind_rng_);
    gust_W_ = a * gust_W_ + b * Vector3d(nx, ny, 0.3 * nz);
  }
  const Vector3d wind = w.steady_mps + gust_W_;

  last_ = dynamics_->step(state_, autopilot_command(), wind, dt);
  now_utime_ += dt_us_;
  place_platform(now_utime_);
  after_step(dt, true);
}

void Simulator::follow(const std::function<VehicleState(int64_t)>& state_at, int64_t until_utime,
                       double contact_margin_m) {
  const double dt = dt_us_ * 1e-6;
  while (now_utime_ + dt_us_ <= until_utime) {
    now_utime_ += dt_us_;
    place_platform(now_utime_);
    state_ = state_at(now_utime_);
    last_ = dynamics_->contacts(state_, contact_margin_m);
    after_step(dt, false);
  }
}

void Simulator::after_step(double dt, bool imu) {
  // Outcome flags.
  const Matrix3d R = state_.q_WB.toRotationMatrix();
  const double tilt = std::acos(std::clamp(R(2, 2), -1.0, 1.0));
  const bool touching_ground = last_.contact != Contact::kNone;
  if (last_.rim_touch || (touching_ground && tilt > 35.0 * M_PI / 180.0)) tipped_ = true;
  const bool wall = last_.contact == Contact::kWall || last_.contact == Contact::kFrame;
  if (wall) {
    collided_ = true;
    if (!wall_contact_) ++n_collisions_;
  }
  wall_contact_ = wall;
  const Vector2d off = state_.p_W_B.head<2>() - scenario_.area_center_xy_m;
  if ((off.cwiseAbs() - 0.5 * scenario_.area_size_m).maxCoeff() > 0 ||
      state_.p_W_B.z() > scenario_.area_height_m)
    out_of_area_ = true;
  // At rest on the platform: relative to it when it moves (carried along on a deck).
  Vector3d v_rest = state_.v_W_B, omega_rest = state_.omega_B;
  if (platform_motion_) {
    const Box& deck = scene_->boxes[static_cast<size_t>(scene_->platform_box)];
    v_rest -= deck.velocity_at(state_.p_W_B);
    omega_rest -= R.transpose() * deck.omega_W;
  }
  const bool at_rest = !state_.armed && last_.feet_on_platform_top == 4 && v_rest.norm() < 0.05 &&
                       omega_rest.norm() < 0.2;
  rest_s_ = at_rest ? rest_s_ + dt : 0.0;
  landed_ = rest_s_ >= 0.3 && !tipped_;

  const PoseSample truth = to_pose(state_, now_utime_);
  history_.add(truth);
  if (scenario_.mocap.enabled) mocap_.update(now_utime_, truth);
  if (scenario_.imu.enabled && imu) {
    if (vibration_.enabled()) {
      // The IMU shakes with the frame (imu_share of it): the vibration's mean rate and
      // acceleration over this step, so the IMU's average over its sample is the vibration's
      // exactly; its specific force is seen in the shaken axes (small angles).
      const double share = vibration_.params().imu_share;
      const double t1 = static_cast<double>(now_utime_ - scenario_.start_utime) * 1e-6;
      const double t0 = t1 - dt;
      const Vector3d tilt = share * vibration_.angle(t1);
      const Vector3d& f = last_.specific_force_B;
      imu_.update(now_utime_, dt_us_, f - tilt.cross(f) + share * vibration_.mean_accel(t0, t1),
                  state_.omega_B + share * vibration_.mean_rate(t0, t1));
    } else {
      imu_.update(now_utime_, dt_us_, last_.specific_force_B, state_.omega_B);
    }
  }
  if (scenario_.rangefinder.enabled) rangefinder_.update(now_utime_, truth.X_WB(), *scene_);
  if (scenario_.baro.enabled) baro_.update(now_utime_, state_.p_W_B);
  if (camera_.renderer) schedule_camera(camera_);
  if (flow_camera_.renderer) schedule_camera(flow_camera_);
}

Isometry3d Simulator::camera_pose_at(double t_us, const Isometry3d& X_BC) const {
  const auto pose = history_.at(std::llround(t_us));
  Isometry3d X_WB =
      pose ? pose->X_WB() : make_transform(state_.q_WB.toRotationMatrix(), state_.p_W_B);
  if (vibration_.enabled())
    X_WB = X_WB * vibration_.jitter((t_us - static_cast<double>(scenario_.start_utime)) * 1e-6);
  return camera_in_world(X_WB, X_BC);
}

void Simulator::schedule_camera(CameraStream& cam) {
  const CameraParams& c = cam.params;
  const CameraEffects& fx = c.effects;
  const int rows = cam.rig->model.height;
  const int64_t half_exposure = std::llround(0.5 * c.exposure_s * 1e6);
  // A frame is complete when its last row's exposure has ended.
  if (now_utime_ < cam.next_frame_utime + half_exposure + readout_us(c, rows)) return;
  PendingFrame f;
  f.utime = cam.next_frame_utime;
  f.stamp = f.utime;
  f.seq = ++cam.frame_seq;
  cam.next_frame_utime += cam.period_us;
  std::normal_distribution<double> g(0.0, 1.0);
  f.gain = std::clamp(1.0 + c.gain_jitter * g(cam.rng), 0.2, 3.0);
  f.noise_offset = std::uniform_int_distribution<size_t>(0, cam.noise.size() / 2)(cam.rng);
  const Isometry3d X_BC = cam.rig->mount.X_BC();
  if (!fx.rolling_shutter && !vibration_.enabled()) {
    const int k = c.motion_blur_samples;
    for (int i = 0; i < k; ++i) {
      const int64_t t =
          k == 1 ? f.utime : f.utime - half_exposure + (2 * half_exposure * i) / (k - 1);
      const auto pose = history_.at(t);
      const Isometry3d X_WB =
          pose ? pose->X_WB() : make_transform(state_.q_WB.toRotationMatrix(), state_.p_W_B);
      f.X_WC.push_back(camera_in_world(X_WB, X_BC));
      f.X_WC_utime.push_back(t);
    }
  } else {
    // Bands of rows, each from the poses over its own exposure. A vibration blurs within the
    // exposure: four poses per period of its highest harmonic, at most 8 (each pose is a
    // rendering: 8 keep a 12 ms exposure at 250 Hz, three periods, to a blur of that extent).
    int k = c.motion_blur_samples;
    if (vibration_.enabled())
      k = std::max(
          k, std::min(8, static_cast<int>(std::ceil(4 * c.exposure_s * vibration_.max_hz()))));
    const double line_us = fx.rolling_shutter ? fx.line_delay_s * 1e6 : 0.0;
    const int band = fx.rolling_shutter ? kRowsPerBand : rows;
    for (int r0 = 0; r0 < rows; r0 += band) {
      const int r1 = std::min(rows, r0 + band);
      const double t_mid = static_cast<double>(f.utime) + line_us * 0.5 * (r0 + r1 - 1);
      std::vector<Isometry3d> poses;
      std::vector<int64_t> times;
      for (int i = 0; i < k; ++i) {
        const double t =
            k == 1 ? t_mid : t_mid - half_exposure + (2.0 * half_exposure * i) / (k - 1);
        poses.push_back(camera_pose_at(t, X_BC));
        times.push_back(std::llround(t));
      }
      f.band_rows.push_back(r0);
      f.band_X_WC.push_back(std::move(poses));
      f.band_utime.push_back(std::move(times));
    }
    f.band_rows.push_back(rows);
    f.X_WC = {camera_pose_at(static_cast<double>(f.utime), X_BC)};  // row 0's, at the stamp
  }
  if (fx.exposure_steps) f.ev = cam.exposure_steps.next_ev(cam.fx_rng);
  if (fx.driver) {
    const DriverDraw d = draw_driver(fx, cam.fx_rng);
    if (d.dropped) {
      ++cam.frames_dropped;
      return;
    }
    f.duplicate = d.duplicated;
    // Stamps stay increasing, as a driver's do.
    f.stamp = std::max<int64_t>(f.utime + std::llround(d.stamp_error_s * 1e6), cam.last_stamp + 1);
    cam.last_stamp = f.stamp;
  }
  if (cam.pending) ++cam.frames_skipped;
  cam.pending = std::move(f);
}

std::vector<MocapSample> Simulator::take_mocap() { return mocap_.take(now_utime_); }

std::vector<ImuSample> Simulator::take_imu() { return imu_.take(); }

std::vector<RangeSample> Simulator::take_range() { return rangefinder_.take(now_utime_); }

std::vector<BaroSample> Simulator::take_baro() { return baro_.take(now_utime_); }

std::optional<CameraFrame> Simulator::take_camera() { return take_frame(camera_); }

std::optional<CameraFrame> Simulator::take_flow_camera() { return take_frame(flow_camera_); }

std::optional<CameraFrame> Simulator::take_frame(CameraStream& cam) {
  if (!cam.pending) return std::nullopt;
  const int64_t latency = std::llround(cam.params.latency_s * 1e6);
  const int64_t half_exposure = std::llround(0.5 * cam.params.exposure_s * 1e6);
  const CameraModel& model = cam.rig->model;
  const int64_t readout = readout_us(cam.params, model.height);
  if (now_utime_ < cam.pending->utime + half_exposure + readout + latency) return std::nullopt;
  const PendingFrame f = std::move(*cam.pending);
  cam.pending.reset();
  const CameraEffects& fx = cam.params.effects;
  CameraFrame out;
  out.utime = f.stamp;
  out.seq = f.seq;
  out.exposure_s = cam.params.exposure_s;
  out.line_delay_s = fx.rolling_shutter ? fx.line_delay_s : 0.0;
  out.exposure_ev = f.ev;
  out.X_WC = f.X_WC[f.X_WC.size() / 2];
  if (f.duplicate && !cam.last_pixels.empty()) {
    // The driver hands the previous buffer out again: its pixels, this frame's seq and stamp.
    out.duplicate = true;
    out.gain = cam.auto_gain.gain();
    out.pixels = cam.last_pixels.clone();
    return out;
  }
  cv::Mat acc(model.height, model.width, CV_32F, cv::Scalar(0));
  double gain = f.gain * cam.auto_gain.gain();
  if (f.ev != 0.0) gain *= std::exp2(f.ev);
  // A moving platform where it was at each of the exposure's instants, as the camera: smeared
  // by its motion relative to the camera (a vehicle keeping pace with it sees it sharp over a
  // smeared floor), and skewed by a rolling shutter's readout as the floor is.
  if (f.band_X_WC.empty()) {
    const float w = static_cast<float>(gain / f.X_WC.size());
    for (size_t i = 0; i < f.X_WC.size(); ++i) {
      place_platform(f.X_WC_utime[i]);
      cam.renderer->accumulate(*scene_, f.X_WC[i], w, acc);
    }
  } else {
    for (size_t b = 0; b < f.band_X_WC.size(); ++b) {
      const float w = static_cast<float>(gain / f.band_X_WC[b].size());
      for (size_t i = 0; i < f.band_X_WC[b].size(); ++i) {
        place_platform(f.band_utime[b][i]);
        cam.renderer->accumulate_rows(*scene_, f.band_X_WC[b][i], w, f.band_rows[b],
                                      f.band_rows[b + 1], acc);
      }
    }
  }
  place_platform(now_utime_);
  if (!cam.vignette.empty()) cv::multiply(acc, cam.vignette, acc);
  cam.auto_gain.update(acc, gain);
  const float sigma = static_cast<float>(cam.params.noise_sigma);
  out.gain = gain;
  const float* noise = cam.noise.data() + f.noise_offset;
  for (int v = 0; v < model.height; ++v) {
    float* a = acc.ptr<float>(v);
    const float* nz = noise + static_cast<size_t>(v) * model.width;
    for (int u = 0; u < model.width; ++u) a[u] += sigma * nz[u];
  }
  // Rounded to the nearest (ties to even) and saturated, as saturate_cast<uchar> per pixel.
  acc.convertTo(out.pixels, CV_8U);
  if (fx.driver && fx.dup_prob > 0) cam.last_pixels = out.pixels.clone();
  return out;
}

AutoGain::AutoGain(const CameraParams& params)
    : params_(params), log_brightness_(std::log(params.auto_gain_target)) {}

void AutoGain::update(const cv::Mat& linear, double frame_gain) {
  assert(linear.type() == CV_32F && frame_gain > 0);
  if (!params_.auto_gain || linear.empty()) return;
  std::vector<float> samples;
  samples.reserve(static_cast<size_t>((linear.rows + 3) / 4) * ((linear.cols + 3) / 4));
  for (int v = 0; v < linear.rows; v += 4) {
    const float* a = linear.ptr<float>(v);
    for (int u = 0; u < linear.cols; u += 4) samples.push_back(a[u]);
  }
  const size_t k = std::min(samples.size() - 1,
                            static_cast<size_t>(params_.auto_gain_quantile * samples.size()));
  std::nth_element(samples.begin(), samples.begin() + k, samples.end());
  // A black view meters as 1 grey level: its logarithm stays finite.
  const double unit_brightness = std::max(1.0, samples[k] / frame_gain);
  log_brightness_ += params_.auto_gain_rate * (std::log(unit_brightness) - log_brightness_);
  const double wanted =
      std::clamp(params_.auto_gain_target / std::exp(log_brightness_), params_.auto_gain_min, 1.0);
  if (std::abs(std::log(wanted / gain_)) > std::log1p(params_.auto_gain_tolerance)) gain_ = wanted;
}

cv::Mat Simulator::render(const CameraMount& mount, const CameraModel& model,
                          const Isometry3d& X_WB) const {
  const Renderer* r = nullptr;
  auto same = [&](const CameraModel& m) {
    return m.width == model.width && m.height == model.height && m.fx == model.fx &&
           m.fy == model.fy && m.cx == model.cx && m.cy == model.cy && m.D == model.D &&
           m.distortion == model.distortion;
  };
  if (camera_.renderer && same(camera_.renderer->model()) && camera_.params.supersample == 1) {
    r = camera_.renderer.get();
  } else {
    if (!adhoc_renderer_ || !same(adhoc_renderer_->model()))
      adhoc_renderer_ = std::make_unique<Renderer>(model, 1);
    adhoc_renderer_->set_threads(render_threads_);
    r = adhoc_renderer_.get();
  }
  return r->render(*scene_, camera_in_world(X_WB, mount.X_BC()));
}

Truth Simulator::truth() const {
  Truth t;
  t.utime = now_utime_;
  t.scenario = scenario_.name;
  t.state = state_;
  t.platform = scene_->platform;
  t.opening = scene_->opening;
  t.contact = last_.contact;
  t.landed = landed_;
  t.tipped = tipped_;
  t.collided = collided_;
  t.n_collisions = n_collisions_;
  t.out_of_area = out_of_area_;
  t.command_lost = cmd_lost_since_.has_value();
  t.wind_W = scenario_.wind.steady_mps + gust_W_;
  return t;
}

}  // namespace alight::sim
