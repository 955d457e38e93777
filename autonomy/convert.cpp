#include "autonomy/convert.hpp"

#include <cmath>
#include <utility>

namespace alight::autonomy {

int8_t mission_to_msg(Mission m) {
  switch (m) {
    case Mission::kLanding:
      return target_t::MISSION_LANDING;
    case Mission::kIngress:
      return target_t::MISSION_INGRESS;
    case Mission::kNone:
      break;
  }
  return target_t::MISSION_NONE;
}

Mission mission_from_msg(int8_t m) {
  if (m == target_t::MISSION_LANDING) return Mission::kLanding;
  if (m == target_t::MISSION_INGRESS) return Mission::kIngress;
  return Mission::kNone;
}

int8_t phase_to_msg(Phase p) {
  using S = autonomy_status_t;
  switch (p) {
    case Phase::kIdle:
      return S::PHASE_IDLE;
    case Phase::kTakeoff:
      return S::PHASE_TAKEOFF;
    case Phase::kHover:
      return S::PHASE_HOVER;
    case Phase::kDetection:
      return S::PHASE_DETECTION;
    case Phase::kRefinement:
      return S::PHASE_REFINEMENT;
    case Phase::kApproach:
      return S::PHASE_APPROACH;
    case Phase::kFinalDescent:
      return S::PHASE_FINAL_DESCENT;
    case Phase::kLanded:
      return S::PHASE_LANDED;
    case Phase::kDone:
      return S::PHASE_DONE;
    case Phase::kHold:
      return S::PHASE_HOLD;
    case Phase::kFailsafe:
      return S::PHASE_FAILSAFE;
    case Phase::kKilled:
      return S::PHASE_KILLED;
  }
  return S::PHASE_IDLE;
}

int8_t failsafe_to_msg(Failsafe f) {
  using S = autonomy_status_t;
  switch (f) {
    case Failsafe::kNone:
      return S::FAILSAFE_NONE;
    case Failsafe::kPoseStale:
      return S::FAILSAFE_POSE_STALE;
    case Failsafe::kPoseLost:
      return S::FAILSAFE_POSE_LOST;
    case Failsafe::kOperatorAbort:
      return S::FAILSAFE_OPERATOR_ABORT;
    case Failsafe::kKill:
      return S::FAILSAFE_KILL;
    case Failsafe::kEstimateLost:
      return S::FAILSAFE_ESTIMATE_LOST;
    case Failsafe::kVisionDisagrees:
      return S::FAILSAFE_VISION_DISAGREES;
    case Failsafe::kPlatformTooFast:
      return S::FAILSAFE_PLATFORM_TOO_FAST;
  }
  return S::FAILSAFE_NONE;
}

ImuSample from_msg(const imu_t& msg) {
  ImuSample s;
  s.utime = msg.utime;
  s.accel_B = Vector3d(msg.accel_B[0], msg.accel_B[1], msg.accel_B[2]);
  s.gyro_B = Vector3d(msg.gyro_B[0], msg.gyro_B[1], msg.gyro_B[2]);
  return s;
}

imu_t to_msg(const ImuSample& imu, int64_t seq) {
  imu_t m{};
  m.utime = imu.utime;
  m.seq = seq;
  for (int i = 0; i < 3; ++i) {
    m.accel_B[i] = imu.accel_B[i];
    m.gyro_B[i] = imu.gyro_B[i];
  }
  return m;
}

TargetMeasurement from_msg(const target_t& msg) {
  TargetMeasurement t;
  t.utime = msg.utime;
  t.mission = mission_from_msg(msg.mission);
  t.found = msg.found;
  t.partial = !msg.found && (msg.reason == target_t::REASON_PARTIAL_VIEW ||
                             msg.reason == target_t::REASON_LOW_PARALLAX ||
                             msg.reason == target_t::REASON_TOP_PARALLAX_GAP ||
                             msg.reason == target_t::REASON_TOP_RUNS_ON);
  t.cut = !msg.found && (msg.reason == target_t::REASON_PARTIAL_VIEW ||
                         msg.reason == target_t::REASON_TOP_RUNS_ON);
  t.p_W_target = Vector3d(msg.p_W_target[0], msg.p_W_target[1], msg.p_W_target[2]);
  t.n_W = Vector3d(msg.n_W[0], msg.n_W[1], msg.n_W[2]);
  t.size_m = Vector2d(msg.size_m[0], msg.size_m[1]);
  t.yaw_rad = msg.target_yaw_rad;
  return t;
}

target_t to_msg(const TargetMeasurement& t, int64_t seq) {
  target_t m{};
  m.utime = t.utime;
  m.ref_utime = t.utime;
  m.seq = seq;
  m.mission = mission_to_msg(t.mission);
  m.found = t.found;
  m.reason = t.found     ? target_t::REASON_OK
             : t.partial ? target_t::REASON_PARTIAL_VIEW
                         : target_t::REASON_NO_TARGET_PLANE;
  for (int i = 0; i < 3; ++i) {
    m.p_W_target[i] = t.p_W_target[i];
    m.n_W[i] = t.n_W[i];
  }
  m.size_m[0] = t.size_m.x();
  m.size_m[1] = t.size_m.y();
  m.target_yaw_rad = t.yaw_rad;
  return m;
}

OperatorCommand from_msg(const operator_cmd_t& msg) {
  OperatorCommand c;
  c.utime = msg.utime;
  c.seq = msg.seq;
  c.sender = msg.sender;
  switch (msg.command) {
    case operator_cmd_t::CMD_TAKEOFF:
      c.command = Command::kTakeoff;
      break;
    case operator_cmd_t::CMD_GO:
      c.command = Command::kGo;
      break;
    case operator_cmd_t::CMD_ABORT:
      c.command = Command::kAbort;
      break;
    case operator_cmd_t::CMD_LAND_HERE:
      c.command = Command::kLandHere;
      break;
    case operator_cmd_t::CMD_KILL:
      c.command = Command::kKill;
      break;
    case operator_cmd_t::CMD_NUDGE:
      c.command = Command::kNudge;
      break;
    default:
      c.command = Command::kNone;
      break;
  }
  c.mission = mission_from_msg(msg.mission);
  c.nudge_W = Vector3d(msg.nudge_W[0], msg.nudge_W[1], msg.nudge_W[2]);
  // Never kInternal from the wire: only the node itself issues internal commands.
  c.auth = msg.auth == operator_cmd_t::AUTH_NONE ? CommandAuth::kNone : CommandAuth::kHmacSha256;
  return c;
}

namespace {
template <class T>
std::optional<T> refuse(std::string* why, const std::string& text) {
  if (why) *why = text;
  return std::nullopt;
}
bool finite(const double* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}
bool within(const double* v, int n, double bound) {
  for (int i = 0; i < n; ++i)
    if (!(std::abs(v[i]) <= bound)) return false;  // NaN-safe
  return true;
}
}  // namespace

std::optional<ImuSample> imu_from_msg(const imu_t& m, std::string* why) {
  if (!finite(m.accel_B, 3)) return refuse<ImuSample>(why, "imu: non-finite accel_B");
  if (!finite(m.gyro_B, 3)) return refuse<ImuSample>(why, "imu: non-finite gyro_B");
  if (!within(m.accel_B, 3, kMaxAccelMps2))
    return refuse<ImuSample>(why, "imu: accel_B beyond any IMU's range");
  if (!within(m.gyro_B, 3, kMaxGyroRadps))
    return refuse<ImuSample>(why, "imu: gyro_B beyond any IMU's range");
  return from_msg(m);
}

std::optional<TargetMeasurement> target_from_msg(const target_t& m, std::string* why) {
  using T = TargetMeasurement;
  if (!finite(m.p_W_target, 3)) return refuse<T>(why, "target: non-finite p_W_target");
  if (!finite(m.n_W, 3)) return refuse<T>(why, "target: non-finite n_W");
  if (!finite(m.size_m, 2)) return refuse<T>(why, "target: non-finite size_m");
  if (!std::isfinite(m.target_yaw_rad)) return refuse<T>(why, "target: non-finite target_yaw_rad");
  if (m.size_m[0] < 0 || m.size_m[1] < 0) return refuse<T>(why, "target: negative size_m");
  TargetMeasurement t = from_msg(m);
  if (t.found || t.partial) {
    // Measured geometry must be usable: a zero normal has no direction to approach along.
    if (t.n_W.norm() < 1e-6) return refuse<T>(why, "target: zero normal n_W");
    t.n_W.normalize();
  }
  return t;
}

std::optional<PlatformMeasurement> platform_from_msg(const platform_motion_t& m, std::string* why) {
  using P = PlatformMeasurement;
  if (m.version > platform_motion_t::VERSION)
    return refuse<P>(why, "platform: version " + std::to_string(m.version) + " is newer than " +
                              std::to_string(platform_motion_t::VERSION));
  if (!m.found) return std::nullopt;
  if (!finite(m.p_W, 3) || !finite(m.v_W, 3) || !finite(m.cov_p_W, 9) || !finite(m.cov_v_W, 9) ||
      !std::isfinite(m.yaw_rad) || !std::isfinite(m.yaw_rate_rps) || !std::isfinite(m.var_yaw) ||
      !std::isfinite(m.var_yaw_rate) || !finite(m.size_m, 2))
    return refuse<P>(why, "platform: non-finite field");
  if (m.var_yaw < 0 || m.var_yaw_rate < 0 || m.cov_p_W[0] < 0 || m.cov_p_W[4] < 0 ||
      m.cov_v_W[0] < 0 || m.cov_v_W[4] < 0)
    return refuse<P>(why, "platform: negative variance");
  if (m.ref_utime >= m.utime) return refuse<P>(why, "platform: earlier frame not before");
  P p;
  p.utime = m.utime;
  p.ref_utime = m.ref_utime;
  for (int i = 0; i < 3; ++i) {
    p.p_W[i] = m.p_W[i];
    p.v_W[i] = m.v_W[i];
    for (int j = 0; j < 3; ++j) {
      p.cov_p_W(i, j) = m.cov_p_W[3 * i + j];
      p.cov_v_W(i, j) = m.cov_v_W[3 * i + j];
    }
  }
  p.yaw_rad = m.yaw_rad;
  p.yaw_rate_rps = m.yaw_rate_rps;
  p.var_yaw = m.var_yaw;
  p.var_yaw_rate = m.var_yaw_rate;
  p.size_m = Vector2d(m.size_m[0], m.size_m[1]);
  if (m.version >= 2) {
    // Where the top was placed from: only a camera above the plane placed it.
    if (!finite(m.camera_W, 3) || !finite(m.ref_camera_W, 3) || !std::isfinite(m.plane_z_m))
      return refuse<P>(why, "platform: non-finite camera_W, ref_camera_W or plane_z_m");
    if (!(m.camera_W[2] > m.plane_z_m) || !(m.ref_camera_W[2] > m.plane_z_m))
      return refuse<P>(why, "platform: a camera not above plane_z_m");
    p.camera_W = Vector3d(m.camera_W[0], m.camera_W[1], m.camera_W[2]);
    p.ref_camera_W = Vector3d(m.ref_camera_W[0], m.ref_camera_W[1], m.ref_camera_W[2]);
    p.plane_z_m = m.plane_z_m;
  }
  if (m.version >= 3) p.outline = m.outline;
  return p;
}

platform_motion_t to_msg(const PlatformMeasurement& p, int64_t seq) {
  platform_motion_t m{};
  m.utime = p.utime;
  m.ref_utime = p.ref_utime;
  m.seq = seq;
  m.version = platform_motion_t::VERSION;
  m.found = true;
  m.reason = platform_motion_t::REASON_OK;
  for (int i = 0; i < 3; ++i) {
    m.p_W[i] = p.p_W[i];
    m.v_W[i] = p.v_W[i];
    for (int j = 0; j < 3; ++j) {
      m.cov_p_W[3 * i + j] = p.cov_p_W(i, j);
      m.cov_v_W[3 * i + j] = p.cov_v_W(i, j);
    }
  }
  m.yaw_rad = p.yaw_rad;
  m.yaw_rate_rps = p.yaw_rate_rps;
  m.var_yaw = p.var_yaw;
  m.var_yaw_rate = p.var_yaw_rate;
  m.size_m[0] = p.size_m.x();
  m.size_m[1] = p.size_m.y();
  m.scale = 1.0;
  m.outline = p.outline;
  if (p.placed_from_cameras()) {
    for (int i = 0; i < 3; ++i) {
      m.camera_W[i] = p.camera_W[i];
      m.ref_camera_W[i] = p.ref_camera_W[i];
    }
    m.plane_z_m = p.plane_z_m;
  } else {
    // A version-2 message carries cameras; one without them is sent as version 1 says.
    m.version = 1;
  }
  return m;
}

std::optional<OperatorCommand> command_from_msg(const operator_cmd_t& m, std::string* why) {
  using C = OperatorCommand;
  if (m.command < operator_cmd_t::CMD_NONE || m.command > operator_cmd_t::CMD_NUDGE)
    return refuse<C>(why, "command: unknown code " + std::to_string(m.command));
  if (!finite(m.nudge_W, 3)) return refuse<C>(why, "command: non-finite nudge_W");
  if (!within(m.nudge_W, 3, kMaxNudgeM)) return refuse<C>(why, "command: nudge_W out of range");
  return from_msg(m);
}

static_assert(static_cast<int8_t>(CommandReject::kUnsigned) == autonomy_status_t::REJECT_UNSIGNED &&
              static_cast<int8_t>(CommandReject::kReplayed) == autonomy_status_t::REJECT_REPLAYED &&
              static_cast<int8_t>(CommandReject::kWrongSession) ==
                  autonomy_status_t::REJECT_WRONG_SESSION);
static_assert(kCommandRejectSlots ==
              sizeof(autonomy_status_t::cmds_rejected_by_reason) / sizeof(int32_t));

static_assert(kEstimateReasonNoFlow == state_estimate_t::REASON_NO_FLOW);
static_assert(kEstimateReasonNoRange == state_estimate_t::REASON_NO_RANGE);
// state_estimate_t.n_fused's rows: IMU, range, baro, flow.
constexpr int kRangeFused = 1;

std::string estimate_reasons_text(uint32_t reasons) {
  using E = state_estimate_t;
  static constexpr std::pair<int32_t, const char*> kNames[] = {
      {E::REASON_NOT_INITIALISED, "not_initialised"},
      {E::REASON_NO_FLOW, "no_flow"},
      {E::REASON_NO_RANGE, "no_range"},
      {E::REASON_NO_BARO, "no_baro"},
      {E::REASON_POSITION_UNCERTAIN, "position_uncertain"},
      {E::REASON_VELOCITY_UNCERTAIN, "velocity_uncertain"},
      {E::REASON_IMU_GAP, "imu_gap"},
      {E::REASON_IMU_STOPPED, "imu_stopped"},
      {E::REASON_HEIGHT_UNCERTAIN, "height_uncertain"}};
  std::string out;
  uint32_t known = 0;
  for (const auto& [bit, name] : kNames) {
    known |= static_cast<uint32_t>(bit);
    if (reasons & static_cast<uint32_t>(bit)) out += (out.empty() ? "" : "|") + std::string(name);
  }
  // A newer estimator's reasons: named by their bit rather than dropped.
  for (int b = 0; b < 32; ++b) {
    const uint32_t bit = 1u << b;
    if ((reasons & bit) && !(known & bit))
      out += (out.empty() ? "" : "|") + std::string("bit_") + std::to_string(b);
  }
  return out;
}

EstimateHealth from_msg(const state_estimate_t& msg) {
  EstimateHealth e;
  e.utime = msg.utime;
  e.level = msg.health == state_estimate_t::HEALTH_OK         ? EstimateHealth::Level::kOk
            : msg.health == state_estimate_t::HEALTH_DEGRADED ? EstimateHealth::Level::kDegraded
                                                              : EstimateHealth::Level::kLost;
  e.reasons = static_cast<uint32_t>(msg.health_reasons);
  e.text = estimate_reasons_text(e.reasons);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      e.position_cov(r, c) = 0.5 * (msg.cov_pva[9 * r + c] + msg.cov_pva[9 * c + r]);
  if (msg.n_fused[kRangeFused] > 0 && !(e.reasons & kEstimateReasonNoRange))
    e.terrain_m = msg.terrain_height_m;
  return e;
}

state_estimate_t to_msg(const EstimateHealth& e, int64_t seq) {
  state_estimate_t m{};
  m.utime = e.utime;
  m.seq = seq;
  m.orientation[0] = 1.0;
  for (int i = 0; i < 9; ++i) m.cov_pva[10 * i] = 1e-4;  // a small diagonal: a healthy filter
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (e.position_cov(r, c) != 0.0) m.cov_pva[9 * r + c] = e.position_cov(r, c);
  switch (e.level) {
    case EstimateHealth::Level::kOk:
      m.health = state_estimate_t::HEALTH_OK;
      break;
    case EstimateHealth::Level::kDegraded:
      m.health = state_estimate_t::HEALTH_DEGRADED;
      break;
    case EstimateHealth::Level::kLost:
      m.health = state_estimate_t::HEALTH_LOST;
      break;
  }
  m.health_reasons = static_cast<int32_t>(e.reasons);
  if (e.terrain_m) {
    m.terrain_height_m = *e.terrain_m;
    m.n_fused[kRangeFused] = 1;
  }
  return m;
}

std::optional<EstimateHealth> estimate_from_msg(const state_estimate_t& m, std::string* why) {
  using E = EstimateHealth;
  if (m.health != state_estimate_t::HEALTH_OK && m.health != state_estimate_t::HEALTH_DEGRADED &&
      m.health != state_estimate_t::HEALTH_LOST) {
    return refuse<E>(why, "estimate: unknown health " + std::to_string(m.health));
  }
  // The autonomy reads only the health, but an estimate with NaN in it is broken whatever its
  // health says: refused here, it is silent, and silence is LOST after estimate_silent_s.
  if (!finite(m.pos, 3)) return refuse<E>(why, "estimate: non-finite pos");
  if (!finite(m.vel, 3)) return refuse<E>(why, "estimate: non-finite vel");
  if (!finite(m.orientation, 4)) return refuse<E>(why, "estimate: non-finite orientation");
  if (!finite(m.angular_velocity_B, 3))
    return refuse<E>(why, "estimate: non-finite angular_velocity_B");
  if (!finite(m.accel_bias_B, 3) || !finite(m.gyro_bias_B, 3))
    return refuse<E>(why, "estimate: non-finite accel_bias_B / gyro_bias_B");
  if (!std::isfinite(m.terrain_height_m) || !std::isfinite(m.baro_offset_m))
    return refuse<E>(why, "estimate: non-finite terrain_height_m / baro_offset_m");
  if (!finite(m.cov_pva, 81)) return refuse<E>(why, "estimate: non-finite cov_pva");
  double q2 = 0.0;
  for (const double q : m.orientation) q2 += q * q;
  if (std::abs(std::sqrt(q2) - 1.0) > kMaxQuaternionNormError)
    return refuse<E>(why, "estimate: orientation not a unit quaternion");
  for (int i = 0; i < 9; ++i) {
    if (m.cov_pva[10 * i] < 0) return refuse<E>(why, "estimate: negative variance in cov_pva");
  }
  if (!within(m.pos, 3, kMaxEstimatePositionM))
    return refuse<E>(why, "estimate: pos beyond any flying area");
  for (int i = 0; i < 3; ++i) {
    // A position standard deviation wider than any flying area is no estimate.
    if (m.cov_pva[10 * i] > kMaxEstimatePositionM * kMaxEstimatePositionM)
      return refuse<E>(why, "estimate: position variance beyond any flying area");
  }
  return from_msg(m);
}

autonomy_status_t to_msg(const Status& s) {
  autonomy_status_t m{};
  m.utime = s.utime;
  m.mission = mission_to_msg(s.mission);
  m.phase = phase_to_msg(s.phase);
  m.phase_name = phase_name(s.phase);
  m.reason = s.reason;
  m.n_measurements = s.n_measurements;
  m.n_rejected = s.n_rejected;
  m.retries = s.retries;
  m.has_estimate = s.has_estimate;
  for (int i = 0; i < 3; ++i) {
    m.estimate_W[i] = s.estimate_W[i];
    m.setpoint_W[i] = s.setpoint_W[i];
    for (int j = 0; j < 3; ++j) m.covariance[3 * i + j] = s.covariance(i, j);
  }
  m.failsafe = failsafe_to_msg(s.failsafe);
  m.cmds_rejected = s.cmds_rejected;
  m.last_cmd_seq = s.last_cmd_seq;
  m.last_rejected_seq = s.last_rejected_seq;
  m.last_reject_reason = static_cast<int8_t>(s.last_reject_reason);
  for (int r = 0; r < kCommandRejectSlots; ++r)
    m.cmds_rejected_by_reason[r] = s.cmds_rejected_by_reason[r];
  m.geofence_clamped = s.geofence_clamped;
  m.mission_time_s = s.mission_time_s;
  return m;
}

}  // namespace alight::autonomy
