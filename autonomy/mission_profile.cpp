#include "autonomy/mission_profile.hpp"

#include <algorithm>
#include <cmath>

#include "autonomy/search_path.hpp"
#include "autonomy/text.hpp"

namespace alight::autonomy {
namespace {

double seconds(int64_t dt_utime) { return static_cast<double>(dt_utime) * 1e-6; }

// Vantages at least this far from where the vehicle is: the vision needs a baseline of a few
// centimetres (waypoint.min_baseline_m) between its reference and current image [m].
constexpr double kMinVantageStepM = 0.08;

// The horizontal unit normal of the measured normals' sum (the opening faces -x without one).
Vector3d horizontal_normal(const Vector3d& normal_sum_W) {
  Vector3d n = normal_sum_W;
  n.z() = 0;
  return n.norm() > 1e-6 ? Vector3d(n.normalized()) : Vector3d(-1, 0, 0);
}

// Facing the opening: the camera looks along -n.
double yaw_facing(const Vector3d& n_W) { return std::atan2(-n_W.y(), -n_W.x()); }

class LandingProfile final : public MissionProfile {
 public:
  explicit LandingProfile(const AutonomyParams& params) : p_(params) {}

  Mission mission() const override { return Mission::kLanding; }

  Search search(const Vector3d& p_W) const override {
    // Up (or down) to the search height above where we are: a safe hover, then the lawnmower.
    const auto& d = p_.detection;
    Search s;
    s.path_W.emplace_back(p_W.x(), p_W.y(), d.landing_height_m);
    const auto lm = lawnmower(d.landing_area_min_W_m, d.landing_area_max_W_m, d.lane_spacing_m,
                              d.landing_height_m);
    s.path_W.insert(s.path_W.end(), lm.begin(), lm.end());
    return s;
  }

  Vantage vantage(const Vector3d& mu_W, const Matrix3d& S_W, int n, const Vector3d& here_W,
                  const Vector3d& /*normal_sum_W*/, VantageSampler& sampler) const override {
    // A vantage next to the current position gives the vision no baseline: redraw (bounded).
    const Vector2d here = here_W.head<2>();
    Vector2d xy = sampler.draw(mu_W.head<2>(), S_W.topLeftCorner<2, 2>(), n);
    for (int k = 0; k < 10 && (xy - here).norm() < kMinVantageStepM; ++k)
      xy = sampler.draw(mu_W.head<2>(), S_W.topLeftCorner<2, 2>(), n);
    return {Vector3d(xy.x(), xy.y(), p_.detection.landing_height_m), std::nullopt};
  }

  std::optional<Refusal> refuse(double size_a_m, double size_b_m) const override {
    const auto& L = p_.landing;
    const double short_side = std::min(size_a_m, size_b_m);
    const double needed = L.gear_footprint_m + 2 * L.fit_margin_m;
    if (short_side >= needed) return std::nullopt;  // NaN-safe: an unmeasured size is refused
    return Refusal{"refused to land: platform short side " + fmt(short_side) +
                       " m < gear footprint " + fmt(L.gear_footprint_m) + " m + 2 x margin " +
                       fmt(L.fit_margin_m) + " m",
                   p_.takeoff.height_m};
  }

  Start begin_approach(const PoseSample& pose, double yaw_sp_rad, const Vector3d& /*normal_sum_W*/,
                       const Vector2d& yaw4_sum) const override {
    Start s{LandingApproach{pose.p_W_B.z(), false, {}, {}}, yaw_sp_rad};
    if (p_.landing.align_yaw_tol_deg > 0 && yaw4_sum.norm() > 1e-9) {
      // The platform's edges modulo 90 deg (the gear is square): the turn of at most 45 deg.
      const double edges = std::atan2(yaw4_sum.y(), yaw4_sum.x()) / 4;
      const double now = yaw_of(pose.q_WB.toRotationMatrix());
      const double k = std::round(wrap_angle(now - edges) / (M_PI / 2));
      s.yaw_sp_rad = wrap_angle(edges + k * M_PI / 2);
    }
    return s;
  }

  ApproachStep step_approach(ApproachState& state, const ApproachInputs& in) const override {
    auto& a = std::get<LandingApproach>(state);
    const auto& L = p_.landing;
    const Vector3d& p = in.p_W;
    const Vector3d& target = in.target_W;
    ApproachStep out;
    const double z_touch = target.z() + L.gear_height_m;  // body z on the platform
    const Vector2d body_over_gear = body_over_gear_xy(L, in.pose);
    const Vector2d e_W = p.head<2>() - body_over_gear - target.head<2>();
    const double e_r = e_W.norm();
    const bool turned =
        L.align_yaw_tol_deg <= 0 || !in.pose ||
        std::abs(wrap_angle(yaw_of(in.pose->q_WB.toRotationMatrix()) - in.yaw_sp_rad)) <=
            L.align_yaw_tol_deg * M_PI / 180.0;
    const bool descending = e_r <= descent_tolerance_m(L, p.z() - z_touch) && turned;
    // Beyond the paper: a target unseen for lost_timeout_s is lost, counting only the time the
    // vehicle was not descending onto the estimate. That descent moves the camera along its
    // axis, so the top sits at the epipole, where its parallax against the floor vanishes and
    // vision cannot part it from the floor (a top near the epipole, no target plane, small
    // baseline): not seeing it there is no sign that it is gone. Held or moving sideways, vision
    // has the parallax to see it. A sighting starts the count again.
    a.unseen_s = std::min(in.since_found_s, a.unseen_s + (descending ? 0.0 : in.dt_s));
    if (!a.land_here && p.z() - z_touch > L.lost_check_height_m && a.unseen_s > L.lost_timeout_s) {
      out.next = ApproachStep::Next::kTargetLost;
      out.reason = "no target seen for " + fmt(in.since_found_s, 1) + " s in approach (" +
                   fmt(a.unseen_s, 1) + " s of it not descending)";
      return out;
    }
    if (descending) {  // descend only inside the prescribed volume
      a.z_sp_m -= L.descent_rate_mps * in.dt_s;
      out.sp_v_W.z() = -L.descent_rate_mps;
    }
    const bool may_hold = L.final_hold_speed_mps > 0 && !a.land_here;
    if (may_hold && a.z_sp_m - z_touch <= L.final_height_m) {
      a.z_sp_m = z_touch + L.final_height_m;  // waits here (final_descent_allowed)
      out.sp_v_W.z() = 0.0;
    }
    out.sp_p_W << target.head<2>() + body_over_gear, a.z_sp_m;
    if (a.at_final_height(target.z(), L.gear_height_m, L.final_height_m)) {
      if (!final_descent_allowed(a, e_W, in)) {
        if (seconds(in.now_utime - *a.held_since_utime) > L.final_hold_timeout_s) {
          out.next = ApproachStep::Next::kTargetLost;
          out.reason = no_calm_moment(L, "held");
          return out;
        }
        out.reason = "final descent held: waiting for calm";
        return out;
      }
      out.next = ApproachStep::Next::kFinalDescent;
      out.reason = "final descent: " + fmt(L.final_height_m, 2) + " m above the platform";
    }
    return out;
  }

  double lost_hold_min_z_m() const override { return p_.detection.landing_height_m; }

  Vector3d approach_failsafe_hold_W(const Vector3d& /*here_W*/,
                                    const Vector3d& sp_W) const override {
    return sp_W;
  }

  // At final_height_m: the rapid final descent starts only in a calm moment
  // (calm_for_final_descent).
  bool final_descent_allowed(LandingApproach& a, const Vector2d& e_W,
                             const ApproachInputs& in) const {
    const auto& L = p_.landing;
    if (L.final_hold_speed_mps <= 0 || a.land_here) return true;
    if (!a.held_since_utime) a.held_since_utime = in.now_utime;
    return calm_for_final_descent(L, e_W, in.pose, seconds(in.now_utime - *a.held_since_utime),
                                  in.room, in.now_utime, a.calm_since_utime);
  }

 private:
  AutonomyParams p_;
};

class IngressProfile final : public MissionProfile {
 public:
  explicit IngressProfile(const AutonomyParams& params) : p_(params) {}

  Mission mission() const override { return Mission::kIngress; }

  Search search(const Vector3d& /*p_W*/) const override {
    const auto& d = p_.detection;
    return {{d.ingress_start_W_m, d.ingress_end_W_m}, d.ingress_yaw_deg * M_PI / 180.0};
  }

  Vantage vantage(const Vector3d& mu_W, const Matrix3d& S_W, int n, const Vector3d& here_W,
                  const Vector3d& normal_sum_W, VantageSampler& sampler) const override {
    // In the plane parallel to the wall at the standoff: along-wall t and vertical z.
    const Vector3d nh = horizontal_normal(normal_sum_W);
    // One frame's sighting (a partial view, or the detection's waypoint before any dwell) never
    // draws the vehicle towards the wall: a smooth wall misread as the busy room's back wall
    // seen through the opening puts the sighting metres beyond the true wall, and the standoff
    // from it lies behind the wall. Until a dwell's waypoint stands beside it, the vantage keeps
    // the vehicle's own distance from the sighted plane where that is the larger: a sighting
    // from nearer than the standoff (the search pass) backs off to it as before, one from
    // farther (GO where the hover sees the opening) closes in after the first dwell.
    double standoff_m = p_.refinement.ingress_standoff_m;
    if (n <= 1) standoff_m = std::max(standoff_m, nh.dot(here_W - mu_W));
    const Vector3d t(-nh.y(), nh.x(), 0);
    Eigen::Matrix<double, 3, 2> B;
    B.col(0) = t;
    B.col(1) = Vector3d::UnitZ();
    const Vector2d mu2(t.dot(mu_W), mu_W.z());
    const Eigen::Matrix2d S2 = B.transpose() * S_W * B;
    const Vector2d d = sampler.draw(mu2, S2, n) - mu2;
    return {mu_W + nh * standoff_m + t * d.x() + Vector3d::UnitZ() * d.y(), yaw_facing(nh)};
  }

  std::optional<Refusal> refuse(double size_a_m, double size_b_m) const override {
    const auto& I = p_.ingress;
    const double need_w = I.vehicle_span_m + 2 * I.clearance_m;
    const double need_h = I.vehicle_height_m + 2 * I.clearance_m;
    if (size_a_m >= need_w && size_b_m >= need_h) return std::nullopt;  // NaN-safe
    return Refusal{"refused ingress: opening " + fmt(size_a_m) + " x " + fmt(size_b_m) +
                       " m smaller than the vehicle + clearance " + fmt(need_w) + " x " +
                       fmt(need_h) + " m",
                   0.0};
  }

  Start begin_approach(const PoseSample& /*pose*/, double /*yaw_sp_rad*/,
                       const Vector3d& normal_sum_W, const Vector2d& /*yaw4_sum*/) const override {
    IngressApproach a;
    a.n_W = horizontal_normal(normal_sum_W);
    return {a, yaw_facing(a.n_W)};
  }

  ApproachStep step_approach(ApproachState& state, const ApproachInputs& in) const override {
    auto& a = std::get<IngressApproach>(state);
    const auto& I = p_.ingress;
    const Vector3d& p = in.p_W;
    const Vector3d& n = a.n_W;
    const Vector3d t(-n.y(), n.x(), 0);
    ApproachStep out;
    if (!a.through) {
      if (I.lost_timeout_s > 0 && in.since_found_s > I.lost_timeout_s) {
        out.next = ApproachStep::Next::kTargetLost;
        out.reason = "no target seen for " + fmt(in.since_found_s, 1) + " s while aligning";
        return out;
      }
      out.sp_p_W = in.target_W + n * I.standoff_m;
      const bool aligned = (p - out.sp_p_W).norm() < I.align_tol_m && in.pose &&
                           in.pose->v_W_B.norm() < I.align_speed_mps;
      if (!aligned) {
        a.aligned_since_utime.reset();
      } else if (!a.aligned_since_utime) {
        a.aligned_since_utime = in.now_utime;
      } else if (seconds(in.now_utime - *a.aligned_since_utime) >= I.align_settle_s) {
        a.through = true;
        a.through_s_m = 0.0;
        out.reason = "aligned on the opening's normal: flying through";
      }
      return out;
    }
    const Vector3d d = p - in.target_W;
    const double lateral = d.dot(t), vertical = d.z();
    const double s_end = I.standoff_m + I.pass_distance_m;
    const double s_vehicle = I.standoff_m - d.dot(n);  // progress of the vehicle
    const bool inside =
        std::abs(lateral) <= I.lateral_tol_m && std::abs(vertical) <= I.vertical_tol_m;
    if (inside && a.through_s_m < s_end && a.through_s_m - s_vehicle < kPathLeadM) {
      a.through_s_m = std::min(s_end, a.through_s_m + I.speed_mps * in.dt_s);
      out.sp_v_W = -n * I.speed_mps;
    }
    out.sp_p_W = in.target_W + n * (I.standoff_m - a.through_s_m);
    if (a.through_s_m >= s_end && (p - out.sp_p_W).norm() < p_.hover_tol_m) {
      out.next = ApproachStep::Next::kDone;
      out.reason = "through the opening: " + fmt(I.pass_distance_m, 2) + " m past the wall";
    }
    return out;
  }

  double lost_hold_min_z_m() const override { return 0.0; }

  Vector3d approach_failsafe_hold_W(const Vector3d& here_W,
                                    const Vector3d& /*sp_W*/) const override {
    return here_W;
  }

 private:
  AutonomyParams p_;
};

}  // namespace

std::string no_calm_moment(const LandingParams& L, const std::string& what) {
  const double speed_max_mps = std::max(L.final_hold_speed_mps, L.final_hold_speed_max_mps);
  return "final descent " + what + " " + fmt(L.final_hold_timeout_s, 0) +
         " s without a calm moment (e_r within " +
         fmt(std::min(L.radial_tol_m, L.final_hold_radial_m), 3) + " m, speed within " +
         fmt(L.final_hold_speed_mps, 2) +
         (speed_max_mps > L.final_hold_speed_mps ? " to " + fmt(speed_max_mps, 2) : "") +
         " m/s; or heading within the top's room)";
}

double descent_tolerance_m(const LandingParams& L, double gear_above_top_m) {
  return L.radial_tol_m * std::max(1.0, gear_above_top_m / L.final_height_m);
}

Vector2d body_over_gear_xy(const LandingParams& L, const std::optional<PoseSample>& pose) {
  if (!L.aim_gear || !pose) return Vector2d::Zero();
  return L.gear_height_m * (pose->q_WB * Vector3d::UnitZ()).head<2>();
}

double range_to_fit(const DownwardView& view, const Vector2d& size_m, double top_yaw_rad,
                    double view_yaw_rad, double pad_m) {
  const double c = std::abs(std::cos(top_yaw_rad - view_yaw_rad));
  const double s = std::abs(std::sin(top_yaw_rad - view_yaw_rad));
  const double along_long = 0.5 * (c * size_m.x() + s * size_m.y()) + pad_m;
  const double along_short = 0.5 * (s * size_m.x() + c * size_m.y()) + pad_m;
  return std::max(along_long / view.tan_long, along_short / view.tan_short);
}

std::optional<ViewToFit> view_to_fit(const DownwardView& view, const Vector2d& size_m,
                                     double top_yaw_rad, double top_z_m, double body_yaw_rad,
                                     double from_z_m, double max_z_m) {
  if (!(view.tan_long > 0 && view.tan_short > 0) || !size_m.allFinite() ||
      !std::isfinite(top_yaw_rad) || !std::isfinite(top_z_m))
    return std::nullopt;
  const double view_yaw = body_yaw_rad + view.long_axis_yaw_B_rad;
  if (top_z_m + range_to_fit(view, size_m, top_yaw_rad, view_yaw, kViewPadM) <= from_z_m)
    return std::nullopt;
  ViewToFit v;
  v.top_yaw_rad = top_yaw_rad;
  // The image's long axis along the top's: two headings half a turn apart; the nearer.
  v.yaw_rad = wrap_angle(top_yaw_rad - view.long_axis_yaw_B_rad);
  if (std::abs(wrap_angle(v.yaw_rad - body_yaw_rad)) > M_PI / 2)
    v.yaw_rad = wrap_angle(v.yaw_rad + M_PI);
  const double range = range_to_fit(view, size_m, top_yaw_rad, top_yaw_rad, kViewPadM);
  v.z_m = std::clamp(top_z_m + range, from_z_m, std::max(from_z_m, max_z_m));
  const double at = v.z_m - top_z_m;
  v.slack_m =
      Vector2d(at * view.tan_long - 0.5 * size_m.x(), at * view.tan_short - 0.5 * size_m.y())
          .cwiseMax(0.0);
  return v;
}

Vector3d vantage_in_view(const ViewToFit& view, const Vector3d& mu_W, const Vector3d& drawn_W) {
  const Vector2d axis(std::cos(view.top_yaw_rad), std::sin(view.top_yaw_rad));
  const Vector2d across(-axis.y(), axis.x());
  const Vector2d d = (drawn_W - mu_W).head<2>();
  const Vector2d half = 0.5 * view.slack_m;
  const double a = std::clamp(axis.dot(d), -half.x(), half.x());
  const double b = std::clamp(across.dot(d), -half.y(), half.y());
  const Vector2d xy = mu_W.head<2>() + a * axis + b * across;
  return Vector3d(xy.x(), xy.y(), view.z_m);
}

double fit_radius_m(const LandingParams& L, double side_m) {
  const double r = 0.5 * (side_m - L.gear_footprint_m) - L.fit_margin_m;
  return r > 0 ? r : 0.0;  // NaN-safe: an unmeasured top leaves no room
}

Vector2d TopRoom::in_top(const Vector2d& e_W) const {
  return Vector2d(long_axis_W.dot(e_W), long_axis_W.x() * e_W.y() - long_axis_W.y() * e_W.x());
}

TopRoom top_room(const LandingParams& L, const Vector2d& size_m, const Vector2d& long_axis,
                 const Vector2d& edges) {
  TopRoom room;
  const double across = fit_radius_m(L, std::min(size_m.x(), size_m.y()));
  if (long_axis.allFinite() && long_axis.norm() >= kAxisAgreement) {
    const double yaw = std::atan2(long_axis.y(), long_axis.x()) / 2;
    room.long_axis_W = Vector2d(std::cos(yaw), std::sin(yaw));
    room.half_m << std::max(across, fit_radius_m(L, std::max(size_m.x(), size_m.y()))), across;
  } else if (edges.allFinite() && edges.norm() >= kAxisAgreement) {
    const double yaw = std::atan2(edges.y(), edges.x()) / 4;
    room.long_axis_W = Vector2d(std::cos(yaw), std::sin(yaw));
    room.half_m.setConstant(across);
  } else {
    room.half_m.setConstant(across / std::sqrt(2.0));
  }
  return room;
}

CalmBounds calm_bounds(const LandingParams& L, double held_s, const TopRoom& room) {
  const double quarter_s = 0.25 * L.final_hold_timeout_s;
  const double relaxed = std::clamp(held_s / (2 * quarter_s), 0.0, 1.0);
  const double reach_relaxed = std::clamp((held_s - quarter_s) / quarter_s, 0.0, 1.0);
  CalmBounds b;
  b.radial_m = std::min(L.radial_tol_m, L.final_hold_radial_m);
  b.speed_mps = L.final_hold_speed_mps +
                std::max(0.0, L.final_hold_speed_max_mps - L.final_hold_speed_mps) * relaxed;
  // Only where the top leaves room beyond the strict radius across it too.
  if (reach_relaxed > 0 && room.half_m.minCoeff() > b.radial_m)
    b.reach_m = Vector2d::Constant(b.radial_m) +
                (room.half_m - Vector2d::Constant(b.radial_m)) * reach_relaxed;
  return b;
}

bool calm_for_final_descent(const LandingParams& L, const Vector2d& e_W,
                            const std::optional<PoseSample>& pose, double held_s,
                            const TopRoom& room, int64_t now_utime,
                            std::optional<int64_t>& calm_since_utime) {
  const CalmBounds b = calm_bounds(L, held_s, room);
  bool calm = false;
  if (pose) {
    const Vector2d v_W = pose->v_W_B.head<2>();
    const double descent_s = L.final_height_m / L.final_descent_rate_mps;
    const bool strict = e_W.norm() <= b.radial_m && v_W.norm() <= b.speed_mps;
    const auto within = [&](const Vector2d& x_W) {
      return (room.in_top(x_W).cwiseAbs() - b.reach_m).maxCoeff() <= 0;
    };
    const bool heading_in = b.predicted() && within(e_W) && within(e_W + v_W * descent_s);
    calm = strict || heading_in;
  }
  if (!calm) {
    calm_since_utime.reset();
    return false;
  }
  if (!calm_since_utime) calm_since_utime = now_utime;
  return seconds(now_utime - *calm_since_utime) >= L.final_hold_settle_s;
}

bool carried_off(const LandingParams& L, const Vector2d& e_W, const CalmBounds& began,
                 const TopRoom& room) {
  if (!began.predicted()) return e_W.norm() > L.final_pause_radial_m;
  const Vector2d bound =
      Vector2d::Constant(L.final_pause_radial_m - began.radial_m) + began.reach_m;
  return (room.in_top(e_W).cwiseAbs() - bound).maxCoeff() > 0;
}

std::unique_ptr<const MissionProfile> MissionProfile::make(Mission mission,
                                                           const AutonomyParams& params) {
  switch (mission) {
    case Mission::kLanding:
      return std::make_unique<LandingProfile>(params);
    case Mission::kIngress:
      return std::make_unique<IngressProfile>(params);
    case Mission::kNone:
      break;
  }
  return nullptr;
}

}  // namespace alight::autonomy
