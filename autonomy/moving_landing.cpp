// Landing on a moving platform (beyond paper 3.4.1; see moving_landing.hpp).
#include "autonomy/moving_landing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "autonomy/mission_profile.hpp"
#include "autonomy/params.hpp"
#include "autonomy/text.hpp"

namespace alight::autonomy {

const ParamSchema<MovingLandingParams>& MovingLandingParams::schema() {
  using P = MovingLandingParams;
  static const ParamSchema<P> schema = [] {
    ParamSchema<P> s;
    s.add("enabled", &P::enabled, Range::any(), "",
          "land on a platform that vision measures moving (VISION_PLATFORM)");
    s.add("min_speed_mps", &P::min_speed_mps, Range::gt(0), "m/s",
          "a platform this fast, its centre gone kMovedM from where its track began, is landed "
          "on as a moving one");
    s.add("follow_height_m", &P::follow_height_m, Range::gt(0), "m",
          "matching the platform's velocity this high above its top");
    s.add("final_height_m", &P::final_height_m, Range::gt(0), "m",
          "the last drop starts this high above the top (the top still seen whole)");
    s.add("match_speed_mps", &P::match_speed_mps, Range::gt(0), "m/s",
          "matched: the velocity relative to the platform within this");
    s.add("match_radial_m", &P::match_radial_m, Range::gt(0), "m",
          "matched: the offset from the platform's centre within this");
    s.add("match_settle_s", &P::match_settle_s, Range::ge(0), "s",
          "matched this long before the descent starts");
    s.add("lost_timeout_s", &P::lost_timeout_s, Range::gt(0), "s",
          "no platform measurement for this long: target lost");
    s.add("max_yaw_rate_dps", &P::max_yaw_rate_dps, Range::gt(0), "deg/s",
          "a platform predicted turning faster is beyond what the vehicle follows");
    s.add("too_fast_s", &P::too_fast_s, Range::ge(0), "s",
          "beyond those bounds this long, over filter.min_consistent fused views: the failsafe");
    s.add("heave_min_amplitude_m", &P::heave_min_amplitude_m, Range::ge(0), "m",
          "a fitted heave smaller than this is no heave: the last drop at once");
    s.add("heave_max_wait_s", &P::heave_max_wait_s, Range::ge(0), "s",
          "waited this long for a crest: the last drop at once");
    s.add("fall_lag_s", &P::fall_lag_s, Range::ge(0), "s",
          "the altitude loop's lag added to the last drop's fall time");
    s.section("filter", &P::filter, PlatformFilterParams::schema(),
              "the platform's constant-velocity filter and heave fit");
    return s;
  }();
  return schema;
}

void MovingLandingParams::validate() const { schema().validate(*this); }

const char* to_string(Release r) {
  switch (r) {
    case Release::kWait:
      return "waiting for a crest";
    case Release::kNoHeave:
      return "no heave";
    case Release::kAfterCrest:
      return "contact just after a crest";
    case Release::kWaitedEnough:
      return "waited long enough for a crest";
  }
  return "?";
}

Release heave_release(const HeaveModel& heave, int64_t now_utime, double fall_s, double waited_s,
                      const MovingLandingParams& params) {
  if (!(heave.w_rps > 0) || heave.amplitude_m() < params.heave_min_amplitude_m)
    return Release::kNoHeave;
  const int64_t contact = now_utime + static_cast<int64_t>(fall_s * 1e6);
  // The quarter period after a crest: high (above the mean) and going down.
  if (heave.z(contact) >= 0 && heave.vz(contact) - heave.c <= 0) return Release::kAfterCrest;
  if (waited_s >= params.heave_max_wait_s) return Release::kWaitedEnough;
  return Release::kWait;
}

double followed_turn_radps(double yaw_rate_rps, const MovingLandingParams& params) {
  const double max_rps = params.max_yaw_rate_dps * M_PI / 180;
  return std::clamp(yaw_rate_rps, -max_rps, max_rps);
}

double aligned_yaw(double platform_yaw_rad, double current_rad) {
  const double q = M_PI / 2;
  const double k = std::round((current_rad - platform_yaw_rad) / q);
  return platform_yaw_rad + k * q;
}

double final_view_height_m(const DownwardView& view, const Vector2d& whole_top_m, bool long_known,
                           const MovingLandingParams& params) {
  if (!(whole_top_m.minCoeff() > 0)) return params.final_height_m;
  const double pad_m = view.offset_m + params.match_radial_m;
  double range_m = range_to_fit(view, whole_top_m, 0.0, 0.0, pad_m);
  if (!long_known)
    range_m = std::max(range_m, range_to_fit(view, whole_top_m, M_PI / 2, 0.0, pad_m));
  return std::clamp(range_m, params.final_height_m, params.follow_height_m);
}

double long_axis_yaw(const DownwardView& view, double long_yaw_rad, double current_rad) {
  const double base = long_yaw_rad - view.long_axis_yaw_B_rad;
  return base + M_PI * std::round((current_rad - base) / M_PI);
}

bool moving_enough(const PlatformFilter::Prediction& p, const MovingLandingParams& params) {
  return p.v_W.norm() >= params.min_speed_mps && p.travelled_m >= kMovedM;
}

double candidate_look_s(const MovingLandingParams& params) {
  return 2 * kMovedM / params.min_speed_mps;
}

std::optional<std::string> too_fast(const PlatformFilter::Prediction& p,
                                    const MovingLandingParams& params) {
  const double speed = p.v_W.norm();
  const double rate_dps = std::abs(p.yaw_rate_rps) * 180 / M_PI;
  if (speed > params.max_speed_mps)
    return "platform at " + fmt(speed, 2) + " m/s, beyond " + fmt(params.max_speed_mps, 2) +
           ": beyond what the vehicle follows";
  if (rate_dps > params.max_yaw_rate_dps)
    return "platform turning at " + fmt(rate_dps, 2) + " deg/s, beyond " +
           fmt(params.max_yaw_rate_dps, 2) + ": beyond what the vehicle follows";
  return std::nullopt;
}

// The predicted top's lowest point, its heave's trough: what step 7 judges the beam against.
static double top_trough_m(const PlatformFilter& filter, const PlatformFilter::Prediction& pr) {
  return pr.top_z_m - filter.heave().amplitude_m();
}

Beam beam_under(std::optional<double> terrain_m, double top_low_m) {
  if (!terrain_m || !std::isfinite(*terrain_m) || !(top_low_m >= kLowestToldTopM))
    return Beam::kUnknown;
  return *terrain_m < 0.5 * top_low_m ? Beam::kFloor : Beam::kTop;
}

bool touched_down_on_top(double gear_below_top_m, double heave_amplitude_m) {
  return gear_below_top_m <= heave_amplitude_m + kBesideTopM;
}

double drop_room_m(const Vector2d& whole_top_m, double gear_footprint_m) {
  if (!(whole_top_m.minCoeff() > 0)) return std::numeric_limits<double>::quiet_NaN();
  return std::max(0.0, 0.5 * (whole_top_m.minCoeff() - gear_footprint_m));
}

DropCheck check_drop(const PlatformFilter& filter, const PoseSample& pose, int64_t now_utime,
                     const LandingGear& gear, const MovingLandingParams& params,
                     std::optional<double> terrain_m) {
  DropCheck c;
  const auto pr = filter.predict(now_utime);
  const Vector3d gear_W = pose.p_W_B - gear.gear_height_m * (pose.q_WB * Vector3d::UnitZ());
  c.gear_above_m = gear_W.z() - (pr.top_z_m + filter.heave().z(now_utime));
  const Vector2d e_W = gear_W.head<2>() - pr.p_W;
  c.off_m = Eigen::Rotation2Dd(-pr.yaw_rad) * e_W;
  c.room_m = drop_room_m(filter.whole_top(), gear.gear_footprint_m);
  c.centre_sd_m = std::sqrt(worst_axis_var(pr.cov_p));
  c.placed_views = filter.n_placed();
  c.beam = beam_under(terrain_m, top_trough_m(filter, pr));
  if (c.gear_above_m <= gear.final_descent_rate_mps * params.fall_lag_s) {
    c.verdict = Drop::kCommitted;
  } else if ((std::isfinite(c.room_m) && c.off_m.cwiseAbs().maxCoeff() > c.room_m) ||
             c.beam == Beam::kFloor) {
    c.verdict = Drop::kOffTheTop;
  }
  return c;
}

bool centre_placed(const DropCheck& c) {
  return kCentreSigmas * c.centre_sd_m <= c.room_m && c.placed_views >= kPlacedToDrop;
}

bool aimed_for_drop(const DropCheck& c, const LandingGear& gear) {
  if (c.beam == Beam::kFloor) return false;
  return !std::isfinite(c.room_m) ||
         (c.off_m.cwiseAbs().maxCoeff() <= c.room_m - gear.fit_margin_m && centre_placed(c));
}

MovingStep step_moving_approach(MovingApproach& s, const PlatformFilter& filter,
                                const PoseSample& pose, int64_t now_utime, double dt_s,
                                double yaw_sp_rad, const LandingGear& gear,
                                const MovingLandingParams& params, const DownwardView* view,
                                std::optional<double> terrain_m) {
  MovingStep out;
  out.yaw_sp_rad = yaw_sp_rad;
  const double since_s = double(now_utime - filter.utime()) * 1e-6;
  if (!filter.initialised() || since_s > params.lost_timeout_s) {
    out.next = MovingStep::Next::kTargetLost;
    out.reason = "moving platform not measured for " + fmt(since_s, 2) + " s";
    return out;
  }
  const auto pr = filter.predict(now_utime);
  // A track not believed yet (started over on measurements its predecessor refused) is followed,
  // but neither judged too fast nor descended onto.
  const bool believed = filter.believed();
  if (const auto why = believed ? too_fast(pr, params) : std::nullopt) {
    if (!s.too_fast_since_utime) {
      s.too_fast_since_utime = now_utime;
      s.too_fast_since_updates = filter.n_updates();
    }
    const bool measured_fast =
        filter.n_updates() - s.too_fast_since_updates >= params.filter.min_consistent;
    if (double(now_utime - *s.too_fast_since_utime) * 1e-6 >= params.too_fast_s && measured_fast) {
      out.next = MovingStep::Next::kTooFast;
      out.reason = *why;
      return out;
    }
  } else {
    s.too_fast_since_utime.reset();
  }
  const double z_top = pr.top_z_m;
  const double z_follow = z_top + gear.gear_height_m + params.follow_height_m;
  const double final_m = s.final_view_height_m.value_or(params.final_height_m);
  const double z_final = z_top + gear.gear_height_m + final_m;
  if (s.z_sp_m <= 0) s.z_sp_m = std::max(z_final, std::min(pose.p_W_B.z(), z_follow));
  // After a climb to place the centre, the image's long axis along the top's: the top's length
  // then fits the view from the lowest height.
  out.yaw_sp_rad = s.final_view_height_m && view && pr.long_axis_known
                       ? long_axis_yaw(*view, pr.long_yaw_rad, yaw_sp_rad)
                       : aligned_yaw(pr.yaw_rad, yaw_sp_rad);
  out.yaw_rate_radps = followed_turn_radps(pr.yaw_rate_rps, params);
  const Vector2d offset = pose.p_W_B.head<2>() - pr.p_W;
  const Vector2d rel_v = pose.v_W_B.head<2>() - pr.v_W;
  const bool measured = since_s <= kMatchedMeasuredS;
  const bool matched = believed && measured && offset.norm() <= params.match_radial_m &&
                       rel_v.norm() <= params.match_speed_mps;
  if (!matched) {
    s.matched_since_utime.reset();
  } else if (!s.matched_since_utime) {
    s.matched_since_utime = now_utime;
  }
  const bool settled = s.matched_since_utime &&
                       double(now_utime - *s.matched_since_utime) * 1e-6 >= params.match_settle_s;
  // Step 7: settled over the predicted centre, the beam is on the top if the track is the
  // platform's.
  const double top_low_m = top_trough_m(filter, pr);
  if (settled && beam_under(terrain_m, top_low_m) == Beam::kFloor) {
    if (!s.floor_under_since_utime) s.floor_under_since_utime = now_utime;
    if (double(now_utime - *s.floor_under_since_utime) * 1e-6 >= kFloorUnderTopS) {
      out.next = MovingStep::Next::kFloorUnderTop;
      out.reason = "the rangefinder reads the floor (" + fmt(*terrain_m, 3) +
                   " m) under the moving platform's predicted top (" + fmt(top_low_m, 3) +
                   " m at its lowest) for " + fmt(kFloorUnderTopS, 2) +
                   " s: the platform is not where its track says";
      return out;
    }
  } else {
    s.floor_under_since_utime.reset();
  }
  out.sp_v_W << pr.v_W, 0.0;
  out.sp_a_W << pr.a_W, 0.0;
  if (settled && s.z_sp_m > z_final) {
    s.z_sp_m = std::max(z_final, s.z_sp_m - gear.descent_rate_mps * dt_s);
    out.sp_v_W.z() = -gear.descent_rate_mps;
  }
  out.sp_p_W << pr.p_W, s.z_sp_m;
  if (s.z_sp_m > z_final) {
    // Following without matching well enough to descend: the vehicle trails the platform's turns
    // (within the speed it follows, so not too_fast), and following on for ever is no landing.
    // The wait is the final height's for a moment to drop, counted over the whole approach (a
    // moment matched now and then descends a step, but does not start it over).
    if (!settled) s.unsettled_s += dt_s;
    if (s.unsettled_s >= gear.final_hold_timeout_s) {
      out.next = MovingStep::Next::kTooFast;
      out.reason = "not matched with the moving platform for " + fmt(s.unsettled_s, 2) + " s (" +
                   fmt(offset.norm(), 2) + " m, " + fmt(rel_v.norm(), 2) +
                   " m/s off now): beyond what the vehicle lands on";
      return out;
    }
    out.reason = settled ? "descending with the moving platform"
                         : "matching the moving platform (" + fmt(offset.norm(), 2) + " m, " +
                               fmt(rel_v.norm(), 2) + " m/s off" +
                               (measured ? "" : ", unmeasured for " + fmt(since_s, 2) + " s") + ")";
    return out;
  }
  // At the final height: the last drop when matched and the heave allows it.
  if (!s.at_final_since_utime) s.at_final_since_utime = now_utime;
  const double waited_s = double(now_utime - *s.at_final_since_utime) * 1e-6;
  const double fall_s = final_m / gear.final_descent_rate_mps + params.fall_lag_s;
  const Release r = heave_release(filter.heave(), now_utime, fall_s, waited_s, params);
  const DropCheck c = check_drop(filter, pose, now_utime, gear, params, terrain_m);
  const bool aimed = aimed_for_drop(c, gear);
  if (settled && aimed && r != Release::kWait) {
    out.next = MovingStep::Next::kFinalDescent;
    out.reason = std::string("moving platform matched, final descent (") + to_string(r) + ")";
    return out;
  }
  const std::string off = "the gear " + fmt(c.off_m.cwiseAbs().maxCoeff(), 3) +
                          " m off its centre, known to " + fmt(c.centre_sd_m, 3) +
                          " m, placed by " + std::to_string(c.placed_views) + " views in a row";
  // A centre the views at this height do not place: its standard deviation past the room, or
  // settled without kPlacedToDrop views in a row for kUnplacedClimbS (views that keep the
  // deviation small but are all cut).
  if (settled && std::isfinite(c.room_m) && !centre_placed(c)) {
    if (!s.unplaced_since_utime) s.unplaced_since_utime = now_utime;
  } else {
    s.unplaced_since_utime.reset();
  }
  const bool unplaced = c.centre_sd_m > c.room_m ||
                        (s.unplaced_since_utime &&
                         double(now_utime - *s.unplaced_since_utime) * 1e-6 >= kUnplacedClimbS);
  if (waited_s < gear.final_hold_timeout_s && settled && unplaced && c.room_m > gear.fit_margin_m) {
    // Close over the top it fills the view, and its views, cut by the border, place nothing:
    // from the follow height it is seen whole. Climb there and descend again (the wait for a
    // moment to drop runs on from the first arrival here). A top with no room for the aim is
    // never dropped onto, placed or not: no climb.
    s.z_sp_m = z_follow;
    s.unplaced_since_utime.reset();
    ++s.placing_climbs;
    if (view)
      s.final_view_height_m =
          final_view_height_m(*view, filter.whole_top(), pr.long_axis_known, params);
    out.sp_p_W.z() = s.z_sp_m;
    out.reason = "over the moving platform: its centre not placed (" + off + ", its room " +
                 fmt(c.room_m, 3) + " m): climbing to see the top whole (" +
                 std::to_string(s.placing_climbs) + ")";
    return out;
  }
  if (waited_s >= gear.final_hold_timeout_s) {
    out.next = MovingStep::Next::kTooFast;
    out.reason = "no moment to drop onto the moving platform in " + fmt(waited_s, 2) + " s (" +
                 off + ", its room " + fmt(c.room_m, 3) + " m" +
                 (c.beam == Beam::kFloor ? ", the rangefinder reading the floor under it (" +
                                               fmt(*terrain_m, 3) + " m)"
                                         : std::string()) +
                 "): beyond what the vehicle lands on";
    return out;
  }
  out.reason = !settled ? std::string("over the moving platform: matching")
               : c.beam == Beam::kFloor
                   ? "over the moving platform: the rangefinder reads the floor under it (" +
                         fmt(*terrain_m, 3) + " m)"
               : !aimed ? "over the moving platform: " + off + "; it drops within " +
                              fmt(c.room_m - gear.fit_margin_m, 3) +
                              " m on a centre known within " + fmt(c.room_m, 3) + " m, placed by " +
                              std::to_string(kPlacedToDrop) + " views in a row"
                        : std::string("over the moving platform: ") + to_string(r);
  return out;
}

}  // namespace alight::autonomy
