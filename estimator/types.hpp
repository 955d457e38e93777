#pragma once
// The estimator's inputs and output (flying without motion capture). Plain structs, no
// middleware: the node converts LCM messages into these. Frames as in docs/ARCHITECTURE.md: world
// W z up, body B x forward / y left / z up, camera C optical; utime in microseconds.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace alight::estimator {

using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector3d;

/// One IMU sample: the mean over the interval that ends at utime (as a decimating IMU reports).
struct ImuSample {
  int64_t utime = 0;
  Vector3d accel_B = Vector3d::Zero();  ///< specific force [m/s^2] (+g up at rest)
  Vector3d gyro_B = Vector3d::Zero();   ///< angular rate [rad/s]
};

/// A downward rangefinder's reading: the distance along the beam (from t_B_R along d_B, see
/// RangeParams) to whatever is below, the floor or the top of an elevated platform.
struct RangeSample {
  int64_t utime = 0;
  double range_m = 0.0;
  bool valid = false;  ///< the sensor's own verdict (signal strength, in its range)
};

/// A barometer's static pressure.
struct BaroSample {
  int64_t utime = 0;
  double pressure_pa = 0.0;
};

/// Another motion among the front end's outliers (flow_odometry.hpp, FlowSample::others).
struct FlowMotion {
  Vector3d t_over_d_C1 = Vector3d::Zero();  ///< [-]
  Matrix3d cov = Matrix3d::Identity();      ///< [-]
  int inliers = 0;
  Matrix3d J_rotation = Matrix3d::Zero();  ///< as FlowSample's [1/rad]
  Matrix3d J_normal = Matrix3d::Zero();    ///< [-]
};

/// The flow front end's output for two consecutive frames: the camera's translation between the
/// exposures at utime_from and utime_to, in the camera frame at utime_from, divided by the distance
/// d of that camera from the (horizontal) plane below. From the floor-plane homography
/// H = R + t n^T / d with R known from the gyro.
///
/// The front end needs R_C2C1 (camera 1 to camera 2) and n_C1 (the floor's up normal in camera
/// 1); both come from this estimate (Onboard: the gyro less the estimated bias between the
/// frames, the estimated attitude at the first; Estimator::attitude_at gives the same to first
/// order). Their errors are then the estimate's attitude errors, and the sensitivities below enter
/// the flow update's Jacobian (add_input_sensitivities; zero: no dependence).
struct FlowSample {
  int64_t utime_from = 0;
  int64_t utime_to = 0;
  Vector3d t_over_d_C1 = Vector3d::Zero();  ///< [-] (metres per metre of height)
  Matrix3d cov = Matrix3d::Identity();      ///< covariance of t_over_d_C1 [-]
  int inliers = 0;                          ///< homography inliers behind it
  /// The front end's sensitivities (flow_odometry.hpp): given R_C2C1 Exp(theta) instead of the
  /// rotation passed in (theta in C1), t_over_d_C1 moves by J_rotation theta [1/rad]; given the
  /// normal n_C1 + delta (normalised), by J_normal delta [-].
  Matrix3d J_rotation = Matrix3d::Zero();
  Matrix3d J_normal = Matrix3d::Zero();
  double residual_rms_px = 0.0;  ///< inliers' reprojection error, root mean square [px]
  /// Other motions in view: the largest set among the fit's outliers that shares one
  /// (min_inliers or more; the front end fits at most one). Where a textured platform moving
  /// under the camera outnumbers a sparse floor's features, the fit above is the platform's and
  /// this one the floor's (or the reverse): the filter fuses whichever its prediction explains
  /// best (Estimator::apply_flow).
  std::vector<FlowMotion> others;
};

/// What the estimator did with an input. kFused and kQueued are not rejections; every other
/// value is a reason, counted per sensor in Counters.
enum class Outcome : uint8_t {
  kFused = 0,       ///< used (IMU: propagated; measurement: update applied or terrain reset)
  kQueued,          ///< newer than the newest IMU sample: fused once the IMU reaches its time
  kNonFinite,       ///< NaN / inf in a value
  kAbsurd,          ///< outside physical bounds (accel, rate, pressure, flow magnitude, cov)
  kOutOfOrder,      ///< IMU stamp not after the previous one
  kTooOld,          ///< older than the history (or its flow clone time is)
  kTooNew,          ///< further ahead of the newest IMU sample than max_ahead_s
  kNotInitialised,  ///< before static alignment finished
  kInvalid,         ///< the sensor flagged it invalid
  kOutOfRange,      ///< range outside [min_range_m, max_range_m]
  kBeamAngle,       ///< rangefinder beam too far from vertical
  kGate,            ///< innovation outside the chi-square gate
  kTooFewInliers,   ///< flow with fewer homography inliers than min_inliers
  kGeometry,        ///< flow span or camera height unusable
  kNoClone,         ///< flow whose clone could not be made (too many overlapping samples)
  kQueueFull,       ///< too many measurements waiting for the IMU
  kDuplicate,       ///< the sensor's second sample with the same stamp (a repeated message)
  kNumerical,       ///< innovation covariance not positive definite / non-finite result
  kCount
};
constexpr int kOutcomeCount = static_cast<int>(Outcome::kCount);
const char* to_string(Outcome o);

enum class Sensor : uint8_t { kImu = 0, kRange, kBaro, kFlow, kCount };
constexpr int kSensorCount = static_cast<int>(Sensor::kCount);
const char* to_string(Sensor s);

/// Per sensor, how many inputs ended with each Outcome. A delayed measurement that is fused
/// again after an older one arrives is counted once, with its latest outcome.
struct Counters {
  std::array<std::array<int64_t, kOutcomeCount>, kSensorCount> by_outcome{};
  int64_t terrain_resets = 0;  ///< platform steps: terrain state reset from the rangefinder
  /// Flow samples fused against the floor while the rangefinder's terrain was a platform's top.
  int64_t flow_on_floor = 0;
  /// Flow samples fused with their noise inflated to their innovation, after the gate had refused
  /// the flow for half of health.flow_timeout_s (Estimator::apply_flow).
  int64_t flow_inflated = 0;
  /// Flow samples fused on another motion of the front end's (FlowSample::others), its own
  /// being the one the prediction explained worse.
  int64_t flow_second = 0;
  /// Flow samples fused as the camera's motion relative to a moving top (a top's velocity state).
  int64_t flow_top = 0;
  /// Times the horizontal velocity was set to the flow's after the flow had been refused for
  /// health.flow_timeout_s (Estimator::apply_flow).
  int64_t flow_velocity_resets = 0;
  int64_t baro_resets = 0;  ///< baro offset started over after baro.reset_after_s refused
  int64_t imu_gaps = 0;     ///< IMU intervals longer than health.imu_gap_s
  int64_t replays = 0;      ///< re-propagations from the history for delayed inputs

  int64_t count(Sensor s, Outcome o) const {
    return by_outcome[static_cast<int>(s)][static_cast<int>(o)];
  }
  int64_t fused(Sensor s) const { return count(s, Outcome::kFused); }
  /// Every outcome except kFused and kQueued.
  int64_t rejected(Sensor s) const;
};

/// OK: fly. DEGRADED: hold (autonomy holds position and waits). LOST: failsafe descent.
enum class Health : uint8_t { kOk = 0, kDegraded, kLost };
const char* to_string(Health h);

/// Why the health is not OK; several can hold at once (bits of State::health_reasons).
enum HealthReason : uint32_t {
  kReasonNone = 0,
  kNotInitialised = 1u << 0,     ///< LOST: static alignment not finished
  kNoFlow = 1u << 1,             ///< DEGRADED: no flow fused for health.flow_timeout_s
  kNoRange = 1u << 2,            ///< DEGRADED: no range fused for health.range_timeout_s
  kNoBaro = 1u << 3,             ///< DEGRADED: no baro fused for health.baro_timeout_s
  kPositionUncertain = 1u << 4,  ///< DEGRADED / LOST: horizontal position sigma over a limit
  kVelocityUncertain = 1u << 5,  ///< DEGRADED / LOST: velocity sigma over a limit
  kImuGap = 1u << 6,             ///< DEGRADED: an IMU gap within health.imu_gap_recovery_s
  kImuStopped = 1u << 7,         ///< LOST: other sensors run imu_lost_s ahead of the IMU
  kHeightUncertain = 1u << 8,    ///< DEGRADED / LOST: vertical position sigma over a limit
};
/// "no_flow|no_range" for a reasons bit set ("" for none).
std::string health_reasons_text(uint32_t reasons);

/// Error-state layout (Sola 2017, 5.3): the order of the covariance's rows and columns.
namespace idx {
constexpr int kP = 0;         ///< position p_W_B [m]
constexpr int kV = 3;         ///< velocity v_W_B [m/s]
constexpr int kTheta = 6;     ///< attitude error, local (body) frame: q = q_nominal (x) Exp(dtheta)
constexpr int kBa = 9;        ///< accelerometer bias [m/s^2], body
constexpr int kBg = 12;       ///< gyro bias [rad/s], body
constexpr int kBaro = 15;     ///< baro offset [m]: baro altitude = p_z + offset
constexpr int kTerrain = 16;  ///< terrain height under the rangefinder h_W_terrain [m]
constexpr int kTopV = 17;     ///< horizontal velocity of the top under the rangefinder [m/s], W
constexpr int kCore = 19;     ///< dimension without clones
}  // namespace idx

using CoreMatrix = Eigen::Matrix<double, idx::kCore, idx::kCore>;

/// The estimate at the newest IMU sample.
struct State {
  int64_t utime = 0;  ///< the newest IMU sample fused (0 before initialisation)
  bool initialised = false;
  Vector3d p_W_B = Vector3d::Zero();
  Vector3d v_W_B = Vector3d::Zero();
  Quaterniond q_WB = Quaterniond::Identity();
  Vector3d accel_bias_B = Vector3d::Zero();  ///< [m/s^2]
  Vector3d gyro_bias_B = Vector3d::Zero();   ///< [rad/s]
  double baro_offset_m = 0.0;                ///< baro altitude minus p_z
  double terrain_height_m = 0.0;             ///< h_W_terrain: surface under the rangefinder
  /// The horizontal velocity of that surface when it is a moving top ([m/s], W; README, "The
  /// top's velocity"), and whether the flow has shown it to move.
  Eigen::Vector2d top_velocity_W = Eigen::Vector2d::Zero();
  bool top_moving = false;
  CoreMatrix cov = CoreMatrix::Zero();  ///< error-state covariance in the idx:: order

  Matrix3d cov_p() const { return cov.block<3, 3>(idx::kP, idx::kP); }  ///< [m^2]
  Matrix3d cov_v() const { return cov.block<3, 3>(idx::kV, idx::kV); }  ///< [m^2/s^2]
  Matrix3d cov_attitude() const { return cov.block<3, 3>(idx::kTheta, idx::kTheta); }  ///< rad^2

  Health health = Health::kLost;
  uint32_t health_reasons = kNotInitialised;
  Counters counters;
};

}  // namespace alight::estimator
