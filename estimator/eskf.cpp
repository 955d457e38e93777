#include "estimator/eskf.hpp"

#include <Eigen/Cholesky>
#include <cassert>
#include <cmath>

#include "common/geometry.hpp"

namespace alight::estimator {

namespace {
// ISA troposphere: T0 = 288.15 K, lapse rate 0.0065 K/m, p0 = 101325 Pa; the exponent is
// R L / (g M) = 8.31446 * 0.0065 / (9.80665 * 0.0289644).
constexpr double kIsaP0 = 101325.0;
constexpr double kIsaT0OverL = 288.15 / 0.0065;
constexpr double kIsaExponent = 0.190263;
}  // namespace

void RangeStreak::add(int64_t t, double h, bool was_refused) {
  utime[head] = t;
  implied_terrain_m[head] = h;
  refused[head] = was_refused;
  head = (head + 1) % kCapacity;
  if (count < kCapacity) ++count;
}

int FilterState::clone_index(int64_t key) const {
  for (int i = 0; i < n_clones; ++i)
    if (clones[i].key == key) return i;
  return -1;
}

double isa_altitude_m(double pressure_pa) {
  return kIsaT0OverL * (1.0 - std::pow(pressure_pa / kIsaP0, kIsaExponent));
}

double isa_pressure_pa(double altitude_m) {
  return kIsaP0 * std::pow(1.0 - altitude_m / kIsaT0OverL, 1.0 / kIsaExponent);
}

Quaterniond quat_exp(const Vector3d& theta) {
  const double angle = theta.norm();
  if (angle < 1e-12) return Quaterniond(1.0, 0.5 * theta.x(), 0.5 * theta.y(), 0.5 * theta.z());
  const Vector3d axis = theta / angle;
  const double s = std::sin(0.5 * angle);
  return Quaterniond(std::cos(0.5 * angle), s * axis.x(), s * axis.y(), s * axis.z());
}

CoreMatrix transition_matrix(const Nominal& x, const Vector3d& accel_B, const Vector3d& gyro_B,
                             double dt_s) {
  const Matrix3d R = x.q_WB.toRotationMatrix();
  const Vector3d a = accel_B - x.accel_bias_B;
  const Vector3d w = gyro_B - x.gyro_bias_B;
  CoreMatrix F = CoreMatrix::Identity();
  F.block<3, 3>(idx::kP, idx::kV) = Matrix3d::Identity() * dt_s;
  F.block<3, 3>(idx::kV, idx::kTheta) = -R * skew(a) * dt_s;
  F.block<3, 3>(idx::kV, idx::kBa) = -R * dt_s;
  F.block<3, 3>(idx::kTheta, idx::kTheta) = quat_exp(w * dt_s).toRotationMatrix().transpose();
  F.block<3, 3>(idx::kTheta, idx::kBg) = -Matrix3d::Identity() * dt_s;
  return F;
}

void propagate(FilterState& s, const Vector3d& accel_B, const Vector3d& gyro_B, double dt_s,
               const EstimatorParams& params) {
  const CoreMatrix F = transition_matrix(s.x, accel_B, gyro_B, dt_s);

  // Process noise (Sola 5.4.3): densities integrated over dt.
  const auto& n = params.imu;
  Eigen::Matrix<double, idx::kCore, 1> q = Eigen::Matrix<double, idx::kCore, 1>::Zero();
  q.segment<3>(idx::kV).setConstant(n.accel_noise_density * n.accel_noise_density * dt_s);
  q.segment<3>(idx::kTheta).setConstant(n.gyro_noise_density * n.gyro_noise_density * dt_s);
  q.segment<3>(idx::kBa).setConstant(n.accel_bias_rw * n.accel_bias_rw * dt_s);
  q.segment<3>(idx::kBg).setConstant(n.gyro_bias_rw * n.gyro_bias_rw * dt_s);
  q[idx::kBaro] = params.baro.offset_rw * params.baro.offset_rw * dt_s;
  // The terrain under a moving vehicle changes with the distance flown (PX4 ECL's idea): its
  // random walk grows with horizontal speed.
  const double slope_mps = params.range.terrain_gradient * s.x.v_W_B.head<2>().norm();
  q[idx::kTerrain] =
      (params.range.terrain_rw * params.range.terrain_rw + slope_mps * slope_mps) * dt_s;
  q.segment<2>(idx::kTopV).setConstant(kTopAccelMps2 * kTopAccelMps2 * dt_s);

  const int n_dim = s.dim();
  const int n_x = n_dim - idx::kCore;
  const CoreMatrix Pcc = s.P.topLeftCorner<idx::kCore, idx::kCore>();
  s.P.topLeftCorner<idx::kCore, idx::kCore>() = F * Pcc * F.transpose();
  s.P.topLeftCorner<idx::kCore, idx::kCore>().diagonal() += q;
  // A top's velocity unobserved for long is no longer known at all: it starts over.
  if (s.P(idx::kTopV, idx::kTopV) + s.P(idx::kTopV + 1, idx::kTopV + 1) >
      2 * kTopMaxSpeedMps * kTopMaxSpeedMps) {
    s.P.middleRows<2>(idx::kTopV).setZero();
    s.P.middleCols<2>(idx::kTopV).setZero();
    s.P.block<2, 2>(idx::kTopV, idx::kTopV)
        .diagonal()
        .setConstant(kTopMaxSpeedMps * kTopMaxSpeedMps);
    s.x.top_v_W.setZero();
    s.top_moving = false;
  }
  if (n_x > 0) {
    // Clones are constant: only their correlation with the core moves.
    const Eigen::Matrix<double, idx::kCore, Eigen::Dynamic, 0, idx::kCore, kMaxDim> Pcx =
        s.P.topRightCorner(idx::kCore, n_x);
    s.P.topRightCorner(idx::kCore, n_x) = F.lazyProduct(Pcx);
    s.P.bottomLeftCorner(n_x, idx::kCore) = s.P.topRightCorner(idx::kCore, n_x).transpose();
  }

  // Nominal kinematics (Sola eq. 260). The specific force, a mean over the interval, is rotated
  // with the attitude at the interval's middle: second order in the rotation, for free.
  const Quaterniond dq = quat_exp((gyro_B - s.x.gyro_bias_B) * dt_s);
  const Quaterniond q_mid = s.x.q_WB * quat_exp(0.5 * (gyro_B - s.x.gyro_bias_B) * dt_s);
  const Vector3d a_W =
      q_mid * (accel_B - s.x.accel_bias_B) + Vector3d(0.0, 0.0, -params.gravity_mps2);
  s.x.p_W_B += s.x.v_W_B * dt_s + 0.5 * a_W * dt_s * dt_s;
  s.x.v_W_B += a_W * dt_s;
  s.x.q_WB = (s.x.q_WB * dq).normalized();
}

void inject(FilterState& s, const ErrVec& dx) {
  s.x.p_W_B += dx.segment<3>(idx::kP);
  s.x.v_W_B += dx.segment<3>(idx::kV);
  s.x.q_WB = (s.x.q_WB * quat_exp(dx.segment<3>(idx::kTheta))).normalized();
  s.x.accel_bias_B += dx.segment<3>(idx::kBa);
  s.x.gyro_bias_B += dx.segment<3>(idx::kBg);
  s.x.baro_offset_m += dx[idx::kBaro];
  s.x.terrain_m += dx[idx::kTerrain];
  s.x.top_v_W += dx.segment<2>(idx::kTopV);
  for (int i = 0; i < s.n_clones; ++i) {
    const int o = idx::kCore + kCloneDim * i;
    s.clones[i].p_W_B += dx.segment<3>(o);
    s.clones[i].q_WB = (s.clones[i].q_WB * quat_exp(dx.segment<3>(o + 3))).normalized();
  }
  // Reset (Sola eq. 287): the attitude errors are re-expressed about the corrected nominal,
  // G = I - [dtheta / 2]x on each attitude block.
  auto reset_block = [&s](int o, const Vector3d& dtheta) {
    const Matrix3d G = Matrix3d::Identity() - 0.5 * skew(dtheta);
    s.P.middleRows(o, 3) = (G * s.P.middleRows(o, 3)).eval();
    s.P.middleCols(o, 3) = (s.P.middleCols(o, 3) * G.transpose()).eval();
  };
  reset_block(idx::kTheta, dx.segment<3>(idx::kTheta));
  for (int i = 0; i < s.n_clones; ++i) {
    const int o = idx::kCore + kCloneDim * i + 3;
    reset_block(o, dx.segment<3>(o));
  }
}

Outcome fuse(FilterState& s, const MeasVec& r, const MeasJac& H, const MeasCov& R, double gate_chi2,
             double* nis, bool heading_unobservable) {
  const int n = s.dim();
  const int m = static_cast<int>(r.size());
  assert(H.rows() == m && H.cols() == n && R.rows() == m && R.cols() == m);
  // Small products: coefficient-wise (lazyProduct) beats the blocked GEMM at these sizes.
  const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxDim, 3> PHt =
      s.P.lazyProduct(H.transpose());
  MeasCov S = H.lazyProduct(PHt) + R;
  S = (0.5 * (S + S.transpose())).eval();
  const Eigen::LLT<MeasCov> llt(S);
  if (llt.info() != Eigen::Success || !S.allFinite()) return Outcome::kNumerical;
  const double d2 = r.dot(llt.solve(r));
  if (nis) *nis = d2;
  if (!std::isfinite(d2)) return Outcome::kNumerical;
  if (d2 > gate_chi2) return Outcome::kGate;

  // K = P H^T S^-1, computed as (S^-1 (P H^T)^T)^T.
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxDim, 3> K =
      llt.solve(PHt.transpose()).transpose();
  if (heading_unobservable) {
    // No sensor here measures the heading, yet the EKF's linearisation at changing estimates
    // hands it spurious information through the correlations (Huang, Mourikis, Roumeliotis 2010;
    // Hesch et al. 2014), and the heading and the gyro bias about the vertical then wander far
    // beyond their variance. So the update leaves the heading alone, a consider (Schmidt) update
    // of that direction. The heading is one direction of the whole state: turning the world about
    // the vertical (through W's origin, the take-off spot) by an angle turns the attitude (core
    // and clones) and also swings the positions and the velocity about it. Its gain is removed
    // along that whole direction N, not from the attitude alone: removing only the attitude's
    // part left the positions' part, and every flow update then shifted them (a few mm, all the
    // same way: 0.4 m after a 40 m square) as if the heading had changed while it had not. The
    // gyro bias about the vertical is dropped on its own.
    const Vector3d e_z = Vector3d::UnitZ();
    const Matrix3d R_WB = s.x.q_WB.toRotationMatrix();
    ErrVec N = ErrVec::Zero(n);
    N.segment<3>(idx::kP) = e_z.cross(s.x.p_W_B);
    N.segment<3>(idx::kV) = e_z.cross(s.x.v_W_B);
    N.segment<3>(idx::kTheta) = R_WB.transpose() * e_z;
    N.segment<2>(idx::kTopV) = Vector2d(-s.x.top_v_W.y(), s.x.top_v_W.x());  // e_z x (v, 0)
    for (int i = 0; i < s.n_clones; ++i) {
      const int c = idx::kCore + kCloneDim * i;
      N.segment<3>(c) = e_z.cross(s.clones[i].p_W_B);
      N.segment<3>(c + 3) = s.clones[i].q_WB.toRotationMatrix().transpose() * e_z;
    }
    // The heading part of the gain (its attitude rows along the body's vertical; N's is 1).
    const Eigen::Matrix<double, 1, Eigen::Dynamic, Eigen::RowMajor, 1, 3> heading =
        N.segment<3>(idx::kTheta).transpose() * K.middleRows(idx::kTheta, 3);
    K -= N * heading;
    const Vector3d u = R_WB.transpose().col(2);
    K.middleRows(idx::kBg, 3) =
        ((Matrix3d::Identity() - u * u.transpose()) * K.middleRows(idx::kBg, 3)).eval();
  }
  const ErrVec dx = K.lazyProduct(r);
  if (!dx.allFinite()) return Outcome::kNumerical;
  // Joseph's form expanded, valid for any gain: P - K H P - P H^T K^T + K S K^T.
  const Cov KPH = K.lazyProduct(PHt.transpose());
  Cov P = s.P - KPH - KPH.transpose() + K.lazyProduct(S).lazyProduct(K.transpose());
  P = (0.5 * (P + P.transpose())).eval();
  if (!P.allFinite() || (P.diagonal().array() < 0).any()) return Outcome::kNumerical;
  s.P = P;
  inject(s, dx);
  return Outcome::kFused;
}

bool add_clone(FilterState& s, int64_t key) {
  if (s.n_clones >= kMaxClones) return false;
  const int n = s.dim();
  const int m = n + kCloneDim;
  // J picks p (rows 0-2) and dtheta (rows 6-8): the new rows are J P, the new block J P J^T.
  Eigen::Matrix<double, kCloneDim, Eigen::Dynamic, 0, kCloneDim, kMaxDim> JP(kCloneDim, n);
  JP.topRows<3>() = s.P.middleRows(idx::kP, 3);
  JP.bottomRows<3>() = s.P.middleRows(idx::kTheta, 3);
  Cov P(m, m);
  P.topLeftCorner(n, n) = s.P;
  P.bottomLeftCorner(kCloneDim, n) = JP;
  P.topRightCorner(n, kCloneDim) = JP.transpose();
  P.block<3, 3>(n, n) = JP.block<3, 3>(0, idx::kP);
  P.block<3, 3>(n, n + 3) = JP.block<3, 3>(0, idx::kTheta);
  P.block<3, 3>(n + 3, n) = JP.block<3, 3>(3, idx::kP);
  P.block<3, 3>(n + 3, n + 3) = JP.block<3, 3>(3, idx::kTheta);
  s.P = P;
  Clone& c = s.clones[s.n_clones++];
  c.key = key;
  c.utime = s.utime;
  c.p_W_B = s.x.p_W_B;
  c.q_WB = s.x.q_WB;
  return true;
}

void remove_clone(FilterState& s, int index) {
  assert(index >= 0 && index < s.n_clones);
  const int n = s.dim();
  const int o = idx::kCore + kCloneDim * index;
  const int tail = n - o - kCloneDim;
  Cov P(n - kCloneDim, n - kCloneDim);
  P.topLeftCorner(o, o) = s.P.topLeftCorner(o, o);
  if (tail > 0) {
    P.topRightCorner(o, tail) = s.P.topRightCorner(o, tail);
    P.bottomLeftCorner(tail, o) = s.P.bottomLeftCorner(tail, o);
    P.bottomRightCorner(tail, tail) = s.P.bottomRightCorner(tail, tail);
  }
  s.P = P;
  for (int i = index; i + 1 < s.n_clones; ++i) s.clones[i] = s.clones[i + 1];
  --s.n_clones;
}

RangeModel range_model(const Nominal& x, const Vector3d& t_B_R, const Vector3d& d_B) {
  const Matrix3d R = x.q_WB.toRotationMatrix();
  RangeModel m;
  m.cos_tilt = -(R * d_B).z();
  const double height = x.p_W_B.z() + (R * t_B_R).z() - x.terrain_m;
  m.range_m = height / m.cos_tilt;
  // d(R v)/d(dtheta) = -R [v]x for the local attitude error.
  const Eigen::RowVector3d dheight_dtheta = -(R * skew(t_B_R)).row(2);
  const Eigen::RowVector3d dcos_dtheta = (R * skew(d_B)).row(2);
  m.H(idx::kP + 2) = 1.0 / m.cos_tilt;
  m.H(idx::kTerrain) = -1.0 / m.cos_tilt;
  m.H.segment<3>(idx::kTheta) =
      dheight_dtheta / m.cos_tilt - height / (m.cos_tilt * m.cos_tilt) * dcos_dtheta;
  return m;
}

double implied_terrain_m(const Nominal& x, const Vector3d& t_B_R, const Vector3d& d_B,
                         double range_m, CoreRow* J) {
  const Matrix3d R = x.q_WB.toRotationMatrix();
  const double cos_tilt = -(R * d_B).z();
  if (J) {
    J->setZero();
    (*J)(idx::kP + 2) = 1.0;
    J->segment<3>(idx::kTheta) = -(R * skew(t_B_R)).row(2) - range_m * (R * skew(d_B)).row(2);
  }
  return x.p_W_B.z() + (R * t_B_R).z() - range_m * cos_tilt;
}

FlowModel flow_model(const Nominal& x, const Clone& c, const Matrix3d& R_BC, const Vector3d& t_B_C,
                     double top_dt_s) {
  const Matrix3d R1 = c.q_WB.toRotationMatrix();
  const Matrix3d R2 = x.q_WB.toRotationMatrix();
  const Matrix3d R_CB = R_BC.transpose();
  const Vector3d top_W(x.top_v_W.x() * top_dt_s, x.top_v_W.y() * top_dt_s, 0.0);
  const Vector3d delta_W = x.p_W_B + R2 * t_B_C - c.p_W_B - R1 * t_B_C - top_W;
  const Vector3d delta_B1 = R1.transpose() * delta_W;
  const Vector3d u = R_CB * delta_B1;
  FlowModel m;
  m.height_m = c.p_W_B.z() + (R1 * t_B_C).z() - x.terrain_m;
  const double d = m.height_m;
  m.t_over_d = u / d;

  // z = u / d: dz = du / d - u / d^2 dd.
  const Matrix3d du_dp2 = R_CB * R1.transpose();
  const Matrix3d du_dtheta2 = -R_CB * R1.transpose() * R2 * skew(t_B_C);
  const Matrix3d du_dp1 = -du_dp2;
  const Matrix3d du_dtheta1 = R_CB * (skew(delta_B1) + skew(t_B_C));
  const Eigen::RowVector3d dd_dp1(0.0, 0.0, 1.0);
  const Eigen::RowVector3d dd_dtheta1 = -(R1 * skew(t_B_C)).row(2);
  const Vector3d z_over_d = m.t_over_d / d;

  m.H_core.block<3, 3>(0, idx::kP) = du_dp2 / d;
  m.H_core.block<3, 3>(0, idx::kTheta) = du_dtheta2 / d;
  m.H_core.col(idx::kTerrain) = z_over_d;  // dd/dterrain = -1
  if (top_dt_s > 0) m.H_core.block<3, 2>(0, idx::kTopV) = -du_dp2.leftCols<2>() * top_dt_s / d;
  m.H_clone.block<3, 3>(0, 0) = du_dp1 / d - z_over_d * dd_dp1;
  m.H_clone.block<3, 3>(0, 3) = du_dtheta1 / d - z_over_d * dd_dtheta1;
  return m;
}

void add_input_sensitivities(FlowModel& m, const Nominal& x, const Clone& c, const Matrix3d& R_BC,
                             const Matrix3d& J_rotation, const Matrix3d& J_normal) {
  const Matrix3d R1 = c.q_WB.toRotationMatrix();
  const Matrix3d R2 = x.q_WB.toRotationMatrix();
  const Matrix3d R_CB = R_BC.transpose();
  // R_C2C1 from estimates R^_i = R_i Exp(-dtheta_i) is the true one times
  // Exp(R_CB (R1^T R2 dtheta2 - dtheta1)); n_C1 = R_CB R^_1^T e_z is the true one minus
  // R_CB [R1^T e_z]x dtheta1.
  m.H_core.block<3, 3>(0, idx::kTheta) += J_rotation * R_CB * R1.transpose() * R2;
  m.H_clone.block<3, 3>(0, 3) += -J_rotation * R_CB - J_normal * R_CB * skew(R1.transpose().col(2));
}

}  // namespace alight::estimator
