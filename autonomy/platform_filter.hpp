#pragma once
// The moving platform's motion from the vision's measurements (VISION_PLATFORM; beyond the
// paper, whose 3.4.1 averages a still platform's waypoints, eqs. 7-9).
//
// A constant-velocity Kalman filter: horizontally the state [x, y, vx, vy] driven by white
// acceleration of spectral density accel_psd (a cart's turns, a deck's drift), and the long
// axis' yaw with its rate [psi, omega] driven by white angular acceleration; each measurement's
// position, velocity, yaw and yaw rate with the covariances vision publishes. The yaw is a
// direction of a rectangle's axes (mod pi/2: a top seen in part can swap its long and short
// sides): it is kept in (-pi/4, pi/4], its innovation wrapped there. Measurements come in
// exposure order. Each refusal is counted by its reason (Refusal):
//  - not finite, or older than the filter's time;
//  - its extent kLargerThanTheTop times the track's whole top: another object (judged once the
//    track holds min_consistent views: its first may be of part of it);
//  - its position and velocity innovation beyond gate_chi2 (Mahalanobis distance by the
//    predicted covariance, 4 dof);
//  - its velocity farther from the prediction than kMaxPlatformAccelMps2 reaches since the
//    track's last update, plus three sigmas of the track's velocity then and of the
//    measurement's: the white acceleration's variance grows with the gap (accel_psd dt), and
//    after a few frames unmeasured the gate admits velocities no platform reaches in that time.
//    The refused measurements start a candidate track of their
//    own; after max_consecutive_rejections in a row, the candidate replaces the track once it is
//    believed itself (the platform is not where it was believed), or at once while the track is
//    not believed yet.
// A measurement whose extent falls short of the track's whole top (the extent its latest views
// agree on best, or a larger one kWholeTopViews of them agree on, and, larger than the whole top
// believed so far, a quarter as many as the best supported one: whole_extent) by kPartialViewM
// shows part of the top: its position is not the top's centre and is not fused, its velocity is
// (the part moves with the whole). A view vision marks as cut by the image's border (its position
// variance kCutPositionVarM2 or more) counts towards the whole top too once it spans the whole top
// believed so far (a larger one that only cut views support becomes the whole top once they
// outnumber the views that showed the smaller one uncut: a cut view can hold more than the top);
// one whose extent is the whole top's has nothing beyond the border, and its
// position is fused (within kPartialViewM / 2). A view wider than the whole top on a side is no
// part of it and joins the extents too; where they then make the whole top shorter on a side
// than before, the centre fused on the old one was another object's, and its variance grows
// (forget_centre_of_another_top); where they make it longer than the latest view that placed the
// centre (the track's first, whatever it showed, may be the only one), that view was of a part
// of it, and the variance grows by half the difference (doubt_centre_of_a_part). The whole views,
// clearly longer than wide, vote which of the filter's two axes is the top's long one
// (Prediction::long_yaw_rad). A track is believed (believed()) after min_consistent measurements in
// a row, each within the gate, over at least kConfirmS: a short burst of wrong measurements (a
// mismatched frame pair during the search reads as a fast platform) never is. A track not measured
// for kConfirmS is confirmed again (its grown covariance lets a wrong measurement through the
// gate). Pure: time passed in.
//
// The prediction turns the velocity at the course's turn rate (the filtered velocity's direction
// over course_tau_s, or over kCourseBaselineM of a creeping top's path): a cart round a bend is
// led into it, not extrapolated off its path. A
// measured velocity is the mean over vision's interval, the velocity at its middle: it is turned
// on to the measurement's time at that rate before it is fused.
//
// The deck's heave: the vertical velocities vision measures (each the mean over its interval,
// at the interval's middle) in a window of heave_window_s, fitted by one sine of the
// frequency in heave_band_hz that explains them best (least squares per frequency on a grid),
// so the deck's vertical position and velocity can be predicted a fall time ahead
// (HeaveModel).

#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>

#include "common/geometry.hpp"
#include "common/param_schema.hpp"

namespace alight::autonomy {

using Eigen::Matrix2d;

/// One measurement of the moving top (platform_motion_t, found).
struct PlatformMeasurement {
  int64_t utime = 0;      ///< exposure of the current image [us]
  int64_t ref_utime = 0;  ///< exposure of the earlier image [us]
  Vector3d p_W = Vector3d::Zero();
  Vector3d v_W = Vector3d::Zero();
  double yaw_rad = 0.0, yaw_rate_rps = 0.0;
  Matrix3d cov_p_W = Matrix3d::Identity(), cov_v_W = Matrix3d::Identity();
  double var_yaw = 1.0, var_yaw_rate = 1.0;
  Vector2d size_m = Vector2d::Zero();
  /// The cameras the top was placed from (current, earlier exposure) and the level plane vision
  /// placed it on (platform_motion_t version 2); plane_z_m NaN: not sent, the top is taken at
  /// vision's plane.
  Vector3d camera_W = Vector3d::Zero(), ref_camera_W = Vector3d::Zero();
  double plane_z_m = NAN;
  bool placed_from_cameras() const { return std::isfinite(plane_z_m); }
  /// Measured by its outline (platform_motion_t version 3): four corners give the scale, and so
  /// the heave, to a few per cent, as much as a deck heaves over an interval; its vertical
  /// velocity is left out of the heave and the top's height.
  bool outline = false;
};

/// The top's height less the plane vision placed it on (dh), measured from the vertical
/// velocities vision reads while the camera climbs or descends. A level top dh above the plane
/// is placed by each view scaled about its camera's nadir by (z_c - plane) / (z_c - plane - dh);
/// between two cameras at z_1 and z_2, dt apart, that reads as the top rising at
/// dh g with g = (z_1 - z_2) / (dt (z_1 - plane - dh)) (vision/landing/moving_top.hpp), on top of
/// the deck's heave. Fitted over the heave's window jointly with the heave (a sine, and a drift
/// held near zero: a deck's mean height does not move, a cart's floor is level) and dh held near
/// zero by kTopHeightPriorSigmaM; the velocities are means over overlapping intervals, so a
/// window weighs as many independent ones as intervals fit in its span. A window where the camera
/// barely moved vertically knows little of dh (its variance stays near the prior's), so the best
/// informed window's is kept, its variance grown by kTopHeightDriftM2PerS since; one that
/// disagrees with it beyond kTopHeightGateSigmas waits kTopHeightDisagreeS of disagreeing windows.
struct TopHeight {
  double dh_m = 0.0;
  double var_m2 = 0.0;  ///< 0: not measured (dh_m 0)
  int64_t utime = 0;    ///< of the window it was fitted over (its last sample)
  /// Since when the better informed windows have disagreed with it (0: none do) [us].
  int64_t disagreed_utime = 0;
};

/// One vertical velocity vision measured: the interval's middle [us], the velocity [m/s], g
/// [1/s], the velocity a height error of one metre adds (TopHeight), 0 without cameras, and the
/// interval it is the mean over [s] (samples whose intervals overlap share their errors).
struct VerticalSample {
  int64_t utime = 0;
  double vz_mps = 0.0, g_per_s = 0.0;
  double interval_s = 0.25;
};

/// The spread of the tops' heights the plane is set among (8-30 cm about vision's 15 cm) [m].
inline constexpr double kTopHeightPriorSigmaM = 0.1;
/// The spread of a deck's mean vertical velocity over the heave's window (none on a level floor
/// or a moored deck) [m/s]: so that a steady descent's reading is the height's, not a drift.
inline constexpr double kHeaveDriftSigmaMps = 0.005;
/// A vertical velocity's noise where the fit's residuals say less [m/s]: vision's over a quarter
/// second from 1-2 px of scale noise on a top a few hundred pixels across.
inline constexpr double kVerticalSigmaMps = 0.02;
/// A velocity this many times the residuals' robust spread (1.4826 times their median, at least
/// half kVerticalSigmaMps) off the window's fit is left out of dh's fit: a normal residual is
/// that far once in several hundred samples.
inline constexpr double kVerticalOutlierSigmas = 3.0;
/// How fast a kept height goes stale [m^2/s]: the top does not change height, but a window fitted
/// with a wrong heave frequency can be confident and wrong; a better informed one replaces it.
inline constexpr double kTopHeightDriftM2PerS = 1e-5;
/// A better informed window that disagrees with the height kept by more than this many sigmas
/// of the two (each window's heave is a model: a sea state's is not one sine, and its misfit
/// leaks into dh) replaces it only after kTopHeightDisagreeS of windows that all disagree.
inline constexpr double kTopHeightGateSigmas = 3.0;
inline constexpr double kTopHeightDisagreeS = 1.0;
/// The height error is applied only with the camera this far above the top at the least [m].
inline constexpr double kMinPlacingRangeM = 0.1;

/// dh from one window of samples (TopHeight): the least-squares fit of a sine of the best
/// frequency in min_hz..max_hz (none over less than most of a period), a drift and dh g to the
/// velocities, with the priors above; var_m2 from the fit's residuals.
TopHeight fit_top_height(const std::deque<VerticalSample>& samples, double min_hz, double max_hz);

/// The measurement placed again on the level plane plane_z_m + dh instead of plane_z_m: position,
/// velocity and extent scaled about the cameras' nadirs, the vertical velocity less dh g, z
/// raised by dh. Unchanged without cameras or with a camera within kMinPlacingRangeM of that plane.
PlatformMeasurement placed_at_height(const PlatformMeasurement& m, double dh_m);

struct PlatformFilterParams {
  /// Horizontal acceleration spectral density [m^2/s^3]: a cart at 1 m/s round a 0.6 m turn
  /// accelerates at 1.7 m/s^2 for the 2 s of a half turn.
  double accel_psd = 1.5;
  double yaw_accel_psd = 0.05;  ///< angular acceleration spectral density [rad^2/s^3]
  double gate_chi2 = 18.47;     ///< 4 dof, p = 0.001
  int max_consecutive_rejections = 5;
  /// Measurements in a row within the gate before a track's motion is believed: a fifth of a
  /// second of the camera's frames at the least.
  int min_consistent = 6;
  double stale_s = 1.0;        ///< no measurement for this long: the filter starts over
  double min_sigma_m = 0.005;  ///< floor on a measurement's position sigma [m]
  /// Floor on its velocity sigma [m/s]: the mean over vision's interval lags the velocity now by
  /// half the interval's acceleration (0.2 m/s in a cart's turn).
  double min_sigma_mps = 0.1;
  double course_tau_s = 0.3;
  double heave_window_s = 6.0;
  double heave_min_hz = 0.1, heave_max_hz = 1.0;
  static const ParamSchema<PlatformFilterParams>& schema();
  void validate() const;
};

/// The deck's vertical motion as one sine: vz(t) = a sin(w t) + b cos(w t) + c (t from t0).
struct HeaveModel {
  double w_rps = 0.0;  ///< 0: no heave model (too few samples)
  double a = 0, b = 0, c = 0;
  int64_t t0_utime = 0;
  double rms_mps = 0;  ///< residual
  double amplitude_m() const { return w_rps > 0 ? std::hypot(a, b) / w_rps : 0.0; }
  double vz(int64_t utime) const;
  /// The deck's height about its mean (the sine's integral; the drift c left out).
  double z(int64_t utime) const;
};

/// Fits the heave to the samples with the height's error dh_m taken out (TopHeight): the best
/// frequency on a grid of min_hz..max_hz; none over less than most of a period.
HeaveModel fit_heave(const std::deque<VerticalSample>& samples, double dh_m, double min_hz,
                     double max_hz);

/// Whole views (placing the centre, their long side longer than the short by more than a view's
/// scatter, kPartialViewM) that must agree more for one of the filter's two axes than for the
/// other before it is the top's long one (Prediction::long_axis_known); the votes are kept within
/// kLongAxisVotesKept of even, so that a few wrong early ones are outvoted within a second.
inline constexpr double kLongAxisVotes = 3;
inline constexpr double kLongAxisVotesKept = 30;

/// A horizontal covariance's variance along its worst axis (its largest eigenvalue) [m^2].
double worst_axis_var(const Matrix2d& cov);

/// A measured extent this much shorter than the track's whole top (on either side): a view of
/// part of it [m]. Close over the top, it fills the view and the inliers' rectangle is the
/// visible part's, its centre pulled towards the camera by up to half the shortfall: beyond
/// 1.5 cm, the measured extents' own scatter from one frame to the next.
inline constexpr double kPartialViewM = 0.03;

/// A measurement's horizontal position variance from which vision does not know where the top's
/// centre is (platform_motion_t: a top cut by the image's border, 100 m^2) [m^2]: its extent is
/// the visible part's.
inline constexpr double kCutPositionVarM2 = 1.0;

/// A measured extent this many times the track's whole top (on either side) is not that top: a
/// mismatched cluster of the floor or the vehicle's own motion read as one. The views of one
/// top from the search height down to the last drop's differ by under a third.
inline constexpr double kLargerThanTheTop = 1.5;

/// A track is believed only over this span at the least [s]: vision's positions alone (1-2 cm
/// each) then confirm its velocity within a few centimetres a second, under the approach's
/// match tolerance, whatever the velocities it measured say.
inline constexpr double kConfirmS = 0.5;

/// A platform's velocity changes at most this fast [m/s^2]: the turn accel_psd is sized for (a
/// cart at 1 m/s round a 0.6 m bend, 1.7 m/s^2) with a margin; the families' carts slow for
/// their turns at 0.5 m/s^2 and turn their course at 0.26 m/s^2.
inline constexpr double kMaxPlatformAccelMps2 = 2.0;

/// Faster than this, the course's turn is followed update by update (course_tau_s) [m/s]: a
/// fifth of a second of a 1 m/s cart's frames turn its filtered velocity by more than its noise.
inline constexpr double kFastCourseMps = 0.2;
/// Slower, the course's turn is its direction's change over this much of its path [m]: at the
/// filtered velocity's 1-2 cm/s of noise, a creeping top's turn known within a few degrees a
/// second; a 10 cm/s top covers it in 2.5 s, a quarter of a slow circle.
inline constexpr double kCourseBaselineM = 0.25;
/// Slower than this, a top has no course [m/s]: its filtered velocity's direction is noise.
inline constexpr double kCourseMinSpeedMps = 0.05;

class PlatformFilter {
 public:
  /// Why a measurement was refused.
  enum class Refusal { kNotFinite, kOutOfOrder, kGate, kLargerThanTheTop, kBeyondReach };
  static constexpr int kRefusals = 5;
  static const char* to_string(Refusal r);

  explicit PlatformFilter(const PlatformFilterParams& params);

  /// Fuses a measurement; false when it was refused (counted by its reason).
  bool update(const PlatformMeasurement& m);
  void reset();

  bool initialised() const { return track_.t_utime != 0; }
  /// The track's motion is confirmed: min_consistent measurements in a row within the gate, over
  /// kConfirmS at the least.
  bool believed() const { return believed(track_); }
  int64_t utime() const { return track_.t_utime; }
  /// When the track began or, unmeasured for kConfirmS, was confirmed again [us].
  int64_t since_utime() const { return track_.since_utime; }
  /// The state predicted to `utime` (not before the filter's time).
  struct Prediction {
    Vector2d p_W = Vector2d::Zero(), v_W = Vector2d::Zero();
    Vector2d a_W = Vector2d::Zero();  ///< the velocity's turn at the course's rate [m/s^2]
    Matrix2d cov_p = Matrix2d::Zero(), cov_v = Matrix2d::Zero();
    double yaw_rad = 0;  ///< the axes' direction, in (-pi/4, pi/4] [rad]
    double yaw_rate_rps = 0, var_yaw = 0;
    /// The top's long axis, in (-pi/2, pi/2] [rad]: yaw_rad or a quarter turn from it, as the
    /// whole views' long sides voted (long_axis_known).
    double long_yaw_rad = 0;
    bool long_axis_known = false;
    double top_z_m = 0;  ///< the top's height, the measurements' z averaged [m]
    /// How far the centre is from where the track began [m]: a motion shown by the positions,
    /// which vision measures to 1-2 cm, where a slow one's velocity is lost in its noise.
    double travelled_m = 0;
  };
  Prediction predict(int64_t utime) const { return predict(track_, utime); }
  const HeaveModel& heave() const { return track_.heave; }
  int n_updates() const { return n_updates_; }
  int n_rejected() const { return n_rejected_; }
  int n_refused(Refusal r) const { return refused_[static_cast<int>(r)]; }
  /// Measurements in a row within the gate since the track started.
  int n_consistent() const { return track_.n_consistent; }
  /// Measurements fused as views of part of the top (velocity only).
  int n_partial() const { return n_partial_; }
  /// Times the track's whole top was judged another than the one its centre was fused on
  /// (the centre's variance then grown to the two extents' reach).
  int n_other_tops() const { return track_.n_other_tops; }
  /// Views in a row that placed the centre (their positions fused as the top's: not of part of
  /// it, not cut unless showing the whole top), each within the gate of the ones before: none
  /// that would have placed it was refused since, the centre was not forgotten since
  /// (forget_centre_of_another_top), and none came when the centre's predicted sd was beyond
  /// kPartialViewM (a view the gate cannot test against the centre starts the count again).
  int n_placed() const { return track_.n_placed; }
  /// The track's whole top (long, short side) [m]; zero before its first measured extent.
  Vector2d whole_top() const { return track_.whole; }
  /// The top's height less vision's plane, as measured so far (kept through the filter's
  /// restarts: the platform's, not a track's).
  const TopHeight& top_height() const { return height_; }

 private:
  // The filtered velocity's direction (unwrapped) [rad] and the path travelled [m] at a time [us].
  struct CourseSample {
    int64_t utime = 0;
    double heading = 0, path_m = 0;
  };
  // One track: the filter's state since it (re)started.
  struct Track {
    int64_t t_utime = 0;  // 0: not started
    int64_t since_utime = 0;
    Vector2d p_start = Vector2d::Zero();          // the centre where it began
    Eigen::Vector4d x = Eigen::Vector4d::Zero();  // x, y, vx, vy
    Eigen::Matrix4d P = Eigen::Matrix4d::Zero();
    Vector2d yaw = Vector2d::Zero();  // psi, omega
    Matrix2d P_yaw = Matrix2d::Zero();
    double course_rate = 0;           // the velocity's turn rate [rad/s]
    std::deque<CourseSample> course;  // the filtered velocity's direction along the path
    double top_z_sum = 0;             // of the measurements' z as vision placed them
    double g_dt_sum = 0;              // of their VerticalSample::g_per_s times their interval [m/m]
    int n_z = 0;
    std::deque<VerticalSample> vz;
    HeaveModel heave;
    double dh_m = 0;  // the filter's TopHeight when the track last fused (whole_extent's)
    int n_consistent = 0;
    struct View {
      Vector2d extent = Vector2d::Zero();  // (long, short) as vision placed it [m]
      bool cut = false;                    // marked cut by the image's border
      double range_m = INFINITY;           // its camera's height over vision's plane [m]
      int64_t utime = 0;                   // its exposure (the heave's height then) [us]
    };
    std::deque<View> extents;           // of its views (fuse: which ones)
    Vector2d whole = Vector2d::Zero();  // whole_extent(extents)
    int n_other_tops = 0;               // whole tops given up (forget_centre_of_another_top)
    int n_placed = 0;                   // n_placed()
    // The extent of the latest view that placed the centre (zero: none with a size yet).
    Vector2d placed_extent = Vector2d::Zero();
    // The whole views' votes for their long side lying along yaw(0)'s axis (+1 each) or across
    // it (-1), within +-kLongAxisVotesKept: turned over with yaw(0) when it wraps a quarter.
    double long_votes = 0;
  };
  enum class Fused { kAccepted, kAcceptedPartial, kOutsideGate, kBeyondReach };
  // raw: as vision placed it; fused placed at the track's height (placed_at_height, t.dh_m).
  Fused fuse(Track& t, const PlatformMeasurement& raw) const;
  void follow_course(Track& t, int64_t utime, const Vector2d& v0, double dt) const;
  void start(Track& t, const PlatformMeasurement& m) const;
  static Vector2d whole_extent(const Track& t);
  static bool partial_view(const Track& t, const PlatformMeasurement& m);
  static bool shows_whole_top(const Track& t, const PlatformMeasurement& m);
  // The view's extent is the whole top believed on both sides (within kPartialViewM), or no whole
  // top or no extent is known to judge it by: its rectangle's yaw is taken as the top's.
  static bool spans_whole_top(const Track& t, const PlatformMeasurement& m);
  static bool places_centre(const Track& t, const PlatformMeasurement& m) {
    return !partial_view(t, m) && (!cut(m) || shows_whole_top(t, m));
  }
  static void forget_centre_of_another_top(Track& t, const Vector2d& before);
  static void doubt_centre_of_a_part(Track& t, const Vector2d& before);
  // Adds a view's extent to the track's, judges the whole top again (whole_extent) and forgets a
  // centre fused on another top or doubts one placed on a part of this one.
  static void add_extent(Track& t, const PlatformMeasurement& m);
  static bool cut(const PlatformMeasurement& m) {
    return m.cov_p_W.topLeftCorner<2, 2>().diagonal().maxCoeff() >= kCutPositionVarM2;
  }
  bool larger_than_the_top(const Track& t, const PlatformMeasurement& m) const;
  Prediction predict(const Track& t, int64_t utime) const;
  bool believed(const Track& t) const;
  void refuse(Refusal r);

  PlatformFilterParams params_;
  Track track_;
  // The measurements the track refuses, tracked on their own: the platform may not be where it
  // was believed.
  Track candidate_;
  int consecutive_rejections_ = 0, n_updates_ = 0, n_rejected_ = 0;
  int n_partial_ = 0;
  std::array<int, kRefusals> refused_{};
  TopHeight height_;
  // The track's window fitted for the top's height; kept where better informed than height_.
  void measure_height(Track& t);
  void at_height(Track& t) const;
};

}  // namespace alight::autonomy
