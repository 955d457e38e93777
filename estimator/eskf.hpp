#pragma once
// The error-state Kalman filter's mathematics, without bookkeeping: nominal state, error-state
// covariance with stochastic clones, IMU propagation, the generic update with its chi-square gate,
// injection and reset, and the three measurement models with their Jacobians.
//
// Reference: J. Sola, "Quaternion kinematics for the error-state Kalman filter", 2017
// (arXiv:1711.02508): nominal kinematics eq. 260, error-state transition eqs. 269-270 with the
// attitude error in the local frame (q = q_nominal (x) Exp(dtheta)), process noise 5.4.3, injection
// 6.2 and reset 6.3 (eq. 287). Stochastic cloning: S. Roumeliotis and J. Burdick, "Stochastic
// cloning: a generalized framework for processing relative state measurements", ICRA 2002.
// The terrain state and its speed-scaled process noise are ideas from PX4's ECL/EKF2 (no code).

#include <array>
#include <cstdint>

#include "estimator/params.hpp"
#include "estimator/types.hpp"

namespace alight::estimator {

/// Flow samples in flight at once (each holds a 6-dim clone of p and attitude at utime_from).
constexpr int kMaxClones = 3;
constexpr int kCloneDim = 6;
constexpr int kMaxDim = idx::kCore + kMaxClones * kCloneDim;

/// The platforms a landing follows move at up to 1 m/s and turn at up to 15 deg/s (autonomy's
/// moving landing holds beyond what the vehicle can follow): a top's horizontal acceleration is
/// then at most 1 m/s x 0.26 rad/s. Its velocity state walks at that rate per root second, so a
/// top seen only relative to the camera is trusted for its motion about as long as it cannot
/// have changed it.
constexpr double kTopAccelMps2 = 0.26;
/// A deck rolling and pitching by 3 deg at up to 0.5 Hz turns at up to 0.16 rad/s.
constexpr double kTopRateRadps = 0.16;
/// A top's velocity is at most that fast: its state starts with this sigma, and starts over
/// (uncorrelated, zero, not moving) when its sigma has walked past it unobserved.
constexpr double kTopMaxSpeedMps = 1.0;

/// Dynamic size with fixed capacity: no heap allocation, copies only the active part.
using Cov = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxDim, kMaxDim>;
using ErrVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxDim, 1>;
using MeasJac = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, kMaxDim>;
using MeasVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1>;
using MeasCov = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3>;
using CoreRow = Eigen::Matrix<double, 1, idx::kCore>;

struct Nominal {
  Vector3d p_W_B = Vector3d::Zero();
  Vector3d v_W_B = Vector3d::Zero();
  Quaterniond q_WB = Quaterniond::Identity();
  Vector3d accel_bias_B = Vector3d::Zero();
  Vector3d gyro_bias_B = Vector3d::Zero();
  double baro_offset_m = 0.0;
  double terrain_m = 0.0;
  Vector2d top_v_W = Vector2d::Zero();  ///< horizontal velocity of the terrain's top [m/s]
};

/// p_W_B and q_WB frozen at a flow sample's first exposure; its error is (dp, dtheta) in P.
struct Clone {
  int64_t key = 0;  ///< the flow sample it belongs to
  int64_t utime = 0;
  Vector3d p_W_B = Vector3d::Zero();
  Quaterniond q_WB = Quaterniond::Identity();
};

/// The latest range readings, fused or refused by a gate (the chi-square or the step gate): the
/// platform-step detector's memory. Cleared by a terrain reset.
struct RangeStreak {
  static constexpr int kCapacity = 32;
  int count = 0;  ///< entries held (at most kCapacity, the newest)
  int head = 0;   ///< next slot
  std::array<int64_t, kCapacity> utime{};
  std::array<double, kCapacity> implied_terrain_m{};
  std::array<bool, kCapacity> refused{};

  void clear() { count = 0, head = 0; }
  void add(int64_t t, double h, bool was_refused);
};

/// Everything the estimate depends on: what a history checkpoint holds and a replay restores.
struct FilterState {
  int64_t utime = 0;
  Nominal x;
  Cov P;  ///< (kCore + kCloneDim * n_clones) square
  std::array<Clone, kMaxClones> clones{};
  int n_clones = 0;
  bool baro_initialised = false;
  RangeStreak range_streak;
  std::array<int64_t, kSensorCount> last_fused_utime{};  ///< per sensor, for health
  std::array<Outcome, kSensorCount> last_outcome{};      ///< of the latest update per sensor
  int64_t last_imu_gap_utime = 0;                        ///< end of the latest IMU gap (0: none)
  int64_t terrain_resets = 0;
  int64_t flow_on_floor = 0;           ///< flow samples judged against the floor, not the terrain
  int64_t flow_gated_since_utime = 0;  ///< first of the flow's current run of refusals (0: none)
  int64_t flow_gated_last_utime = 0;   ///< latest of that run
  int64_t flow_inflated = 0;  ///< flow samples fused with their noise inflated after a run refused
  int64_t flow_second = 0;    ///< flow samples fused on the front end's second motion
  int64_t flow_top = 0;       ///< flow samples fused relative to a moving top
  /// The flow has shown the top under the rangefinder to move (Estimator::apply_flow): its
  /// single-motion samples over the top are judged relative to it.
  bool top_moving = false;
  /// The latest refused flow sample's implied horizontal velocity error and its covariance
  /// (Estimator::reset_velocity_to_flow); utime 0: none since the last fused or reset.
  int64_t flow_refused_utime = 0;
  Vector2d flow_refused_dv = Vector2d::Zero();
  Eigen::Matrix2d flow_refused_cov = Eigen::Matrix2d::Zero();
  int64_t flow_velocity_resets = 0;    ///< horizontal velocity set to the flow's
  int64_t baro_gated_since_utime = 0;  ///< first of the baro's current run of refusals (0: none)
  int64_t baro_resets = 0;

  int dim() const { return idx::kCore + kCloneDim * n_clones; }
  int clone_index(int64_t key) const;  ///< -1 when absent
};

/// ISA barometric formula (troposphere): altitude above the 101325 Pa level [m].
double isa_altitude_m(double pressure_pa);
/// Its inverse, for tests and simulators.
double isa_pressure_pa(double altitude_m);

/// Sola eq. 260 and 269-270 over dt with one IMU sample (zero-order hold over the interval).
void propagate(FilterState& s, const Vector3d& accel_B, const Vector3d& gyro_B, double dt_s,
               const EstimatorParams& params);

/// The transition matrix of the core error state over dt (exposed for tests).
CoreMatrix transition_matrix(const Nominal& x, const Vector3d& accel_B, const Vector3d& gyro_B,
                             double dt_s);

/// Applies residual r = z - h(x) with Jacobian H (rows of the error state) and noise R when the
/// normalised innovation squared r' S^-1 r is within gate_chi2: Kalman update, injection into the
/// nominal state (and clones), reset of the covariance. kGate or kNumerical leave s unchanged.
/// heading_unobservable: the update does not touch the heading nor the gyro bias about the
/// vertical (true of every sensor here: none measures the heading).
Outcome fuse(FilterState& s, const MeasVec& r, const MeasJac& H, const MeasCov& R, double gate_chi2,
             double* nis = nullptr, bool heading_unobservable = true);

/// Injects an error-state correction (Sola 6.2) and resets P (6.3, eq. 287).
void inject(FilterState& s, const ErrVec& dx);

/// Appends a clone of the current p and attitude (covariance augmented with their correlations).
/// False when kMaxClones are held.
bool add_clone(FilterState& s, int64_t key);
void remove_clone(FilterState& s, int index);

/// Rangefinder at t_B_R with unit beam d_B over a horizontal surface at the terrain height.
struct RangeModel {
  double range_m = 0.0;   ///< predicted distance along the beam
  double cos_tilt = 1.0;  ///< cosine of the beam's angle from straight down
  CoreRow H = CoreRow::Zero();
};
RangeModel range_model(const Nominal& x, const Vector3d& t_B_R, const Vector3d& d_B);
/// Terrain height that a measured range implies, and its Jacobian (row over the core state).
double implied_terrain_m(const Nominal& x, const Vector3d& t_B_R, const Vector3d& d_B,
                         double range_m, CoreRow* J = nullptr);

/// Flow: t_over_d = R_CB R_WB1^T (p_W_C2 - p_W_C1) / (z of camera 1 above the terrain); with
/// `top_dt_s` > 0, the camera's motion relative to the terrain's top moving at top_v_W over that
/// interval: (p_W_C2 - p_W_C1 - (top_v_W, 0) top_dt_s) instead.
struct FlowModel {
  Vector3d t_over_d = Vector3d::Zero();
  double height_m = 0.0;  ///< camera 1 above the terrain
  Eigen::Matrix<double, 3, idx::kCore> H_core = Eigen::Matrix<double, 3, idx::kCore>::Zero();
  Eigen::Matrix<double, 3, kCloneDim> H_clone = Eigen::Matrix<double, 3, kCloneDim>::Zero();
};
FlowModel flow_model(const Nominal& x, const Clone& c, const Matrix3d& R_BC, const Vector3d& t_B_C,
                     double top_dt_s = 0.0);
/// Adds to the Jacobians what the front end's inputs R_C2C1 and n_C1, computed from the
/// estimate (the clone's attitude and the current one), carry of the attitude errors: the
/// measurement is z = u + J_rotation theta + J_normal delta with theta = R_CB (R1^T R2 dtheta2 -
/// dtheta1) and delta = -R_CB [R1^T e_z]x dtheta1 (the inputs' errors against the truth).
void add_input_sensitivities(FlowModel& m, const Nominal& x, const Clone& c, const Matrix3d& R_BC,
                             const Matrix3d& J_rotation, const Matrix3d& J_normal);

/// exp map of a rotation vector (Sola eq. 101).
Quaterniond quat_exp(const Vector3d& theta);

}  // namespace alight::estimator
