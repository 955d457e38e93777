#pragma once
// Landing on a moving platform (beyond the paper, whose 3.4.1 lands on a still one): the
// approach and the final descent flown on the platform filter's prediction
// (autonomy/platform_filter.hpp) instead of the refinement's fixed estimate.
//
//  0. Entry (moving_enough): a believed platform at least min_speed_mps fast whose centre has
//     gone kMovedM from where its track began; slower or not yet gone that far, the still
//     landing goes on. In the detection a believed track measured within kConfirmS that has not
//     yet shown its motion is looked at: followed at the search height for candidate_look_s
//     (the search paused), once per track, then the search goes on.
//  1. Match: over the platform's predicted centre at follow_height_m above its top, the
//     platform's velocity and its turn's acceleration fed forward and its long axis as the heading
//     (the nearest of the four ways a rectangle's axes align, as the still landing does), until the
//     vehicle's velocity relative to the platform is within match_speed_mps and its offset within
//     match_radial_m, the platform measured within kMatchedMeasuredS, for match_settle_s.
//  2. Descend at landing.descent_rate_mps while matched (the paper's e_r rule on the relative
//     state), holding the altitude whenever not, down to final_height_m over the top.
//  3. The deck's heave: the last drop (landing.final_descent_rate_mps) starts when its contact,
//     a fall time later, falls in the quarter period after a crest of the fitted heave (the deck
//     high and going down: the relative vertical speed at contact is the descent's minus the
//     deck's, the lowest of the high half); no heave above heave_min_amplitude_m: at once;
//     waited heave_max_wait_s: at once.
//  4. The failsafe: a believed platform (PlatformFilter::believed) predicted faster than
//     max_speed_mps or turning faster than max_yaw_rate_dps for too_fast_s, over which the
//     filter fused at least filter.min_consistent views (as many as make a track's motion
//     believed), is beyond what the vehicle follows (Failsafe::kPlatformTooFast: climb and hold).
//     The views ask that the speed be measured: one wrong view fused after a gap (the gate
//     widened by it) sets a speed the prediction then carries unmeasured.
//  5. The go-around (check_drop): in the last drop, while the gear is above the altitude loop's
//     lag over the top, its centre carried off the predicted centre beyond the room the top's
//     short side leaves the gear gives the drop up: back to step 1 at the final height. A cart
//     that turns in the drop carries the vehicle, which trails it, off the top's edge; finishing
//     the drop there tips it. The drop starts only within that room less the aim's margin
//     (aimed_for_drop). After kMaxDropGoArounds, or final_hold_timeout_s at the final height
//     without a drop, the platform is beyond what the vehicle lands on
//     (Failsafe::kPlatformTooFast).
//  6. The centre unplaced at the final height (its standard deviation beyond the room, or fewer
//     than kPlacedToDrop views in a row placing it for kUnplacedClimbS while settled): close
//     over the top it fills the view and its views, cut by the border, place nothing; matched,
//     the vehicle climbs back to follow_height_m, where the top is seen whole, turns the image's
//     long axis along the top's (once the whole views have told which it is) and descends again,
//     now only to the height from which the whole top fits the view (final_view_height_m, never
//     below final_height_m nor above follow_height_m), so that the views there place the centre
//     and the drop starts from it; final_hold_timeout_s runs on from its first arrival at the
//     final height.
//  7. The rangefinder's word (beam_under): flying on the onboard estimate, the surface its
//     rangefinder reads under the vehicle (state_estimate_t.terrain_height_m) must be the top
//     the vision's platform predicts there, not the take-off floor, before the last drop and
//     through it. The vision places the top with the camera's motion the estimate gives; an
//     estimate that drifted with the platform (the flow fused its motion) makes the still floor
//     seen through it move like a top, and the vehicle matched to it settles over the floor. The
//     rangefinder does not follow the estimate: settled over the predicted centre with the floor
//     under the beam for kFloorUnderTopS, the platform is not where the track says (target lost,
//     the track forgotten); in the drop, the gear is going down beside the top (the go-around).
// Pure: the time is passed in.

#include <optional>
#include <string>

#include "autonomy/platform_filter.hpp"
#include "common/param_schema.hpp"
#include "common/pose_buffer.hpp"

namespace alight::autonomy {

struct DownwardView;  // autonomy/params.hpp

struct MovingLandingParams {
  bool enabled = true;
  /// A platform this fast, seen to move (moving_enough), is landed on as a moving one [m/s]:
  /// the still landing averages a fixed point over its refinement's seconds, so a top creeping
  /// at a few centimetres a second (a cart slowed for its turn) leaves it, or is never detected
  /// (the second homography aligns a still scene).
  double min_speed_mps = 0.05;
  /// Matching the platform this high above its top [m]: the camera's view there is wide enough
  /// that a cart's turn stays in it while the vehicle follows.
  double follow_height_m = 1.0;
  /// The last drop starts this high above the top [m]: the top still seen whole (closer, it
  /// fills the view and its centre is no longer measured, only its motion).
  double final_height_m = 0.45;
  double match_speed_mps = 0.1;
  double match_radial_m = 0.05;
  double match_settle_s = 0.5;
  /// No platform measurement for this long: target lost [s]. The filter's prediction carries a
  /// cart through a gap this long (half a 0.6 m turn at 1 m/s), and the gaps of a follow last
  /// over a second: the approach's first swing onto the platform and each turn's blur.
  double lost_timeout_s = 2.0;
  /// What the vehicle follows [m/s]: not a key of its own but kFollowedSpeedShare of the
  /// vehicle's outer_loop.max_feedforward_xy_mps (load_params; followed_speed_mps); its default
  /// that of the outer loop's default, 2 m/s.
  double max_speed_mps = 1.6;
  double max_yaw_rate_dps = 20.0;
  double too_fast_s = 0.5;
  double heave_min_amplitude_m = 0.01;
  double heave_max_wait_s = 6.0;
  double fall_lag_s = 0.15;  ///< the altitude loop's lag added to the last drop's fall time [s]
  PlatformFilterParams filter;
  static const ParamSchema<MovingLandingParams>& schema();
  void validate() const;
};

/// Matched (step 1) only on a measurement this recent [s]: the prediction carries the follow
/// through a gap (lost_timeout_s), but a cart that starts or ends a turn in the gap is off its
/// predicted path by half its turn's acceleration times the gap squared, the match radius' 5 cm
/// after a quarter second at 1.6 m/s^2; descending, or starting the last drop, on a prediction
/// older than that puts the gear down beside the platform.
inline constexpr double kMatchedMeasuredS = 0.25;

/// The share of the velocity the vehicle's outer loop follows (its max_feedforward_xy_mps) a
/// platform may move at and still be followed: a fifth kept in hand, so that the prediction's
/// velocity, which runs ahead of the platform's through a turn, is not cut off at the bound.
inline constexpr double kFollowedSpeedShare = 0.8;

/// The fastest platform a vehicle whose outer loop follows a setpoint's velocity up to
/// `max_feedforward_xy_mps` follows (MovingLandingParams::max_speed_mps) [m/s].
inline double followed_speed_mps(double max_feedforward_xy_mps) {
  return kFollowedSpeedShare * max_feedforward_xy_mps;
}

/// A believed track whose centre has gone this far from where it began moves [m]: over three
/// times what a still top's measured centre wanders (its height's 5 cm uncertainty times the
/// view angle's tangent, 1-3 cm, as the vehicle moves over it), and under what a top creeping at
/// min_speed_mps covers in the two seconds a track is young. A slow top's velocity alone is lost
/// in the filter's 5-10 cm/s of noise.
inline constexpr double kMovedM = 0.10;

/// The believed platform `p` moves: its speed at least min_speed_mps and its centre kMovedM from
/// where its track began.
bool moving_enough(const PlatformFilter::Prediction& p, const MovingLandingParams& params);

/// How long the detection looks at a believed track not yet moving_enough [s] (step 0): twice
/// the time a top creeping at min_speed_mps takes to go kMovedM. The search sweeps on at its
/// speed, and a slow top believed in the view leaves it within a second or two, before it has
/// gone kMovedM; followed, it shows whether it moves.
double candidate_look_s(const MovingLandingParams& params);

/// A touch-down with the gear this far below the top's height, beyond the deck's heave, is
/// beside the platform, on the floor, not on its top [m]. The top's height is the one vision
/// assumes for a moving top (vision.moving_top.top_height_m, 0.15 m; the heave measured about
/// it), off by up to 7 cm for the 8-22 cm tops it is meant for, and a deck's roll at its edge
/// adds 1-2 cm; the floor lies the assumed height, 15 cm, below.
inline constexpr double kBesideTopM = 0.12;

/// What the rangefinder reads under the vehicle against the predicted top (step 7).
enum class Beam { kUnknown, kTop, kFloor };
/// A top lower than this is not told from the floor by the rangefinder [m]: the estimator's step
/// gate (5 cm) with its readings' noise, the lowest of the tops vision's moving tops are set among
/// (8 cm).
inline constexpr double kLowestToldTopM = 0.08;
/// The floor under a settled vehicle this long says the platform is elsewhere [s]: coming over
/// the top, the estimator's terrain steps onto it within its reset window (0.15 s of readings
/// refused by its step gate); a beam crossing the top's edge reads the floor for moments.
inline constexpr double kFloorUnderTopS = 0.5;
/// Step 7: the rangefinder's surface under the vehicle, terrain_m (W; nullopt: no rangefinder
/// fused, nothing said), against a top whose lowest point (its heave's trough) is top_low_m (W):
/// the floor where it lies nearer the take-off floor (z = 0) than that, the top otherwise; nothing
/// said of a top lower than kLowestToldTopM. The half-way mark, not a band about z = 0: the
/// estimate's height error (centimetres after seconds over a top, where only the barometer holds
/// it) shifts the terrain it reads over the floor, and the top vision places (its height measured
/// from the estimate's camera heights) shifts with it.
Beam beam_under(std::optional<double> terrain_m, double top_low_m);

/// Whether a touch-down with the gear gear_below_top_m under the platform's top's height (the
/// top heaving by heave_amplitude_m) came down on the top and not beside it (kBesideTopM).
bool touched_down_on_top(double gear_below_top_m, double heave_amplitude_m);

/// Whether the last drop starts now (step 3 of moving_landing.hpp).
enum class Release { kWait, kNoHeave, kAfterCrest, kWaitedEnough };
Release heave_release(const HeaveModel& heave, int64_t now_utime, double fall_s, double waited_s,
                      const MovingLandingParams& params);
const char* to_string(Release r);

/// The last drop given up this many times, the platform is beyond what the vehicle lands on
/// (Failsafe::kPlatformTooFast), as a precision landing's retries are bounded (ArduPilot's
/// PLND_RET_MAX): each go-around costs the match and the settle again, a few seconds, and a
/// platform that carries the vehicle off three drops in a row does so in its steady motion, not
/// by one unlucky turn.
inline constexpr int kMaxDropGoArounds = 3;

/// The room the top leaves the gear's centre on each of its axes with the whole gear still on
/// it [m]: half of the short side (the filter's whole top) less half the gear's footprint. The
/// filter's axes are a direction mod 90 deg (which one is long is not known in the drop), so the
/// room is a square of the short side's; nothing is kept in hand for aiming (fit_margin_m), this
/// is where the vehicle starts to tip, not where it aims. NaN for a top not measured yet.
double drop_room_m(const Vector2d& whole_top_m, double gear_footprint_m);

/// The still landing's figures the moving one shares (autonomy.landing).
struct LandingGear {
  double gear_height_m = 0.1;           ///< the gear below the body's origin [m]
  double gear_footprint_m = 0.15;       ///< the square gear's side [m]
  double fit_margin_m = 0.02;           ///< the top kept around the gear by the aim [m]
  double descent_rate_mps = 0.25;       ///< to the final height [m/s]
  double final_descent_rate_mps = 1.0;  ///< the last drop [m/s]
  /// At the final height without a drop, or above it never matched, this long [s].
  double final_hold_timeout_s = 10.0;
};

/// Step 5 of moving_landing.hpp.
enum class Drop { kGoOn, kCommitted, kOffTheTop };
struct DropCheck {
  Drop verdict = Drop::kGoOn;
  Vector2d off_m = Vector2d::Zero();  ///< the gear's centre from the predicted centre, top's axes
  double room_m = 0.0;                ///< drop_room_m
  double gear_above_m = 0.0;          ///< the gear over the top (its heave included) [m]
  double centre_sd_m = 0.0;    ///< the predicted centre's standard deviation, its worst axis [m]
  int placed_views = 0;        ///< PlatformFilter::n_placed
  Beam beam = Beam::kUnknown;  ///< beam_under at the predicted top's trough
};
/// Views in a row that must have placed the top's centre before the last drop starts on it. One
/// view's centre can be 10-20 cm off (the view's footprint or the cart's side read as the whole
/// top) while its variance says 1-2 cm; a second and third placed within the filter's gate of it
/// confirm it, one outside the gate puts it in doubt.
inline constexpr int kPlacedToDrop = 3;
/// Standard deviations of the predicted centre that must fit in the room before the last drop.
/// The drop itself drifts a centimetre or two downwind, so a centre known to one sigma of the
/// room leaves a third of drops beyond it; two sigma leaves one in twenty.
inline constexpr double kCentreSigmas = 2.0;
/// The predicted centre known within the room (kCentreSigmas of its standard deviation) and
/// placed by kPlacedToDrop views in a row: what the last drop needs of the centre besides the aim.
bool centre_placed(const DropCheck& c);
/// Settled over a centre not placed this long at the final height, the views there place
/// nothing (step 6: cut by the border, close over a top that fills the view) and the vehicle
/// climbs to see it whole [s]. Where the top is seen whole, kPlacedToDrop views in a row come in
/// a few tenths of a second (a view every frame or two); a centre whose standard deviation
/// outgrows the room climbs at once.
inline constexpr double kUnplacedClimbS = 1.0;

/// Whether the last drop goes on. Committed while the gear is within final_descent_rate_mps x
/// fall_lag_s of the top (the altitude loop's lag: a climb ordered there still touches down);
/// otherwise off the top when the gear's centre (gear_height_m below the body along its z axis:
/// a banked body's gear hangs outwards) lies beyond drop_room_m on either of the top's axes.
/// A top not measured (no whole top yet) goes on: nothing says where its edge is. Off the top too
/// where the rangefinder reads the floor under the gear (step 7; terrain_m: the estimate's
/// terrain, nullopt without a rangefinder).
DropCheck check_drop(const PlatformFilter& filter, const PoseSample& pose, int64_t now_utime,
                     const LandingGear& gear, const MovingLandingParams& params,
                     std::optional<double> terrain_m = std::nullopt);

/// The last drop starts only with the gear's centre within the room less fit_margin_m on both of
/// the top's axes (check_drop's): the aim the still landing keeps, and the go-around's own
/// margin, so that a drop is not given up where it begins; and on a placed centre
/// (centre_placed): a top seen only cut by the border for seconds has a centre the filter has
/// not placed, and a drop matched to it lands wherever it drifted.
bool aimed_for_drop(const DropCheck& c, const LandingGear& gear);

/// Step 6: the gear's height over a top of `whole_top_m` (long, short) from which the whole top
/// lies in the camera's usable view with the image's long axis along the top's (or, the long axis
/// unknown, either way), the body within match_radial_m of the top's centre and the camera
/// view.offset_m off the body's: between final_height_m and follow_height_m [m]. The camera is
/// taken at the gear's height (it sits a few centimetres above it: a margin).
double final_view_height_m(const DownwardView& view, const Vector2d& whole_top_m, bool long_known,
                           const MovingLandingParams& params);

/// The body's heading that lays the image's long axis along the top's long axis at
/// `long_yaw_rad` (the nearer of the two to `current_rad`) [rad].
double long_axis_yaw(const DownwardView& view, double long_yaw_rad, double current_rad);

/// The moving approach's own state.
struct MovingApproach {
  double z_sp_m = 0.0;
  std::optional<int64_t> matched_since_utime;
  /// Time spent above the final height not settled on the platform (no descent) [s].
  double unsettled_s = 0.0;
  std::optional<int64_t> at_final_since_utime;  ///< waiting for the heave since
  std::optional<int64_t> too_fast_since_utime;
  int too_fast_since_updates = 0;  ///< the filter's fused views when it began
  int placing_climbs = 0;          ///< climbs to the follow height to place the centre (step 6)
  /// Settled at the final height over a centre not placed (centre_placed) since.
  std::optional<int64_t> unplaced_since_utime;
  /// After a climb (step 6): the gear's height over the top for the last drop
  /// (final_view_height_m; before it, final_height_m) [m].
  std::optional<double> final_view_height_m;
  /// Settled with the rangefinder reading the floor under the vehicle since (step 7).
  std::optional<int64_t> floor_under_since_utime;
};

struct MovingStep {
  /// kFloorUnderTop: step 7, the track's platform is not under the vehicle (target lost, and the
  /// track is not the platform's).
  enum class Next { kContinue, kFinalDescent, kTargetLost, kTooFast, kFloorUnderTop };
  Next next = Next::kContinue;
  Vector3d sp_p_W = Vector3d::Zero(), sp_v_W = Vector3d::Zero(), sp_a_W = Vector3d::Zero();
  double yaw_sp_rad = 0.0;
  double yaw_rate_radps = 0.0;  ///< the platform's turn, fed forward
  std::string reason;
};

/// The platform's turn as the heading's feed-forward: never beyond max_yaw_rate_dps, a turn the
/// vehicle follows (a faster one is PLATFORM_TOO_FAST once it lasts too_fast_s) [rad/s].
double followed_turn_radps(double yaw_rate_rps, const MovingLandingParams& params);

/// The heading that puts the body's axes along the platform's (yaw mod 90 deg) nearest to
/// `current` [rad].
double aligned_yaw(double platform_yaw_rad, double current_rad);

/// One step of steps 1-4. At the final height without a drop for final_hold_timeout_s (the gear
/// never aimed, or no crest): the platform is beyond what the vehicle lands on (kTooFast). Above
/// it, not matched well enough to descend for final_hold_timeout_s in all (a platform whose turns
/// the vehicle trails, within the speed it follows; a moment matched now and then does not start
/// the wait over): the same.
/// `view`: the downward camera's (nullptr: none declared; step 6 then climbs and comes back to
/// final_height_m). `terrain_m`: the surface under the estimate's rangefinder (step 7; nullopt:
/// none fused).
MovingStep step_moving_approach(MovingApproach& s, const PlatformFilter& filter,
                                const PoseSample& pose, int64_t now_utime, double dt_s,
                                double yaw_sp_rad, const LandingGear& gear,
                                const MovingLandingParams& params,
                                const DownwardView* view = nullptr,
                                std::optional<double> terrain_m = std::nullopt);

/// The platform's motion beyond what the vehicle follows (step 4), or nullopt.
std::optional<std::string> too_fast(const PlatformFilter::Prediction& p,
                                    const MovingLandingParams& params);

}  // namespace alight::autonomy
