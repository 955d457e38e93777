#include "autonomy/autonomy.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <sstream>

namespace alight::autonomy {

const char* mission_name(Mission m) {
  switch (m) {
    case Mission::kNone:
      return "NONE";
    case Mission::kLanding:
      return "LANDING";
    case Mission::kIngress:
      return "INGRESS";
  }
  return "?";
}

const char* phase_name(Phase p) {
  switch (p) {
    case Phase::kIdle:
      return "IDLE";
    case Phase::kTakeoff:
      return "TAKEOFF";
    case Phase::kHover:
      return "HOVER";
    case Phase::kDetection:
      return "DETECTION";
    case Phase::kRefinement:
      return "REFINEMENT";
    case Phase::kApproach:
      return "APPROACH";
    case Phase::kFinalDescent:
      return "FINAL_DESCENT";
    case Phase::kLanded:
      return "LANDED";
    case Phase::kDone:
      return "DONE";
    case Phase::kHold:
      return "HOLD";
    case Phase::kFailsafe:
      return "FAILSAFE";
    case Phase::kKilled:
      return "KILLED";
  }
  return "?";
}

namespace {
constexpr double kPathLeadM = 0.3;  // the search carrot waits when the vehicle is this far behind

double seconds(int64_t dt_utime) { return static_cast<double>(dt_utime) * 1e-6; }

std::string fmt(double v, int precision = 3) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(precision);
  os << v;
  return os.str();
}

// Vantages at least this far from where the vehicle is: the vision needs a baseline of a few
// centimetres (waypoint.min_baseline_m) between its reference and current image [m].
constexpr double kMinVantageStepM = 0.08;

bool finite(const PoseSample& s) {
  return s.p_W_B.allFinite() && s.v_W_B.allFinite() && s.q_WB.coeffs().allFinite() &&
         s.omega_B.allFinite() && std::abs(s.q_WB.norm() - 1.0) < 1e-3;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  return v[mid];
}
}  // namespace

Autonomy::Autonomy(const AutonomyParams& params, const RestartState& restored)
    : params_(params),
      estimator_(params.refinement),
      sampler_(params.refinement, params.seed),
      touchdown_(params.landing),
      restored_(restored) {
  params_.validate();
  if (restored_.killed) {
    // An explicit KILL outlives the process that received it: motors off at once, whatever
    // the pose, and nothing (TAKEOFF, --auto-go) turns them on again.
    started_ = resumed_ = true;
    failsafe_ = Failsafe::kKill;
    enter(Phase::kKilled, "KILL latched before a restart: motors stay off");
  }
}

bool Autonomy::airborne() const {
  switch (phase_) {
    case Phase::kIdle:
    case Phase::kLanded:
    case Phase::kKilled:
      return false;
    case Phase::kFailsafe:
      return motors_on_;
    default:
      return true;
  }
}

bool Autonomy::pose_fresh() const {
  return pose_ && seconds(now_utime_ - pose_->utime) <= params_.failsafe.pose_stale_s;
}

void Autonomy::enter(Phase phase, std::string reason) {
  phase_ = phase;
  reason_ = std::move(reason);
  phase_start_utime_ = now_utime_;
}

void Autonomy::hold(const std::string& reason, Failsafe failsafe, double min_z_m) {
  const Vector3d p = pose_ ? pose_->p_W_B : sp_p_W_;
  hold_p_W_ = Vector3d(p.x(), p.y(), std::max(p.z(), min_z_m));
  failsafe_ = failsafe;
  enter(Phase::kHold, reason);
}

bool Autonomy::vision_silent() {
  // Counted from the phase's start too: a vision that never spoke since GO is as silent.
  const int64_t heard =
      std::max(phase_start_utime_, last_vision_utime_.value_or(phase_start_utime_));
  const double silent_s = seconds(now_utime_ - heard);
  if (silent_s <= params_.failsafe.vision_silent_s) return false;
  hold("no VISION_TARGET for " + fmt(silent_s, 1) +
           " s (camera or vision down): holding; waiting for the operator",
       Failsafe::kNone, 0.0);
  return true;
}

void Autonomy::enter_pose_lost() {
  failsafe_ = Failsafe::kPoseLost;
  failsafe_z_m_ = pose_ ? pose_->p_W_B.z() : sp_p_W_.z();
  failsafe_since_utime_ = now_utime_;
  pose_back_since_utime_.reset();
  if (pose_) sp_p_W_.head<2>() = pose_->p_W_B.head<2>();
  touchdown_.arm(now_utime_);
  enter(Phase::kFailsafe, "motion capture lost for > " + fmt(params_.failsafe.pose_lost_s, 1) +
                              " s: controlled descent, disarm on touch-down");
}

RestartState Autonomy::restart_state() const {
  RestartState r;
  r.killed = phase_ == Phase::kKilled;
  // Stale is a transient (the pose comes back); the one it interrupted is what is latched.
  r.failsafe = failsafe_ == Failsafe::kPoseStale ? failsafe_before_stale_ : failsafe_;
  if (!started_) r = restored_;  // nothing decided yet: keep what the previous one knew
  r.motors_on = started_ ? motors_on_ : restored_.motors_on;
  return r;
}

void Autonomy::start_from_first_pose() {
  started_ = true;
  const auto& R = params_.restart;
  const Vector3d p = pose_->p_W_B;
  const double gear_above_floor_m =
      p.z() - params_.geofence.min_W_m.z() - params_.landing.gear_height_m;
  const bool high = gear_above_floor_m > R.airborne_height_m;
  const bool moving = pose_->v_W_B.norm() > R.airborne_speed_mps;
  sp_p_W_ = p;
  last_finite_sp_p_W_ = p;
  yaw_sp_rad_ = yaw_of(pose_->q_WB.toRotationMatrix());
  last_finite_yaw_rad_ = yaw_sp_rad_;
  if (!(restored_.motors_on || high || moving)) {
    failsafe_ = restored_.failsafe == Failsafe::kPoseStale ? Failsafe::kNone : restored_.failsafe;
    reason_ = "waiting for TAKEOFF";
    return;  // on the ground: a normal start (IDLE)
  }
  resumed_ = true;
  motors_on_ = true;
  takeoff_xy_ = p.head<2>();
  z_sp_m_ = p.z();
  const std::string why = std::string("restarted in flight (") +
                          (restored_.motors_on ? "previous instance flying"
                           : high              ? "gear " + fmt(gear_above_floor_m, 2) + " m up"
                                               : "moving") +
                          ")";
  if (restored_.failsafe == Failsafe::kPoseLost) {
    enter_pose_lost();
    reason_ = why + ": motion-capture-lost failsafe continues, disarm on touch-down";
    return;
  }
  hold_p_W_ = p;
  failsafe_ =
      restored_.failsafe == Failsafe::kOperatorAbort ? Failsafe::kOperatorAbort : Failsafe::kNone;
  enter(Phase::kHold, why + ": holding position, waiting for the operator");
}

bool Autonomy::accept(const OperatorCommand& cmd) {
  std::string why;
  if (cmd.auth == CommandAuth::kInternal) return true;
  if (cmd.auth == CommandAuth::kHmacSha256) {
    why = "signed command, but no operator key to verify it (autonomy.operator_key_file)";
  } else if (cmd.auth == CommandAuth::kVerified) {
    // Signature, freshness and replay were checked by the node's CommandVerifier.
  } else if (!params_.accept_unsigned_commands) {
    why = "unsigned command refused (autonomy.accept_unsigned_commands is false)";
  } else {
    const auto it = last_seq_.find(cmd.sender);
    if (it != last_seq_.end() && cmd.seq <= it->second) {
      why =
          "replayed or out-of-order seq " + std::to_string(cmd.seq) + " from '" + cmd.sender + "'";
    }
  }
  if (!why.empty()) {
    ++cmds_rejected_;
    reason_ = "command rejected: " + why;
    return false;
  }
  last_seq_[cmd.sender] = cmd.seq;
  last_cmd_seq_ = cmd.seq;
  return true;
}

void Autonomy::handle_command(const OperatorCommand& cmd) {
  if (!accept(cmd)) return;
  const bool in_failsafe = phase_ == Phase::kFailsafe;
  switch (cmd.command) {
    case Command::kKill:
      started_ = true;  // an explicit KILL is sent even before the first pose
      motors_on_ = false;
      failsafe_ = Failsafe::kKill;
      if (!end_utime_) end_utime_ = now_utime_;
      enter(Phase::kKilled, "KILL: motors off");
      return;
    case Command::kTakeoff:
      if (phase_ != Phase::kIdle && phase_ != Phase::kLanded) {
        reason_ = std::string("TAKEOFF ignored in ") + phase_name(phase_);
        return;
      }
      if (!pose_fresh()) {
        reason_ = "TAKEOFF refused: no fresh motion-capture pose";
        return;
      }
      takeoff_xy_ = pose_->p_W_B.head<2>();
      z_sp_m_ = pose_->p_W_B.z();
      yaw_sp_rad_ = yaw_of(pose_->q_WB.toRotationMatrix());
      motors_on_ = true;
      failsafe_ = Failsafe::kNone;
      mission_ = Mission::kNone;
      go_utime_.reset();
      end_utime_.reset();
      enter(Phase::kTakeoff, "TAKEOFF");
      return;
    case Command::kGo:
      if (phase_ != Phase::kHover && phase_ != Phase::kHold && phase_ != Phase::kDone) {
        reason_ = std::string("GO ignored in ") + phase_name(phase_);
        return;
      }
      if (cmd.mission != Mission::kLanding && cmd.mission != Mission::kIngress) {
        reason_ = "GO refused: no mission (landing or ingress) given";
        return;
      }
      mission_ = cmd.mission;
      retries_ = 0;
      failsafe_ = Failsafe::kNone;
      go_utime_ = now_utime_;
      end_utime_.reset();
      land_here_ = false;
      start_detection(std::string("GO ") + mission_name(mission_));
      return;
    case Command::kAbort:
      if (!airborne() || in_failsafe) {
        reason_ = std::string("ABORT ignored in ") + phase_name(phase_);
        return;
      }
      touchdown_.disarm();
      hold("operator ABORT: climb to a safe height and hover", Failsafe::kOperatorAbort,
           params_.failsafe.abort_height_m);
      return;
    case Command::kLandHere:
      if (!airborne() || in_failsafe || !pose_) {
        reason_ = std::string("LAND_HERE ignored in ") + phase_name(phase_);
        return;
      }
      mission_ = Mission::kLanding;
      land_here_ = true;
      estimate_W_ = Vector3d(pose_->p_W_B.x(), pose_->p_W_B.y(), params_.geofence.min_W_m.z());
      z_sp_m_ = pose_->p_W_B.z();
      failsafe_ = Failsafe::kNone;
      enter(Phase::kApproach, "LAND_HERE: landing on the floor below");
      return;
    case Command::kNudge:
      if (phase_ != Phase::kHover && phase_ != Phase::kHold && phase_ != Phase::kDone) {
        reason_ = std::string("NUDGE ignored in ") + phase_name(phase_);
        return;
      }
      {
        Vector3d d = cmd.nudge_W;
        if (!d.allFinite()) {
          reason_ = "NUDGE refused: non-finite offset";
          return;
        }
        if (d.norm() > params_.failsafe.max_nudge_m) d *= params_.failsafe.max_nudge_m / d.norm();
        hold_p_W_ += d;
        reason_ = "NUDGE";
      }
      return;
    case Command::kNone:
      return;
  }
}

void Autonomy::start_detection(const std::string& reason) {
  assert(pose_);
  const Vector3d p = pose_->p_W_B;
  std::vector<Vector3d> pts;
  const auto& d = params_.detection;
  if (mission_ == Mission::kLanding) {
    // Up (or down) to the search height above where we are: a safe hover, then the lawnmower.
    pts.emplace_back(p.x(), p.y(), d.landing_height_m);
    const auto lm = lawnmower(d.landing_area_min_W_m, d.landing_area_max_W_m, d.lane_spacing_m,
                              d.landing_height_m);
    pts.insert(pts.end(), lm.begin(), lm.end());
  } else {
    yaw_sp_rad_ = d.ingress_yaw_deg * M_PI / 180.0;
    pts.push_back(d.ingress_start_W_m);
    pts.push_back(d.ingress_end_W_m);
  }
  path_.start(p, std::move(pts));
  estimator_.reset();
  last_found_utime_.reset();
  touchdown_.disarm();
  enter(Phase::kDetection, reason);
}

void Autonomy::start_refinement(const TargetMeasurement& m) {
  estimator_.reset();
  sizes_m_.clear();
  normal_sum_W_.setZero();
  yaw4_sum_.setZero();
  first_sighting_W_ = m.p_W_target;
  if (m.found) {
    estimator_.add(m.p_W_target);
    sizes_m_.push_back(m.size_m);
    normal_sum_W_ += m.n_W;
    yaw4_sum_ += Vector2d(std::cos(4 * m.yaw_rad), std::sin(4 * m.yaw_rad));
  } else {
    normal_sum_W_ += m.n_W;  // the plane's orientation is measured also from a part of it
  }
  enter(Phase::kRefinement,
        std::string(m.found ? "first waypoint X_V,1" : "first sighting (partly in view)") +
            " at (" + fmt(m.p_W_target.x()) + ", " + fmt(m.p_W_target.y()) + ", " +
            fmt(m.p_W_target.z()) + ")");
  next_vantage();
}

void Autonomy::next_vantage() {
  // Around the first sighting until the first full-view waypoint.
  const Vector3d mu = estimator_.n() > 0 ? estimator_.mean() : first_sighting_W_;
  const Matrix3d S = estimator_.covariance();
  if (mission_ == Mission::kLanding) {
    // A vantage next to the current position gives the vision no baseline: redraw (bounded).
    const Vector2d here = pose_ ? Vector2d(pose_->p_W_B.head<2>()) : Vector2d(mu.head<2>());
    Vector2d xy = sampler_.draw(mu.head<2>(), S.topLeftCorner<2, 2>(), estimator_.n());
    for (int k = 0; k < 10 && (xy - here).norm() < kMinVantageStepM; ++k)
      xy = sampler_.draw(mu.head<2>(), S.topLeftCorner<2, 2>(), estimator_.n());
    vantage_W_ = Vector3d(xy.x(), xy.y(), params_.detection.landing_height_m);
  } else {
    // In the plane parallel to the wall at the standoff: along-wall t and vertical z.
    Vector3d n = normal_sum_W_;
    n.z() = 0;
    n = n.norm() > 1e-6 ? Vector3d(n.normalized()) : Vector3d(-1, 0, 0);
    const Vector3d t(-n.y(), n.x(), 0);
    Eigen::Matrix<double, 3, 2> B;
    B.col(0) = t;
    B.col(1) = Vector3d::UnitZ();
    const Vector2d mu2(t.dot(mu), mu.z());
    const Eigen::Matrix2d S2 = B.transpose() * S * B;
    const Vector2d d = sampler_.draw(mu2, S2, estimator_.n()) - mu2;
    vantage_W_ =
        mu + n * params_.refinement.ingress_standoff_m + t * d.x() + Vector3d::UnitZ() * d.y();
    yaw_sp_rad_ = std::atan2(-n.y(), -n.x());
  }
  vantage_since_utime_ = now_utime_;
  at_vantage_since_.reset();
  at_vantage_W_.clear();
}

void Autonomy::finish_refinement() {
  estimate_W_ = estimator_.mean();
  std::vector<double> a, b;
  for (const auto& s : sizes_m_) {
    a.push_back(s.x());
    b.push_back(s.y());
  }
  const double size_a = median(a), size_b = median(b);
  const std::string where = "estimate (" + fmt(estimate_W_.x()) + ", " + fmt(estimate_W_.y()) +
                            ", " + fmt(estimate_W_.z()) +
                            ") from n = " + std::to_string(estimator_.n());
  if (mission_ == Mission::kLanding) {
    const auto& L = params_.landing;
    const double short_side = std::min(size_a, size_b);
    const double needed = L.gear_footprint_m + 2 * L.fit_margin_m;
    if (!(short_side >= needed)) {  // NaN-safe: an unmeasured size is refused
      hold("refused to land: platform short side " + fmt(short_side) + " m < gear footprint " +
               fmt(L.gear_footprint_m) + " m + 2 x margin " + fmt(L.fit_margin_m) + " m",
           Failsafe::kNone, params_.takeoff.height_m);
      return;
    }
    z_sp_m_ = pose_->p_W_B.z();
    land_here_ = false;
    if (L.align_yaw_tol_deg > 0 && yaw4_sum_.norm() > 1e-9) {
      // The platform's edges modulo 90 deg (the gear is square): the turn of at most 45 deg.
      const double edges = std::atan2(yaw4_sum_.y(), yaw4_sum_.x()) / 4;
      const double now = yaw_of(pose_->q_WB.toRotationMatrix());
      const double k = std::round(wrap_angle(now - edges) / (M_PI / 2));
      yaw_sp_rad_ = wrap_angle(edges + k * M_PI / 2);
    }
    enter(Phase::kApproach, "refinement converged (eqs. 7-9): " + where);
  } else {
    const auto& I = params_.ingress;
    const double need_w = I.vehicle_span_m + 2 * I.clearance_m;
    const double need_h = I.vehicle_height_m + 2 * I.clearance_m;
    if (!(size_a >= need_w && size_b >= need_h)) {  // NaN-safe
      hold("refused ingress: opening " + fmt(size_a) + " x " + fmt(size_b) +
               " m smaller than the vehicle + clearance " + fmt(need_w) + " x " + fmt(need_h) +
               " m",
           Failsafe::kNone, 0.0);
      return;
    }
    Vector3d n = normal_sum_W_;
    n.z() = 0;
    normal_W_ = n.norm() > 1e-6 ? Vector3d(n.normalized()) : Vector3d(-1, 0, 0);
    yaw_sp_rad_ = std::atan2(-normal_W_.y(), -normal_W_.x());
    ingress_stage_ = IngressStage::kAlign;
    aligned_since_.reset();
    through_s_m_ = 0.0;
    enter(Phase::kApproach, "refinement converged (eqs. 7-9): " + where);
  }
}

void Autonomy::target_lost(const std::string& what) {
  ++retries_;
  estimator_.reset();
  if (retries_ > params_.detection.max_retries) {
    hold("target lost (" + what + "); " + std::to_string(params_.detection.max_retries) +
             " retries exhausted: holding",
         Failsafe::kNone, mission_ == Mission::kLanding ? params_.detection.landing_height_m : 0.0);
    return;
  }
  start_detection("target lost (" + what + "): detection retry " + std::to_string(retries_) +
                  " of " + std::to_string(params_.detection.max_retries));
}

void Autonomy::handle_target(const TargetMeasurement& m) {
  if (!(m.found || m.partial) || m.mission != mission_ || !m.p_W_target.allFinite() ||
      !m.n_W.allFinite() || !m.size_m.allFinite() || !std::isfinite(m.yaw_rad)) {
    return;
  }
  // A target cut by the image border is in sight (not lost) and locates it well enough to fly
  // the vantages around; it is never averaged into the estimate.
  last_found_utime_ = std::max(m.utime, last_found_utime_.value_or(m.utime));
  if (phase_ == Phase::kDetection) {
    start_refinement(m);
  } else if (phase_ == Phase::kRefinement && !m.found) {
    // Until the first full view the vantages follow the newest partial one: its centre lies
    // between the vehicle and the true centre, so each vantage sees more of the target (in
    // Monte Carlo runs the draws around the first sighting alone kept it cut for 60 s).
    if (estimator_.n() == 0) first_sighting_W_ = m.p_W_target;
  } else if (phase_ == Phase::kRefinement) {
    sizes_m_.push_back(m.size_m);
    normal_sum_W_ += m.n_W;
    yaw4_sum_ += Vector2d(std::cos(4 * m.yaw_rad), std::sin(4 * m.yaw_rad));
    if (params_.refinement.one_waypoint_per_vantage) {
      if (at_vantage_since_) at_vantage_W_.push_back(m.p_W_target);  // added when the dwell ends
      return;
    }
    add_waypoint(m.p_W_target);
  }
}

void Autonomy::add_waypoint(const Vector3d& X_W) {
  const auto verdict = estimator_.add(X_W);
  if (verdict == RefinementEstimator::Verdict::kRestarted) {
    reason_ =
        "estimate restarted: " + std::to_string(params_.refinement.max_consecutive_rejections) +
        " waypoints in a row outside the gate";
  }
  if (estimator_.converged()) finish_refinement();
}

void Autonomy::step_phase(double dt_s) {
  const Vector3d p = pose_ ? pose_->p_W_B : sp_p_W_;
  sp_v_W_.setZero();
  const double since_found_s = last_found_utime_ ? seconds(now_utime_ - *last_found_utime_)
                                                 : seconds(now_utime_ - phase_start_utime_);

  switch (phase_) {
    case Phase::kIdle:
    case Phase::kLanded:
    case Phase::kKilled:
      motors_on_ = false;
      sp_p_W_ = p;
      return;

    case Phase::kTakeoff: {
      const auto& T = params_.takeoff;
      if (z_sp_m_ < T.height_m) {
        z_sp_m_ = std::min(T.height_m, z_sp_m_ + T.climb_rate_mps * dt_s);
        sp_v_W_.z() = T.climb_rate_mps;
      }
      sp_p_W_ = Vector3d(takeoff_xy_.x(), takeoff_xy_.y(), z_sp_m_);
      if (z_sp_m_ >= T.height_m && (p - sp_p_W_).norm() < T.reached_tol_m) {
        hold_p_W_ = sp_p_W_;
        enter(Phase::kHover, "take-off complete: hovering, waiting for GO");
      }
      return;
    }

    case Phase::kHover:
    case Phase::kHold:
    case Phase::kDone:
      sp_p_W_ = hold_p_W_;
      return;

    case Phase::kDetection:
      if (vision_silent()) return;
      path_.step(p, dt_s, params_.detection.speed_mps, kPathLeadM);
      sp_p_W_ = path_.carrot();
      sp_v_W_ = path_.carrot_velocity();
      if (path_.finished(p, params_.hover_tol_m)) {
        target_lost("search path flown without a detection");
      }
      return;

    case Phase::kRefinement: {
      if (vision_silent()) return;
      const auto& R = params_.refinement;
      if (since_found_s > R.lost_timeout_s) {
        target_lost("no target seen for " + fmt(since_found_s, 1) + " s in refinement");
        return;
      }
      if (seconds(now_utime_ - phase_start_utime_) > R.max_time_s) {
        hold("refinement did not converge in " + fmt(R.max_time_s, 0) + " s", Failsafe::kNone, 0.0);
        return;
      }
      if ((p - vantage_W_).norm() < R.vantage_reach_tol_m) {
        if (!at_vantage_since_) at_vantage_since_ = now_utime_;
        if (seconds(now_utime_ - *at_vantage_since_) >= R.vantage_dwell_s) {
          if (!R.one_waypoint_per_vantage) {
            next_vantage();
          } else if (!at_vantage_W_.empty()) {
            // The vantage's waypoint: the median is robust to a stray frame among few.
            Vector3d X_W;
            for (int k = 0; k < 3; ++k) {
              std::vector<double> v;
              for (const auto& w : at_vantage_W_) v.push_back(w[k]);
              X_W[k] = median(v);
            }
            add_waypoint(X_W);
            if (phase_ != Phase::kRefinement) return;  // converged (or held)
            next_vantage();
          } else {
            // Nothing seen here: hovering does not help (the vision's baseline shrinks to zero
            // as the reference frames age), moving on does.
            next_vantage();
          }
        }
      } else if (seconds(now_utime_ - vantage_since_utime_) > R.vantage_timeout_s) {
        next_vantage();
      }
      sp_p_W_ = vantage_W_;
      return;
    }

    case Phase::kApproach:
      if (mission_ == Mission::kLanding) {
        const auto& L = params_.landing;
        const double z_touch = estimate_W_.z() + L.gear_height_m;  // body z on the platform
        const double e_r = (p.head<2>() - estimate_W_.head<2>()).norm();
        if (!land_here_ && p.z() - z_touch > L.lost_check_height_m &&
            since_found_s > L.lost_timeout_s) {
          target_lost("no target seen for " + fmt(since_found_s, 1) + " s in approach");
          return;
        }
        const bool turned =
            L.align_yaw_tol_deg <= 0 || !pose_ ||
            std::abs(wrap_angle(yaw_of(pose_->q_WB.toRotationMatrix()) - yaw_sp_rad_)) <=
                L.align_yaw_tol_deg * M_PI / 180.0;
        if (e_r <= L.radial_tol_m && turned) {  // descend only inside the prescribed volume
          z_sp_m_ -= L.descent_rate_mps * dt_s;
          sp_v_W_.z() = -L.descent_rate_mps;
        }
        sp_p_W_ = Vector3d(estimate_W_.x(), estimate_W_.y(), z_sp_m_);
        if (z_sp_m_ - z_touch <= L.final_height_m) {
          touchdown_.arm(now_utime_);
          enter(Phase::kFinalDescent,
                "final descent: " + fmt(L.final_height_m, 2) + " m above the platform");
        }
      } else {
        const auto& I = params_.ingress;
        const Vector3d& n = normal_W_;
        const Vector3d t(-n.y(), n.x(), 0);
        if (ingress_stage_ == IngressStage::kAlign) {
          if (I.lost_timeout_s > 0 && since_found_s > I.lost_timeout_s) {
            target_lost("no target seen for " + fmt(since_found_s, 1) + " s while aligning");
            return;
          }
          sp_p_W_ = estimate_W_ + n * I.standoff_m;
          const bool aligned = (p - sp_p_W_).norm() < I.align_tol_m && pose_ &&
                               pose_->v_W_B.norm() < I.align_speed_mps;
          if (!aligned) {
            aligned_since_.reset();
          } else if (!aligned_since_) {
            aligned_since_ = now_utime_;
          } else if (seconds(now_utime_ - *aligned_since_) >= I.align_settle_s) {
            ingress_stage_ = IngressStage::kThrough;
            through_s_m_ = 0.0;
            reason_ = "aligned on the opening's normal: flying through";
          }
        } else {
          const Vector3d d = p - estimate_W_;
          const double lateral = d.dot(t), vertical = d.z();
          const double s_end = I.standoff_m + I.pass_distance_m;
          const double s_vehicle = I.standoff_m - d.dot(n);  // progress of the vehicle
          const bool inside =
              std::abs(lateral) <= I.lateral_tol_m && std::abs(vertical) <= I.vertical_tol_m;
          if (inside && through_s_m_ < s_end && through_s_m_ - s_vehicle < kPathLeadM) {
            through_s_m_ = std::min(s_end, through_s_m_ + I.speed_mps * dt_s);
            sp_v_W_ = -n * I.speed_mps;
          }
          sp_p_W_ = estimate_W_ + n * (I.standoff_m - through_s_m_);
          if (through_s_m_ >= s_end && (p - sp_p_W_).norm() < params_.hover_tol_m) {
            hold_p_W_ = sp_p_W_;
            end_utime_ = now_utime_;
            enter(Phase::kDone,
                  "through the opening: " + fmt(I.pass_distance_m, 2) + " m past the wall");
          }
        }
      }
      return;

    case Phase::kFinalDescent: {
      const auto& L = params_.landing;
      const double z_touch = estimate_W_.z() + L.gear_height_m;
      const double z_floor = z_touch - L.final_depth_m;
      if (z_sp_m_ > z_floor) {
        z_sp_m_ = std::max(z_floor, z_sp_m_ - L.final_descent_rate_mps * dt_s);
        sp_v_W_.z() = -L.final_descent_rate_mps;
      }
      sp_p_W_ = Vector3d(estimate_W_.x(), estimate_W_.y(), z_sp_m_);
      if (pose_fresh()) touchdown_.add_pose(*pose_, z_sp_m_, now_utime_);
      if (touchdown_.detected()) {
        motors_on_ = false;
        touchdown_.disarm();
        end_utime_ = now_utime_;
        enter(Phase::kLanded, std::string("touch-down (") + touchdown_.cue() + "): motors off");
      }
      return;
    }

    case Phase::kFailsafe:
      if (!motors_on_) return;
      if (failsafe_ == Failsafe::kPoseLost && pose_fresh() && !touchdown_.detected()) {
        // Pose back for good: stop descending where the failsafe happened to be (over a
        // platform's edge it tips the vehicle) and hold; the operator decides, as after any
        // failsafe whose cause has cleared.
        if (!pose_back_since_utime_) pose_back_since_utime_ = now_utime_;
        const double back_s = seconds(now_utime_ - *pose_back_since_utime_);
        if (back_s >= params_.failsafe.pose_recovered_s) {
          touchdown_.disarm();
          hold("motion capture back for " + fmt(back_s, 1) +
                   " s: failsafe descent stopped, holding; waiting for the operator",
               Failsafe::kNone, 0.0);
          return;
        }
      } else if (!pose_fresh()) {
        pose_back_since_utime_.reset();
      }
      if (pose_fresh()) {
        // Pose back: a controlled descent on it instead of the outer loop's open-loop one.
        sp_p_W_.z() = failsafe_z_m_ -
                      params_.failsafe.descent_mps * seconds(now_utime_ - failsafe_since_utime_);
        sp_v_W_.z() = -params_.failsafe.descent_mps;
        touchdown_.add_pose(*pose_, sp_p_W_.z(), now_utime_);
      }
      if (touchdown_.detected()) {
        motors_on_ = false;
        touchdown_.disarm();
        reason_ =
            std::string("failsafe descent: touch-down (") + touchdown_.cue() + "): motors off";
      }
      return;
  }
}

Output Autonomy::make_output() {
  // The last line of defence: whatever got through, a non-finite setpoint is never sent (NaN
  // passes cwiseMax / cwiseMin, so the geofence alone does not stop it).
  if (!sp_p_W_.allFinite() || !sp_v_W_.allFinite() || !std::isfinite(yaw_sp_rad_)) {
    sp_p_W_ = last_finite_sp_p_W_;
    sp_v_W_.setZero();
    yaw_sp_rad_ = last_finite_yaw_rad_;
    hold_p_W_ = hold_p_W_.allFinite() ? hold_p_W_ : last_finite_sp_p_W_;
    reason_ = "non-finite setpoint refused: holding the last finite one";
  }
  last_finite_sp_p_W_ = sp_p_W_;
  last_finite_yaw_rad_ = yaw_sp_rad_;
  const auto& G = params_.geofence;
  const Vector3d clamped = sp_p_W_.cwiseMax(G.min_W_m).cwiseMin(G.max_W_m);
  geofence_clamped_ = motors_on_ && (clamped - sp_p_W_).norm() > 1e-9;
  Output out;
  auto& sp = out.setpoint;
  sp.utime = now_utime_;
  sp.p_W = motors_on_ ? clamped : sp_p_W_;
  sp.v_W = geofence_clamped_ ? Vector3d::Zero() : sp_v_W_;
  sp.yaw_rad = yaw_sp_rad_;
  sp.motors_on = motors_on_;
  sp.kill = phase_ == Phase::kKilled;  // the outer loop disarms in the air only on an explicit KILL
  sp.idle = false;

  out.has_setpoint = started_;
  auto& st = out.status;
  st.utime = now_utime_;
  st.mission = mission_;
  st.phase = phase_;
  st.reason = reason_;
  st.n_measurements = estimator_.n();
  st.n_rejected = estimator_.n_rejected();
  st.retries = retries_;
  const bool final = phase_ == Phase::kApproach || phase_ == Phase::kFinalDescent ||
                     phase_ == Phase::kLanded || phase_ == Phase::kDone;
  st.has_estimate = final || estimator_.n() > 0;
  st.estimate_W = final ? estimate_W_ : estimator_.mean();
  st.covariance = estimator_.covariance();
  st.setpoint_W = sp.p_W;
  st.failsafe = failsafe_;
  st.cmds_rejected = cmds_rejected_;
  st.last_cmd_seq = last_cmd_seq_;
  st.geofence_clamped = geofence_clamped_;
  if (go_utime_) st.mission_time_s = seconds(end_utime_.value_or(now_utime_) - *go_utime_);
  return out;
}

Output Autonomy::update(const Inputs& in, int64_t now_utime) {
  now_utime_ = std::max(now_utime_, now_utime);
  double dt_s = 0.0;
  if (last_step_utime_) dt_s = std::clamp(seconds(now_utime_ - *last_step_utime_), 0.0, 0.1);
  last_step_utime_ = now_utime_;

  if (in.pose && finite(*in.pose) && (!pose_ || in.pose->utime >= pose_->utime)) pose_ = in.pose;
  if (in.imu && in.imu->accel_B.allFinite() && in.imu->gyro_B.allFinite())
    touchdown_.add_imu(*in.imu);
  if (!started_ && pose_) start_from_first_pose();
  if (in.command) handle_command(*in.command);

  if (airborne() && phase_ != Phase::kFailsafe) {
    const double age_s = pose_ ? seconds(now_utime_ - pose_->utime) : 1e9;
    if (age_s > params_.failsafe.pose_lost_s) {
      enter_pose_lost();
    } else if (age_s > params_.failsafe.pose_stale_s) {
      if (failsafe_ != Failsafe::kPoseStale) {
        failsafe_before_stale_ = failsafe_;
        failsafe_ = Failsafe::kPoseStale;
        reason_ = "motion capture stale: mission frozen, outer loop holds level";
      }
      return make_output();  // no progress on old data
    } else if (failsafe_ == Failsafe::kPoseStale) {
      failsafe_ = failsafe_before_stale_;
      reason_ = "motion capture back: mission resumed";
    }
  }

  if (in.target) {
    last_vision_utime_ = now_utime_;
    handle_target(*in.target);
  }
  step_phase(dt_s);
  return make_output();
}

}  // namespace alight::autonomy
