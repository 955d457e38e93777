#pragma once
// What differs between the two missions, in one place: landing on a platform (paper 3.4.1) and
// ingress through an opening (3.4.2, 4.3; the paper did not fly it). The autonomy chooses a
// profile once, at GO (or LAND_HERE, which lands), and asks it wherever the two differ instead
// of testing the mission: the search path of detection, where refinement's vantage points lie,
// whether the target fits the vehicle, how the approach flies and where it ends, and how high
// to hold when the target is lost for good. Pure: the autonomy passes in what it knows.
//
//  - Landing: a lawnmower over the landing area at the search height; vantages at that height
//    around the estimate's x, y; the platform's short side must take the gear footprint plus
//    margins; above the estimate at the current altitude, descend at v_des (x3(t+1) = x3(t) -
//    v_des dt) only while the radial error e_r(t) is within radial_tol (and the yaw turned onto
//    the platform's edges), final_height above the platform -> FINAL_DESCENT.
//  - Ingress: a pass along the wall; vantages in the plane parallel to the wall at a standoff
//    (no nearer than the vehicle already is while one frame's sighting is all there is);
//    the opening must take the vehicle plus clearance; align on the opening's normal at a
//    standoff, then advance along it only while the lateral and vertical errors are within
//    tolerance, pass_distance beyond the wall -> DONE.

#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "autonomy/params.hpp"
#include "autonomy/refinement.hpp"
#include "autonomy/types.hpp"

namespace alight::autonomy {

/// A carrot (the search path's, the ingress pass's) waits when the vehicle is this far behind.
inline constexpr double kPathLeadM = 0.3;
/// APPROACH refuses a found target further than this from the final estimate, whatever its
/// spread: half of the smallest platform the families draw, so a target beside the platform is
/// never taken for it [m].
inline constexpr double kVisionGateFloorM = 0.1;
/// Every found target refused this long is a sustained disagreement: longer than a stray plane
/// fit lasts (it changes with the vantage every few frames) [s].
inline constexpr double kVisionDisagreeS = 2.0;
/// ... and at least this many of them: a forged stream or a vision locked onto something else
/// refuses one a frame, while where vision finds the target only now and then (ingress' wait
/// before the wall, a second or more between found targets) two strays seconds apart with
/// nothing between them are no sustained disagreement.
inline constexpr int kVisionDisagreeMinTargets = 5;

/// Refinement's look at a top its views cut (paper 3.4.1 flies the vantages at the search
/// height, which takes the platform to fit the view from there): the height and heading from
/// which the top fits the downward camera's view, and how far a vantage may stray from the top's
/// centre with it whole in view.
struct ViewToFit {
  double z_m = 0.0;          ///< the vantages' height, world z [m]
  double yaw_rad = 0.0;      ///< body yaw laying the image's long axis along the top's [rad]
  double top_yaw_rad = 0.0;  ///< the top's long axis [rad]
  Vector2d slack_m = Vector2d::Zero();  ///< room around the top along its long, short axis [m]
};

/// A top whole in the view stays this far inside the view's usable part on each side: the
/// vantages' own scatter (vantage_sigma_floor_m's 8 cm) and part of the way to the vision's
/// reference image, which may lie up to 0.3 m off (vision.landing.max_reference_baseline_m); a
/// pad that covered all of it would put a large top's vantage above a room's geofence [m].
inline constexpr double kViewPadM = 0.15;
/// A cut view moves the vantages again only when it asks for this much more height [m] or this
/// much more turn [rad]: less is inside kViewPadM, and every move costs a vantage's flight.
inline constexpr double kViewStepM = 0.1;
inline constexpr double kViewTurnRad = 10.0 * M_PI / 180.0;
/// The vantages fit the cut view whose long side is the (lower) median of the latest this many:
/// one frame's extent is one walk to the rims, and a seam or a shadow's edge taken for a rim
/// measures a top up to twice its size; fitting that sends the vantages up, where the top's
/// parallax against the floor, which the vision tells it by, shrinks with the height squared.
/// The median follows a top whose cut views grow as more of it comes into view two views late.
inline constexpr size_t kCutViewsToFit = 5;

/// The range (camera to top) from which a top of size (long, short), its long axis at
/// top_yaw, lies pad_m inside the usable view of a camera whose image's long axis lies at
/// view_yaw (world) [m].
double range_to_fit(const DownwardView& view, const Vector2d& size_m, double top_yaw_rad,
                    double view_yaw_rad, double pad_m);

/// From a cut view of the top (the extent in view, a lower bound of the top's; its long axis;
/// its surface's height) and the body's yaw: nothing when that extent fits the view from
/// from_z_m as the body is turned; else the body turned to lay the top's long axis along the
/// image's (the nearer of the two turns) at the height it fits from, within [from_z_m, max_z_m].
std::optional<ViewToFit> view_to_fit(const DownwardView& view, const Vector2d& size_m,
                                     double top_yaw_rad, double top_z_m, double body_yaw_rad,
                                     double from_z_m, double max_z_m);

/// A vantage drawn around mu_W at the view's height, its offset from mu_W clipped to half the
/// view's slack along each of the top's axes (the other half is the reference image's).
Vector3d vantage_in_view(const ViewToFit& view, const Vector3d& mu_W, const Vector3d& drawn_W);

/// A failsafe that holds before its controlled descent holds this long: time for the operator to
/// take over, as PX4's COM_FAIL_ACT_T [s].
inline constexpr double kFailsafeHoldS = 5.0;

/// The landing approach's own state.
struct LandingApproach {
  double z_sp_m = 0.0;     ///< x3(t), the altitude setpoint [m]
  bool land_here = false;  ///< operator LAND_HERE: onto the floor below, no target to lose
  std::optional<int64_t> held_since_utime;  ///< at final_height_m, waiting for calm
  std::optional<int64_t> calm_since_utime;  ///< ... calm (speed and e_r within) since
  /// The time since the target was last seen that the vehicle spent not descending onto the
  /// estimate (the lost-target check's count) [s].
  double unseen_s = 0.0;

  /// The altitude setpoint is down to final_height_m above the platform top at top_z_m (the
  /// final hold, then the rapid descent).
  bool at_final_height(double top_z_m, double gear_height_m, double final_height_m) const {
    return z_sp_m - (top_z_m + gear_height_m) <= final_height_m + 1e-6;
  }
};

/// The landing approach's descent volume (paper 3.4.1: descend only while e_r(t) is within
/// radial_tol_m), beyond the paper a cone: radial_tol_m at final_height_m and below, widening
/// with the gear's height above the top at the same angle as seen from the top [m]. Higher up
/// the same lateral error is a smaller angle off the top, and the descent onto it brings it to
/// the final hold, which asks for radial_tol_m again before the rapid descent. A fixed cylinder
/// made a hover of seconds at the refinement's height the price of each centimetre, and over a
/// low top, whose parallax against the floor there is a few pixels, vision lost the top in that
/// hover before e_r(t) closed.
double descent_tolerance_m(const LandingParams& L, double gear_above_top_m);

/// How far the gear's centre may be off the centre of a top whose side measures side_m and
/// still touch down with fit_margin_m of the top around the gear, along that side [m]; 0 for an
/// unmeasured (NaN) or too small top.
double fit_radius_m(const LandingParams& L, double side_m);

/// The room the measured top leaves around the gear, along each of its axes. The gear is square
/// and turned onto the top's edges (align_yaw_tol_deg), so the gear's centre may stray
/// fit_radius_m of the long side along the long axis and fit_radius_m of the short side across
/// it: a box in the top's frame, not a circle of the short side's room. A narrow top leaves an
/// autopilot that holds to a few centimetres most of its room along its length.
struct TopRoom {
  Vector2d long_axis_W = Vector2d::UnitX();  ///< unit, horizontal: the box's first axis
  Vector2d half_m = Vector2d::Zero();        ///< the room along long_axis_W and across it [m]
  /// e_W in the top's frame: (along long_axis_W, across it).
  Vector2d in_top(const Vector2d& e_W) const;
};

/// The room from the refinement's medians (size_m: long, short; NaN: unmeasured) and the
/// consistency of its yaw measurements: long_axis (the mean of (cos, sin)(2 yaw), |.| <= 1) names
/// the long axis when its length is at least kAxisAgreement; otherwise edges (the mean of
/// (cos, sin)(4 yaw)) give a square of the short side's room on the edges' axes; with neither,
/// the square inside the short side's circle (any direction).
TopRoom top_room(const LandingParams& L, const Vector2d& size_m, const Vector2d& long_axis,
                 const Vector2d& edges);

/// How consistent the views' yaw must be (the length of the mean unit vector) to orient the room:
/// about 30 deg of spread about the mean.
constexpr double kAxisAgreement = 0.75;

/// The final hold's bounds after held_s of waiting at the final height. At first e_r within
/// min(radial_tol_m, final_hold_radial_m) and the horizontal speed within final_hold_speed_mps;
/// over half of final_hold_timeout_s the speed bound grows to final_hold_speed_max_mps. From a
/// quarter of it on, the predicted test's box grows from the strict radius to the top's room
/// along each axis (reached at half of it). A still, centred moment is worth waiting for, and a
/// vehicle that holds to millimetres has one within the first quarter; one that rarely has it
/// (an autopilot's position controller that holds to a few centimetres) should not wait for ever
/// when the top leaves room.
struct CalmBounds {
  double radial_m = 0.0;   ///< the strict test's e_r bound
  double speed_mps = 0.0;  ///< ... and its speed bound
  /// The predicted test's bounds on the offset and where it heads, in the top's frame (zero:
  /// none yet, or the top leaves no room beyond the strict radius across it).
  Vector2d reach_m = Vector2d::Zero();
  bool predicted() const { return reach_m.minCoeff() > 0; }
};
CalmBounds calm_bounds(const LandingParams& L, double held_s, const TopRoom& room);

/// The final hold's calm moment (beyond the paper), for final_hold_settle_s on end: either the
/// strict test (e_r and the speed within CalmBounds' radial_m and speed_mps), or the predicted
/// one: the offset, and the offset the vehicle heads for over the rapid descent's duration
/// (final_height_m / final_descent_rate_mps, e_W + v_W T), both within reach_m along each of
/// the top's axes. The predicted test lets a vehicle swinging through the centre descend while
/// it swings towards it. e_W: the gear's centre minus the target, horizontal. calm_since_utime
/// is the window's own state; true once it has lasted.
bool calm_for_final_descent(const LandingParams& L, const Vector2d& e_W,
                            const std::optional<PoseSample>& pose, double held_s,
                            const TopRoom& room, int64_t now_utime,
                            std::optional<int64_t>& calm_since_utime);

/// A descent begun on the hold's bounds is carried off (final_pause_radial_m) as much further
/// out along each axis as the bounds had grown: true when e_W lies beyond that.
bool carried_off(const LandingParams& L, const Vector2d& e_W, const CalmBounds& began,
                 const TopRoom& room);

/// Beyond the paper: the horizontal offset of the body origin from the gear's centre
/// (gear_height_m below it along the body's z axis) [m]. A body tilted against the wind holds
/// its gear downwind of the origin by gear_height_m sin(tilt); the gear lands where its feet
/// touch, and the body levels above them. With aim_gear the landing approach and the final
/// descent put the gear's centre, not the origin, over the target. Zero without a pose or
/// without aim_gear.
Vector2d body_over_gear_xy(const LandingParams& L, const std::optional<PoseSample>& pose);

/// Why a final hold ("held") or a paused final descent ("paused") gave up: the target-lost reason.
std::string no_calm_moment(const LandingParams& L, const std::string& what);

/// The ingress approach's own state: aligning at the standoff, then through the opening.
struct IngressApproach {
  Vector3d n_W = Vector3d(-1, 0, 0);  ///< horizontal normal of the opening, towards the vehicle
  bool through = false;               ///< aligned: flying through
  std::optional<int64_t> aligned_since_utime;
  double through_s_m = 0.0;  ///< carrot's progress along -n from the standoff [m]
};

using ApproachState = std::variant<LandingApproach, IngressApproach>;

/// What one approach step sees.
struct ApproachInputs {
  const std::optional<PoseSample>& pose;
  Vector3d p_W;  ///< the vehicle (the setpoint when there is no pose)
  Vector3d target_W;
  double yaw_sp_rad = 0.0;
  double since_found_s = 0.0;  ///< since the target was last in sight
  double dt_s = 0.0;
  int64_t now_utime = 0;
  /// The room the refinement's measured top leaves the gear (top_room): how far off the centre
  /// the final hold may let it down.
  TopRoom room;
};

/// What one approach step decided.
struct ApproachStep {
  enum class Next {
    kContinue,      ///< fly sp_p_W / sp_v_W; a non-empty reason is the new status reason
    kTargetLost,    ///< reason says what was lost; the setpoint is left as it was
    kFinalDescent,  ///< landing: fly sp_p_W, then FINAL_DESCENT (reason says why)
    kDone,          ///< ingress: through; hold sp_p_W (reason says why)
  };
  Next next = Next::kContinue;
  Vector3d sp_p_W = Vector3d::Zero();
  Vector3d sp_v_W = Vector3d::Zero();
  std::string reason;
};

class MissionProfile {
 public:
  /// kLanding or kIngress.
  static std::unique_ptr<const MissionProfile> make(Mission mission, const AutonomyParams& params);
  virtual ~MissionProfile() = default;

  virtual Mission mission() const = 0;

  /// Detection: the search path from the vehicle at p_W, and the yaw to fly it with (none: keep
  /// the current one).
  struct Search {
    std::vector<Vector3d> path_W;
    std::optional<double> yaw_rad;
  };
  virtual Search search(const Vector3d& p_W) const = 0;

  /// Refinement: the next vantage point around mu_W with covariance S_W of n waypoints; here_W:
  /// the vehicle (mu_W without a pose); normal_sum_W: the sum of the measured target normals.
  struct Vantage {
    Vector3d p_W = Vector3d::Zero();
    std::optional<double> yaw_rad;
  };
  virtual Vantage vantage(const Vector3d& mu_W, const Matrix3d& S_W, int n, const Vector3d& here_W,
                          const Vector3d& normal_sum_W, VantageSampler& sampler) const = 0;

  /// The fit check on the median measured sizes (a, b of TargetMeasurement::size_m): why it is
  /// refused and how high to hold then, or nothing when the vehicle fits. NaN sizes are refused.
  struct Refusal {
    std::string why;
    double hold_min_z_m = 0.0;
  };
  virtual std::optional<Refusal> refuse(double size_a_m, double size_b_m) const = 0;

  /// The approach's start from the converged refinement: its state and the yaw to fly it with.
  /// yaw4_sum: sum of (cos, sin)(4 yaw) of the platform's measured long axis.
  struct Start {
    ApproachState state;
    double yaw_sp_rad = 0.0;
  };
  virtual Start begin_approach(const PoseSample& pose, double yaw_sp_rad,
                               const Vector3d& normal_sum_W, const Vector2d& yaw4_sum) const = 0;
  virtual ApproachStep step_approach(ApproachState& state, const ApproachInputs& in) const = 0;

  /// Target lost and retries exhausted: hold at least this high [m].
  virtual double lost_hold_min_z_m() const = 0;

  /// Where a failsafe taken in the approach holds, and then descends: here_W is the vehicle,
  /// sp_W the approach's setpoint. Landing: the setpoint, over the estimate (the vehicle may
  /// have swung over the top's edge, and a descent there tips it). Ingress: the vehicle (the
  /// setpoint may lie in the opening).
  virtual Vector3d approach_failsafe_hold_W(const Vector3d& here_W, const Vector3d& sp_W) const = 0;
};

}  // namespace alight::autonomy
