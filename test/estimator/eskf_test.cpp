// The filter's mathematics against finite differences and known values: measurement Jacobians,
// the transition matrix, clones, the gate, the ISA formula.

#include "estimator/eskf.hpp"

#include <gtest/gtest.h>

#include <random>

#include "common/geometry.hpp"

namespace alight::estimator {
namespace {

Vector3d test_log(const Quaterniond& q) {
  const Eigen::AngleAxisd aa(q);
  return aa.angle() * aa.axis();
}

Nominal some_state() {
  Nominal x;
  x.p_W_B = Vector3d(0.3, -0.7, 1.6);
  x.v_W_B = Vector3d(0.4, 0.2, -0.1);
  x.q_WB = Quaterniond(rotation_from_rpy(0.1, -0.15, 0.8));
  x.accel_bias_B = Vector3d(0.05, -0.03, 0.02);
  x.gyro_bias_B = Vector3d(0.001, -0.002, 0.003);
  x.baro_offset_m = 12.0;
  x.terrain_m = 0.2;
  x.top_v_W = Vector2d(0.3, -0.2);
  return x;
}

/// The nominal state moved by a core error-state vector (the estimator's injection).
Nominal perturbed(const Nominal& x, int i, double eps) {
  FilterState s;
  s.x = x;
  s.P = Cov::Identity(idx::kCore, idx::kCore);
  ErrVec dx = ErrVec::Zero(idx::kCore);
  dx[i] = eps;
  inject(s, dx);
  return s.x;
}

TEST(EskfTest, RangeJacobianMatchesFiniteDifferences) {
  const Nominal x = some_state();
  const Vector3d t_B_R(0.05, 0.02, -0.05), d_B = Vector3d(0.1, 0.0, -1.0).normalized();
  const RangeModel m = range_model(x, t_B_R, d_B);
  for (int i = 0; i < idx::kCore; ++i) {
    const double eps = 1e-6;
    const double plus = range_model(perturbed(x, i, eps), t_B_R, d_B).range_m;
    const double minus = range_model(perturbed(x, i, -eps), t_B_R, d_B).range_m;
    EXPECT_NEAR(m.H(i), (plus - minus) / (2 * eps), 1e-6) << "column " << i;
  }
}

TEST(EskfTest, RangeOfALevelVehicleIsItsHeightAboveTheTerrain) {
  Nominal x;
  x.p_W_B = Vector3d(1, 2, 1.5);
  x.terrain_m = 0.4;
  const RangeModel m = range_model(x, Vector3d(0, 0, -0.05), Vector3d(0, 0, -1));
  EXPECT_NEAR(m.range_m, 1.5 - 0.05 - 0.4, 1e-12);
  EXPECT_NEAR(m.cos_tilt, 1.0, 1e-12);
  EXPECT_NEAR(implied_terrain_m(x, Vector3d(0, 0, -0.05), Vector3d(0, 0, -1), 1.05), 0.4, 1e-12);
}

TEST(EskfTest, ImpliedTerrainJacobianMatchesFiniteDifferences) {
  const Nominal x = some_state();
  const Vector3d t_B_R(0.05, 0.02, -0.05), d_B(0, 0, -1);
  CoreRow J;
  implied_terrain_m(x, t_B_R, d_B, 1.3, &J);
  for (int i = 0; i < idx::kCore; ++i) {
    const double eps = 1e-6;
    const double d = implied_terrain_m(perturbed(x, i, eps), t_B_R, d_B, 1.3) -
                     implied_terrain_m(perturbed(x, i, -eps), t_B_R, d_B, 1.3);
    EXPECT_NEAR(J(i), d / (2 * eps), 1e-6) << "column " << i;
  }
}

TEST(EskfTest, FlowJacobiansMatchFiniteDifferences) {
  // Over a still plane, and relative to a top moving at top_v_W over a frame interval.
  const Nominal x = some_state();
  Clone c;
  c.p_W_B = x.p_W_B - Vector3d(0.03, 0.01, -0.005);
  c.q_WB = Quaterniond(rotation_from_rpy(0.08, -0.12, 0.78));
  const Matrix3d R_BC = R_BC_downward();
  const Vector3d t_B_C(0.1, -0.02, -0.06);
  for (const double top_dt : {0.0, 1.0 / 30}) {
    const FlowModel m = flow_model(x, c, R_BC, t_B_C, top_dt);
    const double eps = 1e-6;
    for (int i = 0; i < idx::kCore; ++i) {
      const Vector3d d = flow_model(perturbed(x, i, eps), c, R_BC, t_B_C, top_dt).t_over_d -
                         flow_model(perturbed(x, i, -eps), c, R_BC, t_B_C, top_dt).t_over_d;
      EXPECT_TRUE(m.H_core.col(i).isApprox(d / (2 * eps), 1e-5) ||
                  (m.H_core.col(i) - d / (2 * eps)).norm() < 1e-7)
          << "top_dt " << top_dt << " core column " << i << ": " << m.H_core.col(i).transpose()
          << " vs " << (d / (2 * eps)).transpose();
    }
    for (int i = 0; i < kCloneDim; ++i) {
      auto moved = [&](double e) {
        Clone cc = c;
        if (i < 3)
          cc.p_W_B[i] += e;
        else
          cc.q_WB = cc.q_WB * quat_exp(Vector3d::Unit(i - 3) * e);
        return flow_model(x, cc, R_BC, t_B_C, top_dt).t_over_d;
      };
      const Vector3d d = (moved(eps) - moved(-eps)) / (2 * eps);
      EXPECT_LT((m.H_clone.col(i) - d).norm(), 1e-6 * std::max(1.0, d.norm()))
          << "top_dt " << top_dt << " clone column " << i;
    }
  }
}

TEST(EskfTest, FlowRelativeToAMovingTopIsTheCamerasMotionLessTheTops) {
  // A level camera 1 m over a top that moves with it: no motion relative to the top.
  Nominal x;
  x.p_W_B = Vector3d(0.2, 0, 1.5);
  x.terrain_m = 0.5;
  x.top_v_W = Vector2d(0.6, 0);
  Clone c;
  c.p_W_B = Vector3d(0, 0, 1.5);
  const FlowModel still = flow_model(x, c, R_BC_downward(), Vector3d::Zero());
  const FlowModel with_top = flow_model(x, c, R_BC_downward(), Vector3d::Zero(), 1.0 / 3);
  EXPECT_NEAR(still.t_over_d.norm(), 0.2, 1e-12);
  EXPECT_NEAR(with_top.t_over_d.norm(), 0.0, 1e-12);
  EXPECT_TRUE(still.H_core.middleCols<2>(idx::kTopV).isZero());
}

TEST(EskfTest, FrontEndInputSensitivitiesEnterTheJacobianAsTheEstimateMovesTheInputs) {
  // The front end was given R_C2C1 and n_C1 computed from the estimate; an estimate off by
  // -dx from the truth moves them, and the output by J_rotation theta + J_normal delta. The
  // added Jacobian columns are the derivative of that with respect to the true-minus-estimate dx.
  std::mt19937_64 rng(3);
  std::normal_distribution<double> N;
  Matrix3d J_rot, J_n;
  for (int i = 0; i < 9; ++i) J_rot.data()[i] = N(rng), J_n.data()[i] = N(rng);
  const Matrix3d R_BC = R_BC_downward(), R_CB = R_BC.transpose();
  const Nominal x = some_state();
  Clone c;
  c.p_W_B = x.p_W_B - Vector3d(0.03, 0.01, -0.005);
  c.q_WB = Quaterniond(rotation_from_rpy(0.08, -0.12, 0.78));
  auto inputs_error = [&](const Nominal& x_hat, const Clone& c_hat) {
    const Matrix3d R_true =
        R_CB * x.q_WB.toRotationMatrix().transpose() * c.q_WB.toRotationMatrix() * R_BC;
    const Matrix3d R_used =
        R_CB * x_hat.q_WB.toRotationMatrix().transpose() * c_hat.q_WB.toRotationMatrix() * R_BC;
    const Eigen::AngleAxisd aa(R_true.transpose() * R_used);
    const Vector3d n_true = R_CB * c.q_WB.toRotationMatrix().transpose() * Vector3d::UnitZ();
    const Vector3d n_used = R_CB * c_hat.q_WB.toRotationMatrix().transpose() * Vector3d::UnitZ();
    return Vector3d(J_rot * (aa.angle() * aa.axis()) + J_n * (n_used - n_true));
  };
  const FlowModel plain = flow_model(x, c, R_BC, Vector3d::Zero());
  FlowModel m = plain;
  add_input_sensitivities(m, x, c, R_BC, J_rot, J_n);
  const double eps = 1e-6;
  for (int i = 0; i < 3; ++i) {  // current attitude
    const Vector3d d = (inputs_error(perturbed(x, idx::kTheta + i, eps), c) -
                        inputs_error(perturbed(x, idx::kTheta + i, -eps), c)) /
                       (2 * eps);
    EXPECT_LT((m.H_core.col(idx::kTheta + i) - plain.H_core.col(idx::kTheta + i) + d).norm(), 1e-6);
  }
  for (int i = 0; i < 3; ++i) {  // clone attitude
    auto moved = [&](double e) {
      Clone cc = c;
      cc.q_WB = cc.q_WB * quat_exp(Vector3d::Unit(i) * e);
      return inputs_error(x, cc);
    };
    const Vector3d d = (moved(eps) - moved(-eps)) / (2 * eps);
    EXPECT_LT((m.H_clone.col(3 + i) - plain.H_clone.col(3 + i) + d).norm(), 1e-6);
  }
  EXPECT_EQ(m.H_clone.leftCols<3>(), plain.H_clone.leftCols<3>());
}

TEST(EskfTest, FlowOfAPureTranslationIsTheTranslationOverHeightInCamera1) {
  // Level, heading 0, downward camera at the body origin, 2 m above the floor: moving 0.1 m
  // forward (+x_B) is -0.1 / 2 along y_C (image up is the nose).
  Nominal x;
  x.p_W_B = Vector3d(0.1, 0, 2);
  Clone c;
  c.p_W_B = Vector3d(0, 0, 2);
  const FlowModel m = flow_model(x, c, R_BC_downward(), Vector3d::Zero());
  EXPECT_NEAR(m.height_m, 2.0, 1e-12);
  EXPECT_TRUE(m.t_over_d.isApprox(Vector3d(0, -0.05, 0), 1e-12)) << m.t_over_d.transpose();
}

TEST(EskfTest, TransitionMatrixPredictsHowAnErrorPropagates) {
  // F dx0 ~ (propagated perturbed state) - (propagated state), to first order.
  EstimatorParams params;
  const Nominal x = some_state();
  const Vector3d accel(0.3, -0.2, 9.9), gyro(0.2, -0.3, 0.5);
  const double dt = 0.005;
  const CoreMatrix F = transition_matrix(x, accel, gyro, dt);
  auto run = [&](const Nominal& x0) {
    FilterState s;
    s.x = x0;
    s.P = Cov::Identity(idx::kCore, idx::kCore);
    // A top's velocity known (below kTopMaxSpeedMps), so the propagation keeps it.
    s.P.block<2, 2>(idx::kTopV, idx::kTopV) *= 0.01;
    propagate(s, accel, gyro, dt, params);
    return s.x;
  };
  const Nominal base = run(x);
  for (int i = 0; i < idx::kCore; ++i) {
    const double eps = 1e-6;
    const Nominal moved = run(perturbed(x, i, eps));
    Eigen::Matrix<double, idx::kCore, 1> d;
    d.segment<3>(idx::kP) = moved.p_W_B - base.p_W_B;
    d.segment<3>(idx::kV) = moved.v_W_B - base.v_W_B;
    d.segment<3>(idx::kTheta) = 2.0 * (base.q_WB.conjugate() * moved.q_WB).vec();  // small angle
    d.segment<3>(idx::kBa) = moved.accel_bias_B - base.accel_bias_B;
    d.segment<3>(idx::kBg) = moved.gyro_bias_B - base.gyro_bias_B;
    d[idx::kBaro] = moved.baro_offset_m - base.baro_offset_m;
    d[idx::kTerrain] = moved.terrain_m - base.terrain_m;
    d.segment<2>(idx::kTopV) = moved.top_v_W - base.top_v_W;
    // First-order F: the neglected terms are O(dt^2) (position from v, a; the midpoint rotation).
    EXPECT_LT((F.col(i) - d / eps).norm(), 2e-4) << "column " << i << "\n"
                                                 << F.col(i).transpose() << "\n"
                                                 << (d / eps).transpose();
  }
}

TEST(EskfTest, CloneCopiesPoseAndItsCorrelationsAndRemovalRestoresTheCore) {
  std::mt19937_64 rng(4);
  std::normal_distribution<double> N;
  Eigen::MatrixXd A(idx::kCore, idx::kCore);
  for (int i = 0; i < A.size(); ++i) A.data()[i] = N(rng);
  FilterState s;
  s.x = some_state();
  s.P = A * A.transpose() + Eigen::MatrixXd::Identity(idx::kCore, idx::kCore);
  const Cov P0 = s.P;
  ASSERT_TRUE(add_clone(s, 7));
  ASSERT_EQ(s.dim(), idx::kCore + kCloneDim);
  EXPECT_EQ(s.clone_index(7), 0);
  EXPECT_TRUE(s.P.block(idx::kCore, 0, 3, idx::kCore).isApprox(P0.middleRows(idx::kP, 3)));
  EXPECT_TRUE(s.P.block(idx::kCore + 3, 0, 3, idx::kCore).isApprox(P0.middleRows(idx::kTheta, 3)));
  EXPECT_TRUE(s.P.isApprox(s.P.transpose()));
  ASSERT_TRUE(add_clone(s, 8));
  ASSERT_TRUE(add_clone(s, 9));
  EXPECT_FALSE(add_clone(s, 10));  // kMaxClones
  remove_clone(s, s.clone_index(8));
  EXPECT_EQ(s.clone_index(8), -1);
  EXPECT_EQ(s.clone_index(9), 1);
  remove_clone(s, 0);
  remove_clone(s, 0);
  EXPECT_EQ(s.n_clones, 0);
  EXPECT_TRUE(s.P.isApprox(P0));
}

TEST(EskfTest, GateRefusesAnOutlierAndLeavesTheStateAlone) {
  FilterState s;
  s.x = some_state();
  s.P = Cov::Identity(idx::kCore, idx::kCore) * 0.01;
  const FilterState before = s;
  MeasVec r(1);
  r[0] = 1.0;  // 10 sigma of the prior alone
  MeasJac H = MeasJac::Zero(1, idx::kCore);
  H(0, idx::kP + 2) = 1.0;
  MeasCov R(1, 1);
  R(0, 0) = 1e-4;
  double nis = 0;
  EXPECT_EQ(fuse(s, r, H, R, 25.0, &nis), Outcome::kGate);
  EXPECT_NEAR(nis, 1.0 / (0.01 + 1e-4), 1e-9);
  EXPECT_EQ(s.x.p_W_B, before.x.p_W_B);
  EXPECT_EQ(s.P, before.P);
  r[0] = 0.1;
  EXPECT_EQ(fuse(s, r, H, R, 25.0), Outcome::kFused);
  EXPECT_NEAR(s.x.p_W_B.z(), before.x.p_W_B.z() + 0.1 * 0.01 / 0.0101, 1e-12);
  EXPECT_NEAR(s.P(2, 2), 0.01 - 0.01 * 0.01 / 0.0101, 1e-12);
}

TEST(EskfTest, UpdatesLeaveTheHeadingAndTheVerticalGyroBiasAlone) {
  // A covariance that correlates everything with everything, the vehicle tilted, a clone: a
  // flow update moves position, velocity, tilt and biases but not the heading (no sensor here
  // measures it), and the heading's variance does not shrink.
  std::mt19937_64 rng(12);
  std::normal_distribution<double> N;
  Eigen::MatrixXd A(idx::kCore, idx::kCore);
  for (int i = 0; i < A.size(); ++i) A.data()[i] = 0.05 * N(rng);
  FilterState s;
  s.x = some_state();
  s.P = A * A.transpose() + 1e-4 * Eigen::MatrixXd::Identity(idx::kCore, idx::kCore);
  ASSERT_TRUE(add_clone(s, 1));
  s.x.p_W_B += Vector3d(0.03, 0.01, 0);
  const FlowModel m = flow_model(s.x, s.clones[0], R_BC_downward(), Vector3d(0.1, 0, -0.06));
  MeasJac H = MeasJac::Zero(3, s.dim());
  H.leftCols<idx::kCore>() = m.H_core;
  H.rightCols<kCloneDim>() = m.H_clone;
  const MeasVec r = Vector3d(0.01, -0.02, 0.005);
  const MeasCov R = MeasCov::Identity(3, 3) * 1e-4;
  const FilterState before = s;
  const Vector3d u_B = before.x.q_WB.toRotationMatrix().transpose().col(2);
  ASSERT_EQ(fuse(s, r, H, R, 1e9), Outcome::kFused);
  // The correction's attitude part has no component about the vertical.
  const Vector3d dtheta = test_log(before.x.q_WB.conjugate() * s.x.q_WB);
  EXPECT_GT(dtheta.norm(), 1e-4);
  EXPECT_LT(std::abs(dtheta.dot(u_B)), 1e-12 + 1e-6 * dtheta.norm());
  EXPECT_LT(std::abs((s.x.gyro_bias_B - before.x.gyro_bias_B).dot(u_B)), 1e-15);
  EXPECT_GT((s.x.p_W_B - before.x.p_W_B).norm(), 1e-4);
  // ... and the variance about the vertical is not reduced, but for the reset's turn of the
  // attitude block by dtheta / 2, which moves it by about |dtheta| of itself.
  const double var_before = u_B.dot(before.P.block<3, 3>(idx::kTheta, idx::kTheta) * u_B);
  const double var_after = u_B.dot(s.P.block<3, 3>(idx::kTheta, idx::kTheta) * u_B);
  EXPECT_GT(var_after, var_before * (1.0 - dtheta.norm()));
}

TEST(EskfTest, TheHeadingsShareOfAnUpdateMovesNeitherTheHeadingNorThePositionsItSwings) {
  // Regression: only the attitude's part of the heading's gain was removed, so an update still
  // moved the positions as if the heading had turned (while it had not): a few mm per flow
  // sample, all the same way, 0.2-0.4 m after a 40 m square. Here the covariance is mostly the
  // heading's uncertainty swinging position and velocity about W's origin, 10 m away, and the
  // measurement is the velocity across the path: what it says through the heading is dropped
  // whole, what it says of the velocity itself is kept.
  FilterState s;
  s.x = some_state();
  s.x.p_W_B = Vector3d(10, 0, 1.5);
  s.x.v_W_B = Vector3d(1, 0, 0);
  s.x.q_WB = Quaterniond::Identity();
  ErrVec N = ErrVec::Zero(idx::kCore);  // turning the world about its vertical by 1 rad
  N.segment<3>(idx::kP) = Vector3d::UnitZ().cross(s.x.p_W_B);
  N.segment<3>(idx::kV) = Vector3d::UnitZ().cross(s.x.v_W_B);
  N.segment<3>(idx::kTheta) = Vector3d::UnitZ();
  s.P = 1e-4 * Cov::Identity(idx::kCore, idx::kCore) + 1e-3 * N * N.transpose();
  const FilterState before = s;
  MeasVec r(1);
  r[0] = 0.01;
  MeasJac H = MeasJac::Zero(1, idx::kCore);
  H(0, idx::kV + 1) = 1.0;  // v_y
  MeasCov R(1, 1);
  R(0, 0) = 1e-4;
  ASSERT_EQ(fuse(s, r, H, R, 1e9), Outcome::kFused);
  EXPECT_NEAR((s.x.p_W_B - before.x.p_W_B).norm(), 0.0, 1e-12);
  EXPECT_NEAR(test_log(before.x.q_WB.conjugate() * s.x.q_WB).z(), 0.0, 1e-12);
  // The velocity's own share: its prior variance 1e-4 against the reading's 1e-4 over the
  // whole innovation variance 1e-4 + 1e-3 + 1e-4.
  EXPECT_NEAR(s.x.v_W_B.y() - before.x.v_W_B.y(), 0.01 * 1e-4 / 1.2e-3, 1e-9);
  // Without the heading's removal the position would have swung by 10 m x the heading's share.
  FilterState plain = before;
  ASSERT_EQ(fuse(plain, r, H, R, 1e9, nullptr, false), Outcome::kFused);
  EXPECT_NEAR(plain.x.p_W_B.y() - before.x.p_W_B.y(), 10 * 0.01 * 1e-3 / 1.2e-3, 1e-9);
}

TEST(EskfTest, IsaAltitudeKnownValuesAndRoundTrip) {
  EXPECT_NEAR(isa_altitude_m(101325.0), 0.0, 1e-9);
  EXPECT_NEAR(isa_altitude_m(89874.6), 1000.0, 0.1);  // ISA table: 1000 m
  EXPECT_NEAR(isa_altitude_m(isa_pressure_pa(123.4)), 123.4, 1e-6);
}

}  // namespace
}  // namespace alight::estimator
