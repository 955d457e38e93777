#include "autonomy/autonomy.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <type_traits>

#include "autonomy/text.hpp"
#include "common/median.hpp"

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
// PhaseState's alternatives are in Phase's order: phase() is the variant's index.
template <Phase P, class State>
constexpr bool kAt =
    std::is_same_v<std::variant_alternative_t<static_cast<size_t>(P), PhaseState>, State>;
static_assert(std::variant_size_v<PhaseState> == static_cast<size_t>(Phase::kKilled) + 1);
static_assert(kAt<Phase::kIdle, phases::Idle> && kAt<Phase::kTakeoff, phases::Takeoff> &&
              kAt<Phase::kHover, phases::Hover> && kAt<Phase::kDetection, phases::Detection> &&
              kAt<Phase::kRefinement, phases::Refinement> &&
              kAt<Phase::kApproach, phases::Approach> &&
              kAt<Phase::kFinalDescent, phases::FinalDescent> &&
              kAt<Phase::kLanded, phases::Landed> && kAt<Phase::kDone, phases::Done> &&
              kAt<Phase::kHold, phases::Hold> && kAt<Phase::kFailsafe, phases::FailsafeDescent> &&
              kAt<Phase::kKilled, phases::Killed>);

double seconds(int64_t dt_utime) { return static_cast<double>(dt_utime) * 1e-6; }

LandingGear landing_gear(const LandingParams& L) {
  return LandingGear{L.gear_height_m,    L.gear_footprint_m,       L.fit_margin_m,
                     L.descent_rate_mps, L.final_descent_rate_mps, L.final_hold_timeout_s};
}

/// A DEGRADED estimate first pauses the mission (position held on it, nothing advanced) and
/// holds for the operator only once it has lasted this long [s], as PX4 holds for
/// COM_FAIL_ACT_T before a failsafe's action and goes on when the condition clears within it.
/// The flow's dropouts where the view changes (the platform coming into the downward camera's
/// view, a floor's texture thinning) last a few tenths of a second; lateral dead reckoning on the
/// IMU drifts by centimetres over this.
constexpr double kDegradedPauseS = 2.0;

bool finite(const PoseSample& s) {
  return s.p_W_B.allFinite() && s.v_W_B.allFinite() && s.q_WB.coeffs().allFinite() &&
         s.omega_B.allFinite() && std::abs(s.q_WB.norm() - 1.0) < 1e-3;
}

}  // namespace

Autonomy::Autonomy(const AutonomyParams& params, const RestartState& restored)
    : params_(params),
      estimator_(params.refinement),
      sampler_(params.refinement, params.seed),
      gate_(params.accept_unsigned_commands),
      restored_(restored),
      platform_(params.moving_platform.filter) {
  params_.validate();
  if (restored_.killed) {
    // An explicit KILL outlives the process that received it: motors off at once, whatever
    // the pose, and nothing (TAKEOFF, --auto-go) turns them on again.
    started_ = resumed_ = true;
    failsafe_ = Failsafe::kKill;
    enter(phases::Killed{}, "KILL latched before a restart: motors stay off");
  }
}

template <class State>
State& Autonomy::enter(State state, std::string reason) {
  state_ = std::move(state);
  reason_ = std::move(reason);
  phase_start_utime_ = now_utime_;
  return std::get<State>(state_);
}

Vector3d Autonomy::current_vantage() const {
  const auto* r = std::get_if<phases::Refinement>(&state_);
  return r ? r->vantage_W : Vector3d::Zero();
}

Vector3d* Autonomy::held_position() {
  if (auto* s = std::get_if<phases::Hover>(&state_)) return &s->hold_p_W;
  if (auto* s = std::get_if<phases::Hold>(&state_)) return &s->hold_p_W;
  if (auto* s = std::get_if<phases::Done>(&state_)) return &s->hold_p_W;
  return nullptr;
}

TouchdownDetector* Autonomy::touchdown() {
  if (auto* s = std::get_if<phases::FinalDescent>(&state_)) return &s->touchdown;
  if (auto* s = std::get_if<phases::FailsafeDescent>(&state_)) return &s->touchdown;
  return nullptr;
}

bool Autonomy::airborne() const {
  switch (phase()) {
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

bool Autonomy::precise_setpoint() const {
  const auto& L = params_.landing;
  if (!L.precise_final) return false;
  if (phase() == Phase::kFinalDescent) return true;
  const auto* a = std::get_if<phases::Approach>(&state_);
  if (!a) return false;
  const auto* l = std::get_if<LandingApproach>(&a->how);
  return l && !l->land_here &&
         l->at_final_height(estimate_W_.z(), L.gear_height_m, L.final_height_m);
}

bool Autonomy::pose_fresh() const {
  return pose_ && seconds(now_utime_ - pose_->utime) <= params_.failsafe.pose_stale_s;
}

double Autonomy::since_found_s(const std::optional<int64_t>& last_found_utime) const {
  return seconds(now_utime_ - last_found_utime.value_or(phase_start_utime_));
}

void Autonomy::hold(const std::string& reason, Failsafe failsafe, double min_z_m) {
  const Vector3d p = pose_ ? pose_->p_W_B : sp_p_W_;
  failsafe_ = failsafe;
  enter(phases::Hold{Vector3d(p.x(), p.y(), std::max(p.z(), min_z_m)), std::nullopt}, reason);
}

bool Autonomy::hold_if_vision_silent() {
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

void Autonomy::enter_failsafe_descent(Failsafe cause, std::string reason, const Vector2d& xy_W) {
  failsafe_ = cause;
  phases::FailsafeDescent f{pose_ ? pose_->p_W_B.z() : sp_p_W_.z(), now_utime_, std::nullopt,
                            TouchdownDetector(params_.landing)};
  f.touchdown.arm(now_utime_);
  f.touchdown.confirm_impacts();
  sp_p_W_.head<2>() = xy_W;
  enter(std::move(f), std::move(reason));
}

void Autonomy::enter_failsafe_descent(Failsafe cause, std::string reason) {
  const Vector2d xy_W = pose_ ? pose_->p_W_B.head<2>() : sp_p_W_.head<2>();
  enter_failsafe_descent(cause, std::move(reason), xy_W);
}

void Autonomy::enter_pose_lost() {
  enter_failsafe_descent(Failsafe::kPoseLost, "motion capture lost for > " +
                                                  fmt(params_.failsafe.pose_lost_s, 1) +
                                                  " s: controlled descent, disarm on touch-down");
}

void Autonomy::enter_estimate_lost(const std::string& what) {
  // The estimator goes on dead-reckoning on the IMU when it is LOST, so the pose it publishes
  // still exists and drifts slowly: descending on it is the pose-lost failsafe's controlled
  // descent; if it stops too, the outer loop's open-loop descent takes over as without mocap.
  enter_failsafe_descent(Failsafe::kEstimateLost,
                         what +
                             ": controlled descent on the pose it still dead-reckons, disarm "
                             "on touch-down");
}

std::optional<Autonomy::EstimateCondition> Autonomy::estimate_condition() const {
  using L = EstimateHealth::Level;
  if (!estimate_) return std::nullopt;
  const double age_s = seconds(now_utime_ - estimate_->utime);
  if (age_s > params_.failsafe.estimate_silent_s) {
    return EstimateCondition{L::kLost, "no STATE_ESTIMATE for " + fmt(age_s, 1) + " s"};
  }
  const std::string why = estimate_->text.empty() ? "no reason given" : estimate_->text;
  switch (estimate_->level) {
    case L::kOk:
      return EstimateCondition{L::kOk, "state estimate OK"};
    case L::kDegraded:
      return EstimateCondition{L::kDegraded, "state estimate degraded (" + why + ")"};
    case L::kLost:
      break;
  }
  return EstimateCondition{L::kLost, "state estimate lost (" + why + ")"};
}

std::optional<double> Autonomy::terrain_m() const {
  if (!estimate_ || seconds(now_utime_ - estimate_->utime) > params_.failsafe.estimate_silent_s)
    return std::nullopt;
  return estimate_->terrain_m;
}

std::optional<std::string> Autonomy::estimate_refusal() const {
  const auto e = estimate_condition();
  if (!e) {
    if (!params_.failsafe.require_estimate) return std::nullopt;
    return std::string("no STATE_ESTIMATE yet (failsafe.require_estimate)");
  }
  // Once an estimate is heard the autonomy reacts to it in flight: starting on a DEGRADED one
  // would hold at once, on a LOST one (the estimator not yet aligned) descend at once.
  if (e->level == EstimateHealth::Level::kOk) return std::nullopt;
  return e->what;
}

bool Autonomy::react_to_estimate() {
  using L = EstimateHealth::Level;
  const auto e = estimate_condition();
  const bool was_paused = paused_on_estimate_;
  paused_on_estimate_ = false;
  if (e && e->level == L::kDegraded && airborne()) {
    if (!degraded_since_utime_) degraded_since_utime_ = now_utime_;
  } else {
    degraded_since_utime_.reset();
    // A pause in the hover has no mission to resume: GO is still to come (refused while paused).
    if (was_paused && e && e->level == L::kOk)
      reason_ = phase() == Phase::kHover ? "state estimate OK again: hovering, waiting for GO"
                                         : "state estimate OK again: mission resumed";
  }
  if (!e || e->level == L::kOk || !airborne()) return false;
  const Phase current = phase();
  // A descent to touch-down is under way. The final descent is on the target (entered only
  // within radial_tol_m of the estimate, the gear final_height_m above the platform) and a
  // second or less from touch-down: finishing it lands on the platform. A hold instead hovers
  // there on a degraded or dead-reckoned pose that drifts, and the descent that follows (the
  // failsafe's, or the operator's LAND_HERE) lands where it drifted to; over a platform's edge
  // that tips the vehicle, as the mocap_drop_2s fault did. PX4's Land mode, too,
  // goes on landing without a position estimate. A failsafe descent is not restarted.
  if (current == Phase::kFailsafe || current == Phase::kFinalDescent) return false;
  if (e->level == L::kLost) {
    enter_estimate_lost(e->what);
    return false;
  }
  // DEGRADED: pause, then hold and wait for the operator, unless already holding (HOLD, DONE) or
  // landing where the operator said (LAND_HERE: the landing was the operator's answer).
  if (current == Phase::kHold || current == Phase::kDone) return false;
  // The take-off's climb goes on through a DEGRADED that is the flow's alone: in its first
  // decimetres the flow camera may be too near the floor to track it (out of a flight camera's
  // focus, the texture magnified beyond its detail), while the rangefinder and the barometer
  // hold the height and the climb is straight up. At the take-off height (HOVER) a flow still
  // missing holds as anywhere else.
  if (current == Phase::kTakeoff && estimate_->reasons == kEstimateReasonNoFlow) return false;
  if (const auto* a = std::get_if<phases::Approach>(&state_)) {
    const auto* landing = std::get_if<LandingApproach>(&a->how);
    if (landing && landing->land_here) return false;
  }
  const double degraded_s = seconds(now_utime_ - *degraded_since_utime_);
  if (degraded_s < kDegradedPauseS) {
    reason_ = e->what + ": mission paused, holding position (" + fmt(degraded_s, 1) + " of " +
              fmt(kDegradedPauseS, 1) + " s)";
    // Held where the vehicle is when the pause begins (the setpoint may lead it: a climb, an
    // approach).
    if (!was_paused) pause_p_W_ = pose_ ? pose_->p_W_B : sp_p_W_;
    paused_on_estimate_ = true;
    return true;
  }
  hold(e->what + ": holding; waiting for the operator", Failsafe::kNone, 0.0);
  return false;
}

RestartState Autonomy::restart_state() const {
  RestartState r;
  r.killed = phase() == Phase::kKilled;
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
  if (restored_.failsafe == Failsafe::kEstimateLost) {
    enter_failsafe_descent(Failsafe::kEstimateLost,
                           why + ": estimate-lost failsafe continues, disarm on touch-down");
    return;
  }
  failsafe_ =
      restored_.failsafe == Failsafe::kOperatorAbort ? Failsafe::kOperatorAbort : Failsafe::kNone;
  enter(phases::Hold{p, std::nullopt}, why + ": holding position, waiting for the operator");
}

void Autonomy::refused_at_link(const OperatorCommand& cmd) {
  assert(cmd.auth == CommandAuth::kHmacSha256 && cmd.link_reject != CommandReject::kNone);
  gate_.check(cmd);
}

void Autonomy::handle_command(const OperatorCommand& cmd) {
  const CommandGate::Verdict verdict = gate_.check(cmd);
  if (!verdict.accepted) {
    if (!verdict.at_link) reason_ = "command rejected: " + verdict.why;
    return;
  }
  const Phase current = phase();
  const bool in_failsafe = current == Phase::kFailsafe;
  switch (cmd.command) {
    case Command::kKill:
      started_ = true;  // an explicit KILL is sent even before the first pose
      motors_on_ = false;
      failsafe_ = Failsafe::kKill;
      if (!end_utime_) end_utime_ = now_utime_;
      enter(phases::Killed{}, "KILL: motors off");
      return;
    case Command::kTakeoff:
      if (current != Phase::kIdle && current != Phase::kLanded) {
        reason_ = std::string("TAKEOFF ignored in ") + phase_name(current);
        return;
      }
      if (!pose_fresh()) {
        reason_ = "TAKEOFF refused: no fresh motion-capture pose";
        return;
      }
      if (const auto why = estimate_refusal()) {
        reason_ = "TAKEOFF refused: " + *why;
        return;
      }
      yaw_sp_rad_ = yaw_of(pose_->q_WB.toRotationMatrix());
      motors_on_ = true;
      failsafe_ = Failsafe::kNone;
      profile_.reset();
      go_utime_.reset();
      end_utime_.reset();
      enter(phases::Takeoff{pose_->p_W_B.head<2>(), pose_->p_W_B.z()}, "TAKEOFF");
      return;
    case Command::kGo:
      if (current != Phase::kHover && current != Phase::kHold && current != Phase::kDone) {
        reason_ = std::string("GO ignored in ") + phase_name(current);
        return;
      }
      if (cmd.mission != Mission::kLanding && cmd.mission != Mission::kIngress) {
        reason_ = "GO refused: no mission (landing or ingress) given";
        return;
      }
      if (const auto why = estimate_refusal()) {
        reason_ = "GO refused: " + *why;
        return;
      }
      profile_ = MissionProfile::make(cmd.mission, params_);
      retries_ = 0;
      drop_go_arounds_ = 0;
      candidate_looks_ = 0;
      failsafe_ = Failsafe::kNone;
      go_utime_ = now_utime_;
      end_utime_.reset();
      start_detection(std::string("GO ") + mission_name(cmd.mission));
      return;
    case Command::kAbort:
      if (!airborne() || in_failsafe) {
        reason_ = std::string("ABORT ignored in ") + phase_name(current);
        return;
      }
      hold("operator ABORT: climb to a safe height and hover", Failsafe::kOperatorAbort,
           params_.failsafe.abort_height_m);
      return;
    case Command::kLandHere:
      if (!airborne() || in_failsafe || !pose_) {
        reason_ = std::string("LAND_HERE ignored in ") + phase_name(current);
        return;
      }
      profile_ = MissionProfile::make(Mission::kLanding, params_);
      estimate_W_ = Vector3d(pose_->p_W_B.x(), pose_->p_W_B.y(), params_.geofence.min_W_m.z());
      failsafe_ = Failsafe::kNone;
      enter(phases::Approach{LandingApproach{pose_->p_W_B.z(), true, {}, {}}, std::nullopt,
                             std::nullopt, std::nullopt},
            "LAND_HERE: landing on the floor below");
      return;
    case Command::kNudge: {
      Vector3d* held = held_position();  // HOVER, HOLD, DONE
      if (!held) {
        reason_ = std::string("NUDGE ignored in ") + phase_name(current);
        return;
      }
      Vector3d d = cmd.nudge_W;
      if (!d.allFinite()) {
        reason_ = "NUDGE refused: non-finite offset";
        return;
      }
      if (d.norm() > params_.failsafe.max_nudge_m) d *= params_.failsafe.max_nudge_m / d.norm();
      *held += d;
      reason_ = "NUDGE";
      return;
    }
    case Command::kNone:
      return;
  }
}

void Autonomy::start_detection(const std::string& reason) {
  assert(pose_ && profile_);
  auto search = profile_->search(pose_->p_W_B);
  if (search.yaw_rad) yaw_sp_rad_ = *search.yaw_rad;
  phases::Detection d;
  d.path.start(pose_->p_W_B, std::move(search.path_W));
  estimator_.reset();
  enter(std::move(d), reason);
}

void Autonomy::start_refinement(const TargetMeasurement& m) {
  estimator_.reset();
  phases::Refinement r;
  r.last_found_utime = m.utime;
  r.first_sighting_W = m.p_W_target;
  r.normal_sum_W = m.n_W;  // the plane's orientation is measured also from a part of it
  if (m.found) {
    estimator_.add(m.p_W_target, frame_cov(), m.size_m);
    r.sizes_m.push_back(m.size_m);
    r.yaw4_sum = Vector2d(std::cos(4 * m.yaw_rad), std::sin(4 * m.yaw_rad));
    r.yaw2_sum = Vector2d(std::cos(2 * m.yaw_rad), std::sin(2 * m.yaw_rad));
  }
  look_to_fit(r, m);
  auto& entered =
      enter(std::move(r),
            std::string(m.found ? "first waypoint X_V,1" : "first sighting (partly in view)") +
                " at (" + fmt(m.p_W_target.x()) + ", " + fmt(m.p_W_target.y()) + ", " +
                fmt(m.p_W_target.z()) + ")");
  next_vantage(entered);
}

void Autonomy::next_vantage(phases::Refinement& r) {
  // Around the first sighting until the first full-view waypoint.
  const Vector3d mu = estimator_.n() > 0 ? estimator_.mean() : r.first_sighting_W;
  const Vector3d here = pose_ ? pose_->p_W_B : mu;
  const auto v = profile_->vantage(mu, estimator_.covariance(), estimator_.n(), here,
                                   r.normal_sum_W, sampler_);
  r.vantage_W = r.view ? vantage_in_view(*r.view, mu, v.p_W) : v.p_W;
  if (v.yaw_rad) yaw_sp_rad_ = *v.yaw_rad;
  if (r.view) yaw_sp_rad_ = r.view->yaw_rad;
  r.vantage_since_utime = now_utime_;
  r.at_vantage_since_utime.reset();
  r.at_vantage_W.clear();
  r.at_vantage_size_m.clear();
}

bool Autonomy::look_to_fit(phases::Refinement& r, const TargetMeasurement& m) {
  if (!m.cut || mission() != Mission::kLanding || !params_.downward_view) return false;
  r.cut_views.push_back(m);
  if (r.cut_views.size() > kCutViewsToFit) r.cut_views.erase(r.cut_views.begin());
  // An unmeasured long side (NaN) sorts first, so the order stays strict.
  const auto long_side = [](const TargetMeasurement& v) {
    return std::isnan(v.size_m.x()) ? -std::numeric_limits<double>::infinity() : v.size_m.x();
  };
  std::vector<const TargetMeasurement*> views;
  for (const auto& v : r.cut_views) views.push_back(&v);
  const auto mid = views.begin() + static_cast<std::ptrdiff_t>((views.size() - 1) / 2);
  std::nth_element(views.begin(), mid, views.end(),
                   [&](const auto* a, const auto* b) { return long_side(*a) < long_side(*b); });
  const TargetMeasurement& fit = **mid;
  const double from_z = r.view ? r.view->z_m : params_.detection.landing_height_m;
  const double max_z = params_.geofence.max_W_m.z() - params_.hover_tol_m;
  const auto v = view_to_fit(*params_.downward_view, fit.size_m, fit.yaw_rad, fit.p_W_target.z(),
                             yaw_sp_rad_, from_z, max_z);
  if (!v) return false;
  if (r.view && v->z_m < r.view->z_m + kViewStepM &&
      std::abs(wrap_angle(v->yaw_rad - r.view->yaw_rad)) < kViewTurnRad)
    return false;
  r.view = *v;
  return true;
}

void Autonomy::finish_refinement(phases::Refinement& r) {
  const TargetFilter filter = estimator_.filter();
  estimate_W_ = filter.x;
  std::vector<double> a, b;
  for (const auto& s : r.sizes_m) {
    a.push_back(s.x());
    b.push_back(s.y());
  }
  const Vector2d size_m(a.empty() ? 0.0 : upper_median(a), b.empty() ? 0.0 : upper_median(b));
  if (const auto refusal = profile_->refuse(size_m.x(), size_m.y())) {
    hold(refusal->why, Failsafe::kNone, refusal->hold_min_z_m);
    return;
  }
  const std::string where = "estimate (" + fmt(estimate_W_.x()) + ", " + fmt(estimate_W_.y()) +
                            ", " + fmt(estimate_W_.z()) +
                            ") from n = " + std::to_string(estimator_.n());
  auto start = profile_->begin_approach(*pose_, yaw_sp_rad_, r.normal_sum_W, r.yaw4_sum);
  yaw_sp_rad_ = start.yaw_sp_rad;
  const double views = std::max<double>(1.0, static_cast<double>(r.sizes_m.size()));
  const TopRoom room = top_room(params_.landing, size_m, r.yaw2_sum / views, r.yaw4_sum / views);
  phases::Approach next{std::move(start.state), r.last_found_utime, {}, {}, size_m, room};
  if (estimate_) {
    const auto& R = params_.refinement;
    next.anchor.emplace(filter, estimator_.waypoint_noise(), frame_cov(), R.vantage_dwell_s,
                        R.gate_chi2);
  }
  enter(std::move(next), "refinement converged (eqs. 7-9): " + where);
}

void Autonomy::target_lost(const std::string& what) {
  ++retries_;
  estimator_.reset();
  if (retries_ > params_.detection.max_retries) {
    hold("target lost (" + what + "); " + std::to_string(params_.detection.max_retries) +
             " retries exhausted: holding",
         Failsafe::kNone, profile_->lost_hold_min_z_m());
    return;
  }
  start_detection("target lost (" + what + "): detection retry " + std::to_string(retries_) +
                  " of " + std::to_string(params_.detection.max_retries));
}

void Autonomy::handle_target(const TargetMeasurement& m) {
  if (!(m.found || m.partial) || m.mission != mission() || !m.p_W_target.allFinite() ||
      !m.n_W.allFinite() || !m.size_m.allFinite() || !std::isfinite(m.yaw_rad)) {
    return;
  }
  // A target cut by the image border is in sight (not lost) and locates it well enough to fly
  // the vantages around; it is never averaged into the estimate.
  const auto seen = [&](std::optional<int64_t>& last_found_utime) {
    last_found_utime = std::max(m.utime, last_found_utime.value_or(m.utime));
  };
  if (std::holds_alternative<phases::Detection>(state_)) {
    start_refinement(m);
  } else if (auto* a = std::get_if<phases::Approach>(&state_)) {
    seen(a->last_found_utime);
    if (a->moving) return;  // flown on the platform filter, not on the still estimate
    if (!m.found || vision_disagrees(*a, m)) return;
    if (a->anchor) {
      const double slack_m = partial_view_slack_m(a->size_m, m.size_m);
      if (const auto x = a->anchor->add(m.p_W_target, slack_m, m.utime, frame_cov()))
        estimate_W_ = *x;
    }
  } else if (auto* r = std::get_if<phases::Refinement>(&state_)) {
    seen(r->last_found_utime);
    if (!m.found) {
      // Until the first full view the vantages follow the newest partial one: its centre lies
      // between the vehicle and the true centre, so each vantage sees more of the target (in
      // Monte Carlo runs the draws around the first sighting alone kept it cut for 60 s).
      if (estimator_.n() == 0) r->first_sighting_W = m.p_W_target;
      if (look_to_fit(*r, m)) next_vantage(*r);
      return;
    }
    r->sizes_m.push_back(m.size_m);
    r->normal_sum_W += m.n_W;
    r->yaw4_sum += Vector2d(std::cos(4 * m.yaw_rad), std::sin(4 * m.yaw_rad));
    r->yaw2_sum += Vector2d(std::cos(2 * m.yaw_rad), std::sin(2 * m.yaw_rad));
    if (params_.refinement.one_waypoint_per_vantage) {
      // Added when the dwell ends.
      if (r->at_vantage_since_utime) {
        r->at_vantage_W.push_back(m.p_W_target);
        r->at_vantage_size_m.push_back(m.size_m);
      }
      return;
    }
    add_waypoint(*r, m.p_W_target, m.size_m);
  }
}

void Autonomy::handle_platform(const PlatformMeasurement& m) {
  const auto& M = params_.moving_platform;
  if (!M.enabled || mission() != Mission::kLanding) return;
  platform_.update(m);
  if (!(std::holds_alternative<phases::Detection>(state_) ||
        std::holds_alternative<phases::Refinement>(state_)))
    return;
  if (!platform_.believed() || !pose_) return;
  const auto pr = platform_.predict(now_utime_);
  if (!moving_enough(pr, M)) return;
  estimator_.reset();
  estimate_W_ << pr.p_W, pr.top_z_m;
  enter(phases::Approach{LandingApproach{}, m.utime, {}, MovingApproach{}},
        "moving platform at (" + fmt(pr.p_W.x()) + ", " + fmt(pr.p_W.y()) + "), " +
            fmt(pr.v_W.norm()) + " m/s: matching its motion");
}

void Autonomy::step_moving(phases::Approach& a, const Vector3d& /*p*/, double dt_s) {
  const auto& L = params_.landing;
  const auto& M = params_.moving_platform;
  if (!pose_) return;
  const MovingStep st = step_moving_approach(
      *a.moving, platform_, *pose_, now_utime_, dt_s, yaw_sp_rad_, landing_gear(L), M,
      params_.downward_view ? &*params_.downward_view : nullptr, terrain_m());
  const auto pr = platform_.predict(now_utime_);
  const auto fly_step = [&] {
    sp_p_W_ = st.sp_p_W;
    sp_v_W_ = st.sp_v_W;
    sp_a_W_ = st.sp_a_W;
    yaw_sp_rad_ = st.yaw_sp_rad;
    sp_yaw_rate_radps_ = st.yaw_rate_radps;
  };
  switch (st.next) {
    case MovingStep::Next::kTargetLost:
      target_lost(st.reason);
      return;
    case MovingStep::Next::kTooFast:
      platform_too_fast(st.reason + ", climbing and holding");
      return;
    case MovingStep::Next::kFloorUnderTop:
      // The track followed is not the platform (the floor seen through a drifted estimate): its
      // measurements would start the same approach again.
      platform_.reset();
      target_lost(st.reason);
      return;
    case MovingStep::Next::kFinalDescent: {
      phases::FinalDescent f{a.moving->z_sp_m, TouchdownDetector(L), false, {}, {}, true};
      f.touchdown.arm(now_utime_);
      fly_step();
      enter(std::move(f), st.reason);
      return;
    }
    case MovingStep::Next::kContinue:
      break;
  }
  estimate_W_ << pr.p_W, pr.top_z_m;
  fly_step();
  reason_ = st.reason;
}

bool Autonomy::look_at_candidate(phases::Detection& s) {
  const auto& M = params_.moving_platform;
  const auto stop = [&](const std::string& why) {
    if (s.looking) reason_ = "search resumed: " + why;
    s.looking = false;
    return false;
  };
  if (!M.enabled || mission() != Mission::kLanding) return false;
  if (!platform_.believed()) return stop("the platform looked at no longer believed");
  // Unmeasured this long the track has left the view (and is confirmed again if it returns).
  if (seconds(now_utime_ - platform_.utime()) > kConfirmS)
    return stop("the platform looked at out of view");
  if (s.looked_track_utime != platform_.since_utime()) {
    s.looked_track_utime = platform_.since_utime();
    s.look_since_utime = now_utime_;
    ++candidate_looks_;
  }
  const double looked_s = seconds(now_utime_ - s.look_since_utime), look_s = candidate_look_s(M);
  if (looked_s > look_s)
    return stop("the platform looked at showed no motion in " + fmt(look_s, 1) + " s");
  s.looking = true;
  const auto pr = platform_.predict(now_utime_);
  // The search's height: the top stays as much in view as the search saw it.
  sp_p_W_ = Vector3d(pr.p_W.x(), pr.p_W.y(), s.path.carrot().z());
  sp_v_W_ = Vector3d(pr.v_W.x(), pr.v_W.y(), 0.0);
  reason_ = "a platform at (" + fmt(pr.p_W.x()) + ", " + fmt(pr.p_W.y()) + "), " +
            fmt(pr.v_W.norm()) + " m/s: search paused, looking whether it moves (" +
            fmt(looked_s, 1) + " of " + fmt(look_s, 1) + " s)";
  return true;
}

void Autonomy::platform_too_fast(const std::string& reason) {
  const auto pr = platform_.predict(now_utime_);
  hold(reason, Failsafe::kPlatformTooFast,
       pr.top_z_m + params_.landing.gear_height_m + params_.moving_platform.follow_height_m + 0.3);
}

void Autonomy::go_around(const DropCheck& c) {
  ++drop_go_arounds_;
  const std::string why = c.beam == Beam::kFloor
                              ? "the rangefinder reads the floor under the gear, " +
                                    fmt(c.gear_above_m) + " m above the moving top"
                              : "the gear " + fmt(c.off_m.cwiseAbs().maxCoeff(), 3) +
                                    " m off the moving top's centre, beyond its room " +
                                    fmt(c.room_m, 3) + " m, " + fmt(c.gear_above_m) + " m above it";
  if (drop_go_arounds_ > kMaxDropGoArounds) {
    platform_too_fast("last drop given up " + std::to_string(drop_go_arounds_) + " times (" + why +
                      "): beyond what the vehicle lands on, climbing and holding");
    return;
  }
  enter(phases::Approach{LandingApproach{}, platform_.utime(), {}, MovingApproach{}},
        "last drop given up (" + why + "): go-around " + std::to_string(drop_go_arounds_) + " of " +
            std::to_string(kMaxDropGoArounds) + ", matching again at the final height");
}

bool Autonomy::vision_disagrees(phases::Approach& a, const TargetMeasurement& m) {
  // The estimate is final from APPROACH on (on the onboard estimate it follows the frame's drift,
  // by the targets that pass this gate); a target found far from it is refused and counted.
  // The gate: four of the waypoints' horizontal standard deviations (their stated noise), never
  // tighter than kVisionGateFloorM. Every found target refused for kVisionDisagreeS, at least
  // kVisionDisagreeMinTargets of them, is a sustained disagreement (a forged stream, or vision
  // locked onto something else): hold, then descend; never a silent move of the estimate onto
  // the new targets.
  const Eigen::Matrix2d cov = estimator_.covariance().topLeftCorner<2, 2>();
  // The larger eigenvalue of the symmetric 2x2 horizontal covariance, in closed form.
  const double mean_var = 0.5 * (cov(0, 0) + cov(1, 1));
  const double half_gap = std::hypot(0.5 * (cov(0, 0) - cov(1, 1)), cov(0, 1));
  const double sigma = std::sqrt(std::max(0.0, mean_var + half_gap));
  const double gate_m =
      std::max(kVisionGateFloorM, 4.0 * sigma) + partial_view_slack_m(a.size_m, m.size_m);
  const double off_m = (m.p_W_target - estimate_W_).head<2>().norm();
  if (off_m <= gate_m) {
    a.disagree_since_utime.reset();
    a.n_disagreeing = 0;
    return false;
  }
  ++vision_refused_;
  if (!a.disagree_since_utime) a.disagree_since_utime = m.utime;
  ++a.n_disagreeing;
  if (seconds(m.utime - *a.disagree_since_utime) >= kVisionDisagreeS &&
      a.n_disagreeing >= kVisionDisagreeMinTargets) {
    // Held and descended over the profile's point, not where the vehicle happened to be: that
    // may be over the top's edge.
    failsafe_ = Failsafe::kVisionDisagrees;
    const Vector3d here = pose_ ? pose_->p_W_B : sp_p_W_;
    enter(phases::Hold{profile_->approach_failsafe_hold_W(here, sp_p_W_),
                       now_utime_ + static_cast<int64_t>(kFailsafeHoldS * 1e6)},
          "vision disagrees with the estimate: every target for " +
              fmt(seconds(m.utime - *a.disagree_since_utime), 1) + " s (" +
              std::to_string(a.n_disagreeing) + ") lay " + fmt(off_m) + " m from it (gate " +
              fmt(gate_m) + " m): holding, then descending");
  }
  return true;
}

void Autonomy::add_waypoint(phases::Refinement& r, const Vector3d& X_W, const Vector2d& size_m) {
  const auto verdict = estimator_.add(X_W, frame_cov(), size_m);
  if (verdict == RefinementEstimator::Verdict::kRestarted) {
    reason_ =
        "estimate restarted: " + std::to_string(params_.refinement.max_consecutive_rejections) +
        " waypoints in a row outside the gate";
  } else if (verdict == RefinementEstimator::Verdict::kSetAside) {
    reason_ = "waypoint set aside: its view measured the target " + fmt(size_m.x()) + " x " +
              fmt(size_m.y()) + " m, a part of it (" + std::to_string(estimator_.n_set_aside()) +
              " set aside)";
  }
  if (estimator_.converged()) finish_refinement(r);  // leaves REFINEMENT: r is gone
}

void Autonomy::step_phase(double dt_s) {
  const Vector3d p = pose_ ? pose_->p_W_B : sp_p_W_;
  zero_feedforward();
  std::visit(
      [&](auto& s) {
        using S = std::decay_t<decltype(s)>;
        if constexpr (std::is_same_v<S, phases::Idle> || std::is_same_v<S, phases::Landed> ||
                      std::is_same_v<S, phases::Killed>) {
          motors_on_ = false;
          sp_p_W_ = p;
        } else if constexpr (std::is_same_v<S, phases::Hold>) {
          sp_p_W_ = s.hold_p_W;
          // Down only once over the hold point: the descent stays where the hold was put.
          const Vector2d hold_xy(s.hold_p_W.x(), s.hold_p_W.y());
          const bool over =
              std::hypot(p.x() - hold_xy.x(), p.y() - hold_xy.y()) <= params_.hover_tol_m;
          if (s.descend_at_utime && now_utime_ >= *s.descend_at_utime && over)
            enter_failsafe_descent(failsafe_,
                                   "failsafe hold over: controlled descent, disarm on "
                                   "touch-down",
                                   hold_xy);
        } else if constexpr (std::is_same_v<S, phases::Hover> || std::is_same_v<S, phases::Done>) {
          sp_p_W_ = s.hold_p_W;
        } else {
          step(s, p, dt_s);
        }
      },
      state_);
}

void Autonomy::step(phases::Takeoff& s, const Vector3d& p, double dt_s) {
  const auto& T = params_.takeoff;
  if (s.z_sp_m < T.height_m) {
    s.z_sp_m = std::min(T.height_m, s.z_sp_m + T.climb_rate_mps * dt_s);
    sp_v_W_.z() = T.climb_rate_mps;
  }
  sp_p_W_ = Vector3d(s.xy_W.x(), s.xy_W.y(), s.z_sp_m);
  if (s.z_sp_m >= T.height_m && (p - sp_p_W_).norm() < T.reached_tol_m) {
    enter(phases::Hover{sp_p_W_}, "take-off complete: hovering, waiting for GO");
  }
}

void Autonomy::step(phases::Detection& s, const Vector3d& p, double dt_s) {
  if (hold_if_vision_silent()) return;
  if (look_at_candidate(s)) return;
  s.path.step(p, dt_s, params_.detection.speed_mps, kPathLeadM);
  sp_p_W_ = s.path.carrot();
  sp_v_W_ = s.path.carrot_velocity();
  if (s.path.finished(p, params_.hover_tol_m)) {
    target_lost("search path flown without a detection");
  }
}

void Autonomy::step(phases::Refinement& r, const Vector3d& p, double /*dt_s*/) {
  if (hold_if_vision_silent()) return;
  const auto& R = params_.refinement;
  const double since_found = since_found_s(r.last_found_utime);
  if (since_found > R.lost_timeout_s) {
    target_lost("no target seen for " + fmt(since_found, 1) + " s in refinement");
    return;
  }
  if (seconds(now_utime_ - phase_start_utime_) > R.max_time_s) {
    hold("refinement did not converge in " + fmt(R.max_time_s, 0) + " s", Failsafe::kNone, 0.0);
    return;
  }
  if ((p - r.vantage_W).norm() < R.vantage_reach_tol_m) {
    if (!r.at_vantage_since_utime) r.at_vantage_since_utime = now_utime_;
    if (seconds(now_utime_ - *r.at_vantage_since_utime) >= R.vantage_dwell_s) {
      if (!R.one_waypoint_per_vantage) {
        next_vantage(r);
      } else if (!r.at_vantage_W.empty()) {
        // The vantage's waypoint: the median is robust to a stray frame among few.
        add_waypoint(r, componentwise_median(r.at_vantage_W),
                     componentwise_median_2d(r.at_vantage_size_m));
        if (phase() != Phase::kRefinement) return;  // converged (or held): r is gone
        next_vantage(r);
      } else {
        // Nothing seen here: hovering does not help (the vision's baseline shrinks to zero
        // as the reference frames age), moving on does.
        next_vantage(r);
      }
    }
  } else if (seconds(now_utime_ - r.vantage_since_utime) > R.vantage_timeout_s) {
    next_vantage(r);
  }
  sp_p_W_ = r.vantage_W;
}

void Autonomy::step(phases::Approach& a, const Vector3d& p, double dt_s) {
  if (a.moving) {
    step_moving(a, p, dt_s);
    return;
  }
  const ApproachInputs in{
      pose_, p,          estimate_W_, yaw_sp_rad_, since_found_s(a.last_found_utime),
      dt_s,  now_utime_, a.room};
  ApproachStep next = profile_->step_approach(a.how, in);
  if (next.next == ApproachStep::Next::kTargetLost) {
    target_lost(next.reason);
    return;
  }
  sp_p_W_ = next.sp_p_W;
  sp_v_W_ = next.sp_v_W;
  switch (next.next) {
    case ApproachStep::Next::kContinue:
      if (!next.reason.empty()) reason_ = std::move(next.reason);
      return;
    case ApproachStep::Next::kFinalDescent: {
      const auto& l = std::get<LandingApproach>(a.how);
      phases::FinalDescent f{l.z_sp_m, TouchdownDetector(params_.landing), !l.land_here, {}, {}};
      f.room = a.room;
      if (l.held_since_utime) f.held_s = seconds(now_utime_ - *l.held_since_utime);
      f.touchdown.arm(now_utime_);
      enter(std::move(f), std::move(next.reason));
      return;
    }
    case ApproachStep::Next::kDone:
      end_utime_ = now_utime_;
      enter(phases::Done{sp_p_W_}, std::move(next.reason));
      return;
    case ApproachStep::Next::kTargetLost:
      return;
  }
}

void Autonomy::step(phases::FinalDescent& s, const Vector3d& /*p*/, double dt_s) {
  const auto& L = params_.landing;
  if (s.moving) {
    // Onto the moving platform: over its predicted centre, its velocity fed forward; a lost
    // platform does not stop the drop (finishing it is the safe end, as in the still landing).
    // Resting is judged relative to the deck's predicted heave.
    if (pose_fresh()) {
      const DropCheck c = check_drop(platform_, *pose_, now_utime_, landing_gear(L),
                                     params_.moving_platform, terrain_m());
      if (c.verdict == Drop::kOffTheTop) {  // leaves the phase: s is gone after this
        go_around(c);
        return;
      }
    }
    const auto pr = platform_.predict(now_utime_);
    const double z_floor = pr.top_z_m + L.gear_height_m - L.final_depth_m;
    if (s.z_sp_m > z_floor)
      s.z_sp_m = std::max(z_floor, s.z_sp_m - L.final_descent_rate_mps * dt_s);
    sp_p_W_ << pr.p_W, s.z_sp_m;
    sp_v_W_ << pr.v_W, s.z_sp_m > z_floor ? -L.final_descent_rate_mps : 0.0;
    sp_a_W_ << pr.a_W, 0.0;
    // The gear stays turned onto the turning platform's edges all the way down.
    yaw_sp_rad_ = aligned_yaw(pr.yaw_rad, yaw_sp_rad_);
    sp_yaw_rate_radps_ = followed_turn_radps(pr.yaw_rate_rps, params_.moving_platform);
    estimate_W_ << pr.p_W, pr.top_z_m;
    s.touchdown.set_contact_z(pr.top_z_m + L.gear_height_m);
    if (pose_fresh()) {
      PoseSample rel = *pose_;
      rel.v_W_B.z() -= platform_.heave().vz(now_utime_) - platform_.heave().c;
      s.touchdown.add_pose(rel, s.z_sp_m, now_utime_);
    }
    if (s.touchdown.detected()) {
      motors_on_ = false;
      end_utime_ = now_utime_;
      // Down on the ground beside the platform (its prediction ran off in the drop's blind end):
      // on the ground all the same, but not landed on the platform, and the status says so.
      const double below_m = pose_ ? pr.top_z_m - (pose_->p_W_B.z() - L.gear_height_m) : 0.0;
      if (touched_down_on_top(below_m, platform_.heave().amplitude_m())) {
        enter(phases::Landed{}, std::string("touch-down on the moving platform (") +
                                    s.touchdown.cue() + "): motors off");
      } else {
        enter(phases::Landed{}, std::string("touch-down beside the moving platform (") +
                                    s.touchdown.cue() + ", the gear " + fmt(below_m) +
                                    " m below its top): motors off");
      }
    }
    return;
  }
  const double z_touch = estimate_W_.z() + L.gear_height_m;
  const double z_floor = z_touch - L.final_depth_m;
  const FinalPause pause = pause_final_descent(s, z_touch);
  if (pause == FinalPause::kGaveUp) {  // leaves the phase: s is gone after this
    target_lost(no_calm_moment(L, "paused"));
    return;
  }
  if (pause == FinalPause::kPaused) {
    sp_v_W_.z() = 0.0;  // s.z_sp_m was set where the pause began
  } else if (s.z_sp_m > z_floor) {
    s.z_sp_m = std::max(z_floor, s.z_sp_m - L.final_descent_rate_mps * dt_s);
    sp_v_W_.z() = -L.final_descent_rate_mps;
  }
  sp_p_W_ << estimate_W_.head<2>() + body_over_gear_xy(L, pose_), s.z_sp_m;
  s.touchdown.set_contact_z(z_touch);
  if (pose_fresh()) s.touchdown.add_pose(*pose_, s.z_sp_m, now_utime_);
  if (s.touchdown.detected()) {
    motors_on_ = false;
    end_utime_ = now_utime_;
    enter(phases::Landed{}, std::string("touch-down (") + s.touchdown.cue() + "): motors off");
  }
}

Autonomy::FinalPause Autonomy::pause_final_descent(phases::FinalDescent& s, double z_touch_m) {
  const auto& L = params_.landing;
  // Only on a fresh pose and a sound estimate: otherwise finishing the descent is the safe end
  // (react_to_estimate leaves the final descent alone for that reason), not hovering on it.
  const auto e = estimate_condition();
  if (!s.may_pause || L.final_pause_radial_m <= 0 || !pose_fresh() ||
      (e && e->level != EstimateHealth::Level::kOk)) {
    s.paused_since_utime.reset();
    return FinalPause::kNone;
  }
  const Vector2d e_W = pose_->p_W_B.head<2>() - body_over_gear_xy(L, pose_) - estimate_W_.head<2>();
  const double e_r = e_W.norm();
  if (!s.paused_since_utime) {
    // A descent that began on the hold's grown bounds pauses as much further out.
    if (!carried_off(L, e_W, calm_bounds(L, s.held_s, s.room), s.room) ||
        pose_->p_W_B.z() - z_touch_m <= L.final_pause_min_height_m)
      return FinalPause::kNone;
    s.paused_since_utime = now_utime_;
    s.calm_since_utime.reset();
    // Stopped where the vehicle is, not below it where the setpoint led: the altitude loop still
    // overshoots by its lag, hence final_pause_min_height_m.
    s.z_sp_m = std::max(s.z_sp_m, pose_->p_W_B.z());
  }
  const double paused_s = seconds(now_utime_ - *s.paused_since_utime);
  if (calm_for_final_descent(L, e_W, pose_, s.held_s + paused_s, s.room, now_utime_,
                             s.calm_since_utime)) {
    // Resumed on the bounds the wait earned: the descent pauses again only beyond them.
    s.held_s += paused_s;
    s.paused_since_utime.reset();
    reason_ = "final descent resumed: calm again";
    return FinalPause::kNone;
  }
  if (paused_s > L.final_hold_timeout_s) return FinalPause::kGaveUp;
  reason_ = "final descent paused: carried " + fmt(e_r, 3) + " m off, waiting for calm";
  return FinalPause::kPaused;
}

void Autonomy::step(phases::FailsafeDescent& s, const Vector3d& /*p*/, double /*dt_s*/) {
  if (!motors_on_) return;
  // The cause cleared: the pose fresh again (and the estimate, if any, not LOST: a hold would
  // fail over to its failsafe at once), or the estimate OK again on a fresh pose.
  const auto e = estimate_condition();
  const bool estimate_ok = e && e->level == EstimateHealth::Level::kOk;
  const bool estimate_lost = e && e->level == EstimateHealth::Level::kLost;
  const bool cleared = pose_fresh() && (failsafe_ == Failsafe::kPoseLost       ? !estimate_lost
                                        : failsafe_ == Failsafe::kEstimateLost ? estimate_ok
                                                                               : false);
  if (cleared && !s.touchdown.detected()) {
    // Cleared for good: stop descending where the failsafe happened to be (over a platform's
    // edge it tips the vehicle) and hold; the operator decides, as after any failsafe whose
    // cause has cleared.
    if (!s.recovered_since_utime) s.recovered_since_utime = now_utime_;
    const double back_s = seconds(now_utime_ - *s.recovered_since_utime);
    if (back_s >= params_.failsafe.pose_recovered_s) {
      hold((failsafe_ == Failsafe::kPoseLost ? "motion capture back for "
                                             : "state estimate OK again for ") +
               fmt(back_s, 1) + " s: failsafe descent stopped, holding; waiting for the operator",
           Failsafe::kNone, 0.0);
      return;
    }
  } else if (!cleared) {
    s.recovered_since_utime.reset();
  }
  if (pose_fresh()) {
    // Pose back: a controlled descent on it instead of the outer loop's open-loop one.
    sp_p_W_.z() = s.z0_m - params_.failsafe.descent_mps * seconds(now_utime_ - s.since_utime);
    sp_v_W_.z() = -params_.failsafe.descent_mps;
    s.touchdown.add_pose(*pose_, sp_p_W_.z(), now_utime_);
  }
  if (s.touchdown.detected()) {
    motors_on_ = false;
    s.touchdown.disarm();
    reason_ = std::string("failsafe descent: touch-down (") + s.touchdown.cue() + "): motors off";
  }
}

void Autonomy::zero_feedforward() {
  sp_v_W_.setZero();
  sp_a_W_.setZero();
  sp_yaw_rate_radps_ = 0.0;
}

Output Autonomy::make_output() {
  // The last line of defence: whatever got through, a non-finite setpoint is never sent (NaN
  // passes cwiseMax / cwiseMin, so the geofence alone does not stop it).
  if (!sp_p_W_.allFinite() || !sp_v_W_.allFinite() || !sp_a_W_.allFinite() ||
      !std::isfinite(yaw_sp_rad_) || !std::isfinite(sp_yaw_rate_radps_)) {
    sp_p_W_ = last_finite_sp_p_W_;
    zero_feedforward();
    yaw_sp_rad_ = last_finite_yaw_rad_;
    if (Vector3d* held = held_position(); held && !held->allFinite()) *held = last_finite_sp_p_W_;
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
  sp.a_W = geofence_clamped_ ? Vector3d::Zero() : sp_a_W_;
  sp.yaw_rad = yaw_sp_rad_;
  sp.yaw_rate_radps = sp_yaw_rate_radps_;
  sp.motors_on = motors_on_;
  sp.kill =
      phase() == Phase::kKilled;  // the outer loop disarms in the air only on an explicit KILL
  sp.idle = false;
  sp.precise = motors_on_ && precise_setpoint();

  out.has_setpoint = started_;
  auto& st = out.status;
  st.utime = now_utime_;
  st.mission = mission();
  st.phase = phase();
  st.reason = reason_;
  st.n_measurements = estimator_.n();
  st.n_rejected = estimator_.n_rejected();
  st.retries = retries_;
  const bool final = st.phase == Phase::kApproach || st.phase == Phase::kFinalDescent ||
                     st.phase == Phase::kLanded || st.phase == Phase::kDone;
  st.has_estimate = final || estimator_.n() > 0;
  st.estimate_W = final ? estimate_W_ : estimator_.mean();
  st.covariance = estimator_.covariance();
  st.setpoint_W = sp.p_W;
  st.failsafe = failsafe_;
  st.cmds_rejected = gate_.n_rejected();
  st.last_cmd_seq = gate_.last_accepted_seq();
  st.last_rejected_seq = gate_.last_rejected_seq();
  st.last_reject_reason = gate_.last_reject_reason();
  st.cmds_rejected_by_reason = gate_.n_rejected_by_reason();
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
  if (in.imu && in.imu->accel_B.allFinite() && in.imu->gyro_B.allFinite()) {
    if (TouchdownDetector* td = touchdown()) td->add_imu(*in.imu);
  }
  if (in.estimate && (!estimate_ || in.estimate->utime >= estimate_->utime)) {
    estimate_ = in.estimate;
  }
  if (!started_ && pose_) start_from_first_pose();
  std::optional<std::string> command_reply;  // this update's command's answer (accepted or why not)
  if (in.command) {
    handle_command(*in.command);
    command_reply = reason_;
  }
  // Before the pose's checks: a stale pose freezes the mission for up to pose_lost_s, and a LOST
  // estimate must not wait behind it.
  const bool paused = react_to_estimate();
  // A pause's progress would overwrite the answer before anything published it (a GO refused
  // for the DEGRADED estimate that paused the hover): the operator reads the answer first.
  if (paused && command_reply) reason_ = *command_reply;

  if (airborne() && phase() != Phase::kFailsafe) {
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

  if (paused) {
    // At rest where the pause began: no progress, no measurement taken on the degraded pose.
    sp_p_W_ = pause_p_W_;
    zero_feedforward();
    return make_output();
  }
  if (in.target) {
    last_vision_utime_ = now_utime_;
    handle_target(*in.target);
  }
  if (in.platform) handle_platform(*in.platform);
  step_phase(dt_s);
  return make_output();
}

}  // namespace alight::autonomy
