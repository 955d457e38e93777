#pragma once
// Flow odometry over the floor (flight without motion capture): the downward camera's
// translation between consecutive frames divided by its distance to the floor, t/d, for the
// error-state EKF, which multiplies it by the rangefinder's height.
//
// Model: the plane-induced homography (Hartley & Zisserman, "Multiple View Geometry in Computer
// Vision", 2nd ed. 2004, sec. 13.1, result 13.1: H = R - t v^T for the plane (v^T, 1)^T), the
// one the paper uses for the dominant plane (Brockers et al. 2011, sec. 3.1.2, eqs. 1-2:
// x2 = R21 (x1 - t12), n1~^T x1 = 1, H = R21 (I - t12 n1~^T); eqs. 4-6 use the same t12, n1~).
//
// Frames (camera C optical: x right, y down, z forward; docs/ARCHITECTURE.md "Frames"):
//   C1, C2     the camera at the first and the second exposure;
//   R_C2C1     C1 axes to C2 axes (the paper's R21): X_C2 = R_C2C1 (X_C1 - p_C1_C2);
//   p_C1_C2    the centre of C2 in C1 (the paper's t12);
//   n_C1       unit normal of the floor in C1, pointing from the floor towards the camera (the
//              world's up, R_C1W e_z, for a level floor): a floor point X_C1 has n_C1^T X_C1 = -d;
//   d          distance of C1 to the floor plane, > 0 [m];
//   u          = t_over_d_C1 = p_C1_C2 / d, the output [-].
// With these, the paper's n1~ = -n_C1 / d and t12 = d u, so a normalised image point x1 =
// (x, y, 1) of the floor maps to x2 ~ R_C2C1 (I + u n_C1^T) x1. In Hartley & Zisserman's form
// (X_C2 = R X_C1 + t, floor n^T X + d = 0) that is H = R - t n^T / d with R = R_C2C1,
// n = n_C1, t = -R_C2C1 p_C1_C2: the brief's x2 ~ (R_C2C1 + t' n^T / d) x1 with
// t' = R_C2C1 p_C1_C2, the displacement expressed in C2.
//
// Given R_C2C1 (the gyro) and n_C1 (the attitude), x2 is linear in u up to the projective scale:
// each correspondence gives two equations in the three unknowns. Cross-multiplied (x2 y_z - y_x
// = 0 with y = R (x1 + (n^T x1) u)) they are linear; divided by y_z they are the reprojection
// error in image 2, which the refinement minimises.
//   1. RANSAC (Fischler & Bolles 1981) over 2-point minimal samples (4 linear equations, least
//      squares), MSAC scoring (Torr & Zisserman 2000), seeded and so deterministic;
//   2. Levenberg-Marquardt with Huber IRLS (Huber 1964; common/robust_lsq.hpp) on the inliers'
//      reprojection errors, the scale from their median, inliers re-selected and refined again;
//   3. covariance: Huber's sandwich sigma_eff^2 (J^T J)^-1, sigma_eff^2 = E|psi|^2 / E[psi']^2,
//      corrected for the inlier threshold's truncation of the noise, floored at min_sigma_px, and
//      counting at most max_independent_points inliers as independent (nearby tracks share
//      their errors); and the sensitivities of u to errors of R_C2C1 and n_C1 (implicit function
//      theorem on the estimating equation): the EKF adds as much of its gyro and attitude
//      uncertainty as it sees fit (J_rotation Sigma_theta J_rotation^T + ...). The covariance
//      covers the image noise only.
// Off-floor points (a box, a platform) move differently and fall out as outliers. Only the
// dominant plane is modelled: d is the distance to the floor, which the rangefinder must measure
// too (over a box it sees the box: the EKF's business).
//
// Front end: Shi-Tomasi corners (goodFeaturesToTrack, Shi & Tomasi 1994) spread over a grid,
// pyramidal Lucas-Kanade (Bouguet 2000) from the previous frame with a forward-backward check
// (Kalal, Mikolajczyk & Matas 2010), started where R_C2C1 and the last u predict; new corners
// when too few tracks survive, or in the cells of the detection grid the tracks have left
// (kMaxEmptyCellShare); the points of the fit and of the second motion (second_motion) stay.
// Lucas-Kanade assumes each patch keeps its brightness, but the sensor's automatic gain and the
// lights' flicker step the whole image by several percent from one frame to the next; at the coarse
// pyramid levels, where a sparse floor (tiles' grout) leaves only the shading of large patches,
// such a step reads as motion and sends the tracks off the image. So the current frame is tracked
// scaled by the ratio of the two frames' mean grey levels (gain_compensation: one multiplicative
// gain for the whole image, the sensor's model; Jin, Favaro & Soatto 2001 fit a gain and an offset
// per patch instead); detection reads the frame as it is. Pure: no LCM, no clock, no files; time is
// the frames' utime.

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "common/camera_model.hpp"
#include "estimator/flow_params.hpp"
#include "estimator/types.hpp"

namespace alight::estimator {

/// One measurement between two consecutive frames: FlowSample (estimator/types.hpp).

/// Why a frame pair gave no sample. kOk exactly when there is one.
enum class FlowReason : int8_t {
  kOk = 0,
  kNoPrevious,      ///< first frame, after reset(), or the previous frame was refused
  kBadImage,        ///< empty, not mono8, or not the camera model's size; frame refused
  kBadTime,         ///< stamp not after the previous frame's; frame refused
  kTimeGap,         ///< frames more than max_gap_s apart
  kBadRotation,     ///< R_C2C1 not finite or not a rotation
  kBadNormal,       ///< n_C1 not finite or not of unit length
  kTooFewTracks,    ///< fewer usable correspondences than min_inliers
  kTooFewInliers,   ///< the fit kept fewer than min_inliers or min_inlier_fraction
  kDegenerate,      ///< the inliers do not fix all three components (clustered, or the fit failed)
  kPlaneNotInView,  ///< too few rays meet the plane (camera not looking at it)
};
inline constexpr int kNumFlowReasons = 11;

const char* to_string(FlowReason r);

/// Outcome of the robust fit on one set of correspondences.
struct FlowFit {
  FlowReason reason = FlowReason::kOk;
  Eigen::Vector3d t_over_d_C1 = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d J_rotation = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d J_normal = Eigen::Matrix3d::Zero();
  std::vector<uint8_t> inlier;  ///< per correspondence (empty when refused before RANSAC)
  int inliers = 0;
  int usable = 0;  ///< correspondences whose ray meets the plane
  double residual_rms_px = 0.0;
  double sigma_px = 0.0;   ///< residual standard deviation used for the covariance [px]
  double condition = 0.0;  ///< eigenvalue ratio of the information matrix [-]
  int ransac_samples = 0;  ///< minimal samples drawn
};

/// Robust t/d from correspondences of normalised, undistorted rays (x, y, 1) (CameraModel::ray)
/// in the first and second image, given R_C2C1 and the unit floor normal n_C1 (pointing
/// towards the camera). `focal_px` (> 0, from a validated CameraModel) converts the pixel
/// thresholds. Pure and deterministic: the same inputs give the same bits.
FlowFit fit_t_over_d(const std::vector<Eigen::Vector3d>& rays_1,
                     const std::vector<Eigen::Vector3d>& rays_2, const Eigen::Matrix3d& R_C2C1,
                     const Eigen::Vector3d& n_C1, double focal_px, const FlowFitParams& params);

/// Another motion in view (FlowSample::others): the fit of the correspondences a first fit
/// left out (inlier: its per-correspondence flags), when they are min_inliers or more and share
/// one; nullopt otherwise. A platform moving under the camera is a plane of its own motion: over
/// a sparse floor its features may outnumber the floor's, and the first fit is then the
/// platform's. `second_inlier` (optional) gets the second fit's inliers as flags over all the
/// correspondences (all zero without a second motion).
std::optional<FlowMotion> second_motion(const std::vector<Eigen::Vector3d>& rays_1,
                                        const std::vector<Eigen::Vector3d>& rays_2,
                                        const std::vector<uint8_t>& inlier,
                                        const Eigen::Matrix3d& R_C2C1, const Eigen::Vector3d& n_C1,
                                        double focal_px, const FlowFitParams& params,
                                        std::vector<uint8_t>* second_inlier = nullptr);

/// Pixel of the floor point seen at ray_1 in the first camera, as the model predicts it in the
/// second camera (x2 ~ R (I + u n^T) x1, then the lens); nullopt behind the camera.
std::optional<Eigen::Vector2d> predict_pixel(const CameraModel& camera,
                                             const Eigen::Vector3d& ray_1,
                                             const Eigen::Matrix3d& R_C2C1,
                                             const Eigen::Vector3d& n_C1,
                                             const Eigen::Vector3d& t_over_d_C1);

/// Two frames' mean grey levels (at the tracking level) agreeing this closely are tracked as
/// they are: a quarter of a grey level at full scale, below the images' quantisation.
inline constexpr double kGainTolerance = 1e-3;
/// Below this mean grey level a frame is black: no ratio is taken from it.
inline constexpr double kMinMeanForGain = 1.0;

/// The factor that brings the current frame to the previous frame's brightness, previous_mean /
/// current_mean, when both frames are lit (kMinMeanForGain) and the factor is more than
/// kGainTolerance from 1; nullopt otherwise (track the frame as it is).
std::optional<double> gain_compensation(double previous_mean, double current_mean);

/// More than this share of the detection grid's cells without a track: the tracks have left a
/// region of the view, and new features are detected there though min_tracks survive. A
/// textured top filling the middle of the view, moving with the camera, keeps its own tracks
/// while the floor's around it leave at the border; its tracks alone can hold min_tracks, and
/// the floor (the camera's own motion, FlowSample::others) would not be seen again. On a floor
/// textured all over, a few border cells at a time empty as the view moves on.
inline constexpr double kMaxEmptyCellShare = 0.125;  // six of the default grid's 48

/// What a frame pair produced, also without a sample.
struct FlowResult {
  std::optional<FlowSample> sample;  ///< set exactly when reason == kOk
  FlowReason reason = FlowReason::kOk;
  int tracked = 0;    ///< features of the previous frame found again (after the FB check)
  int detected = 0;   ///< new features detected in this frame
  int features = 0;   ///< features carried to the next frame
  double gain = 1.0;  ///< this frame's mean grey level over the previous one's (1: no pair)
  explicit operator bool() const { return sample.has_value(); }
};

/// The front end: one downward camera's frames in exposure order.
class FlowOdometry {
 public:
  /// Throws ParamError (params.validate(), camera.validate()) on a bad configuration.
  FlowOdometry(const FlowFrontParams& params, const CameraModel& camera);

  /// The next frame (mono8, camera-sized) with its exposure time, the rotation R_C2C1 from the
  /// previous frame passed here to this one (gyro), and the unit floor normal in the previous
  /// frame's camera, n_C1 (attitude; pointing towards the camera). A frame refused for its
  /// image or stamp (kBadImage, kBadTime) is dropped and the next frame starts anew
  /// (kNoPrevious); every other frame becomes the previous frame of the next call, with or
  /// without a sample.
  FlowResult add_frame(const cv::Mat& gray, int64_t utime, const Eigen::Matrix3d& R_C2C1,
                       const Eigen::Vector3d& n_C1);

  /// Forgets the previous frame and its tracks (the next frame gives kNoPrevious).
  void reset();

  /// Pairs by outcome since construction, indexed by FlowReason.
  const std::array<int64_t, kNumFlowReasons>& counts() const { return counts_; }
  /// The current frame's features, full-resolution pixels (diagnostics).
  std::vector<Eigen::Vector2d> feature_pixels() const;
  const FlowFrontParams& params() const { return params_; }
  const CameraModel& camera() const { return camera_; }

 private:
  FlowResult finish(FlowResult r);
  // New features in `region` (tracking-level pixels) up to max_features in all; in_cell: the
  // tracks per grid cell before them (tracks_per_cell()).
  void detect(int already_tracked, FlowResult& r, const cv::Rect& region, std::vector<int> in_cell);
  // The smallest box holding every grid cell without a track (in_cell: tracks_per_cell()).
  cv::Rect empty_cells_box(const std::vector<int>& in_cell) const;
  int cell_of(const cv::Point2f& tracking_px) const;  // its detection grid cell, row-major
  std::vector<int> tracks_per_cell() const;

  FlowFrontParams params_;
  CameraModel camera_;
  double level_scale_ = 1.0;  // full-resolution pixels per tracking-level pixel
  cv::Size level_size_;
  cv::Size window_;
  cv::TermCriteria lk_criteria_;

  bool have_previous_ = false;
  int64_t previous_utime_ = 0;
  std::vector<cv::Mat> previous_pyramid_;
  double previous_mean_ = 0.0;         // the previous frame's mean grey level (tracking level)
  std::vector<cv::Point2f> points_;    // tracking-level pixels of the previous frame's features
  std::vector<Eigen::Vector3d> rays_;  // their normalised rays
  std::optional<Eigen::Vector3d> last_t_over_d_;  // of the last pair, for the prediction
  double last_dt_s_ = 0.0;
  std::array<int64_t, kNumFlowReasons> counts_{};
};

}  // namespace alight::estimator
