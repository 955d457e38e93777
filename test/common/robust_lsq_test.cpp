#include "common/robust_lsq.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace alight::lsq {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

/// x in R^n, moved by x + dx, residuals and Jacobian from functions of x.
struct VectorProblem {
  VectorXd x;
  Problem problem;

  template <class Residuals>
  VectorProblem(VectorXd x0, Residuals f) : x(std::move(x0)) {
    problem.num_parameters = int(x.size());
    problem.residuals = [this, f](const VectorXd& dx, VectorXd& r) { r = f(VectorXd(x + dx)); };
    problem.accept = [this](const VectorXd& dx) { x += dx; };
  }
  template <class Jacobian>
  void set_jacobian(Jacobian j) {
    problem.jacobian = [this, j](const VectorXd&, MatrixXd& J) { J = j(x); };
  }
};

// Element by element: GCC's -Wmaybe-uninitialized misreads Eigen's comma initializer on a
// dynamic-size temporary.
VectorXd rosenbrock(const VectorXd& x) {
  VectorXd r(2);
  r(0) = 10.0 * (x(1) - x(0) * x(0));
  r(1) = 1.0 - x(0);
  return r;
}
MatrixXd rosenbrock_jacobian(const VectorXd& x) {
  MatrixXd J(2, 2);
  J(0, 0) = -20.0 * x(0);
  J(0, 1) = 10.0;
  J(1, 0) = -1.0;
  J(1, 1) = 0.0;
  return J;
}

TEST(RobustLsqTest, LinearProblemIsSolvedExactlyInOneGaussNewtonStep) {
  // Given an overdetermined linear problem A x = b with noise (nonzero residual at the optimum)
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.1);
  MatrixXd A(20, 3);
  VectorXd b(20);
  for (int i = 0; i < 20; ++i) {
    const double t = 0.1 * i;
    A.row(i) << 1.0, t, t * t;
    b(i) = 2.0 - 3.0 * t + 0.5 * t * t + noise(rng);
  }
  const VectorXd exact = A.colPivHouseholderQr().solve(b);
  VectorProblem p(VectorXd::Zero(3), [&](const VectorXd& x) { return VectorXd(A * x - b); });
  p.set_jacobian([&](const VectorXd&) { return A; });
  // When one undamped step is taken
  Options o;
  o.initial_lambda = 0.0;
  o.max_iterations = 1;
  const Summary s = solve(p.problem, o);
  // Then it lands on the least-squares solution
  EXPECT_EQ(s.iterations, 1);
  EXPECT_EQ(s.termination, Termination::kMaxIterations);
  EXPECT_LT((p.x - exact).norm(), 1e-10 * exact.norm());
  EXPECT_NEAR(s.final_cost, (A * exact - b).squaredNorm(), 1e-12);
  EXPECT_GT(s.initial_cost, s.final_cost);

  // And with the default damping it gets there too, then stops on its own
  p.x.setZero();
  const Summary d = solve(p.problem);
  EXPECT_LT((p.x - exact).norm(), 1e-6 * exact.norm());
  EXPECT_NE(d.termination, Termination::kMaxIterations);
}

TEST(RobustLsqTest, RosenbrockConvergesWithAnalyticAndForwardDifferenceJacobians) {
  for (const bool analytic : {true, false}) {
    VectorProblem p((VectorXd(2) << -1.2, 1.0).finished(), rosenbrock);
    if (analytic) p.set_jacobian(rosenbrock_jacobian);
    Options o;
    o.max_iterations = 200;
    const Summary s = solve(p.problem, o);
    EXPECT_NEAR(p.x(0), 1.0, 1e-6) << "analytic " << analytic;
    EXPECT_NEAR(p.x(1), 1.0, 1e-6) << "analytic " << analytic;
    EXPECT_LT(s.final_cost, 1e-12);
    EXPECT_NEAR(s.initial_cost, 24.2, 1e-12);  // (10 (1 - 1.44))^2 + 2.2^2
    EXPECT_NE(s.termination, Termination::kMaxIterations) << to_string(s.termination);
    EXPECT_LT(s.iterations, 200);
  }
}

TEST(RobustLsqTest, ForwardDifferencesMatchTheAnalyticJacobian) {
  VectorProblem p((VectorXd(2) << 0.3, -0.7).finished(), rosenbrock);
  VectorXd r;
  p.problem.residuals(VectorXd::Zero(2), r);
  MatrixXd J;
  forward_difference_jacobian(p.problem, r, 1e-7, J);
  EXPECT_LT((J - rosenbrock_jacobian(p.x)).norm(), 1e-5);
}

TEST(RobustLsqTest, CauchyReweightingIgnoresOutliersThatPullPlainLeastSquares) {
  // Given 40 points of the line y = 2 x + 1 with 0.05 noise and 10 gross outliers above it
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 0.05);
  std::vector<double> xs, ys;
  for (int i = 0; i < 50; ++i) {
    const double x = 0.2 * i;
    xs.push_back(x);
    ys.push_back(2.0 * x + 1.0 + (i % 5 == 2 ? 4.0 + 0.3 * i : noise(rng)));
  }
  auto line = [&](const VectorXd& ab) {
    VectorXd r(xs.size());
    for (size_t i = 0; i < xs.size(); ++i) r(i) = ab(0) * xs[i] + ab(1) - ys[i];
    return r;
  };
  auto fit = [&](bool robust, Summary* s) {
    VectorProblem p(VectorXd::Zero(2), line);
    p.set_jacobian([&](const VectorXd&) {
      MatrixXd J(xs.size(), 2);
      for (size_t i = 0; i < xs.size(); ++i) J.row(i) << xs[i], 1.0;
      return J;
    });
    if (robust)
      p.problem.weights = [](const VectorXd& r, VectorXd& w) {
        std::vector<double> e(r.size());
        for (int i = 0; i < r.size(); ++i) e[i] = std::abs(r(i));
        const std::vector<double> c = cauchy_weights(e, 1e-9);
        w = Eigen::Map<const VectorXd>(c.data(), Eigen::Index(c.size()));
      };
    Options o;
    o.max_iterations = 50;
    *s = solve(p.problem, o);
    return p.x;
  };
  // When it is fitted by plain least squares and by Cauchy-weighted IRLS
  Summary s_plain, s_robust;
  const VectorXd plain = fit(false, &s_plain), robust = fit(true, &s_robust);
  const Eigen::Vector2d truth(2.0, 1.0);
  std::printf("line fit error: plain %.4f, Cauchy IRLS %.4f (%d iterations, %s)\n",
              (plain - truth).norm(), (robust - truth).norm(), s_robust.iterations,
              to_string(s_robust.termination));
  // Then the robust fit is close to the line and much closer than plain least squares
  EXPECT_GT((plain - truth).norm(), 0.5);
  EXPECT_LT((robust - truth).norm(), 0.1);
  EXPECT_LT((robust - truth).norm(), 0.1 * (plain - truth).norm());
  EXPECT_GT(s_robust.iterations, 1);
}

TEST(RobustLsqTest, WeightsAreEvaluatedAtTheStartAndAfterEachAcceptedStepThatDoesNotEnd) {
  VectorProblem p((VectorXd(2) << -1.2, 1.0).finished(), rosenbrock);
  int calls = 0;
  p.problem.weights = [&](const VectorXd& r, VectorXd& w) {
    ++calls;
    VectorXd r_here;
    p.problem.residuals(VectorXd::Zero(2), r_here);
    EXPECT_EQ(r, r_here);  // the residuals at the current state
    w.setOnes(r.size());
  };
  Options o;
  o.max_iterations = 4;
  const Summary s = solve(p.problem, o);
  ASSERT_EQ(s.termination, Termination::kMaxIterations);
  EXPECT_EQ(calls, 4);  // at the start and after steps 1 to 3
}

/// r(x) = x - 3 from x = 0: a step with lambda = 1 halves the Gauss-Newton step (Marquardt's
/// scaling, D = J^T J), so the cost falls from 9 to 2.25.
struct HalfStep : VectorProblem {
  HalfStep()
      : VectorProblem(VectorXd::Zero(1),
                      [](const VectorXd& x) { return VectorXd(x.array() - 3.0); }) {
    set_jacobian([](const VectorXd&) { return MatrixXd::Ones(1, 1); });
  }
};

TEST(RobustLsqTest, StopsWhenTheRelativeDecreaseIsSmall) {
  HalfStep p;
  Options o;
  o.initial_lambda = 1.0;
  o.relative_decrease = 0.8;  // the step lowers the cost by 75 %
  const Summary s = solve(p.problem, o);
  EXPECT_EQ(s.termination, Termination::kCostConverged);
  EXPECT_EQ(s.iterations, 1);
  EXPECT_NEAR(p.x(0), 1.5, 1e-9);
  EXPECT_NEAR(s.final_cost, 2.25, 1e-9);
  EXPECT_NEAR(s.final_lambda, 0.1, 1e-12);
}

TEST(RobustLsqTest, StopsOnASmallStep) {
  HalfStep p;
  Options o;
  o.initial_lambda = 1.0;
  o.step_tolerance = 2.0;  // the step is 1.5 long
  const Summary s = solve(p.problem, o);
  EXPECT_EQ(s.termination, Termination::kSmallStep);
  EXPECT_EQ(s.iterations, 1);
}

TEST(RobustLsqTest, StopsAtTheLambdaCapWhenNoStepLowersTheCost) {
  // r = (x - 1, x + 1) at its minimum x = 0: every step raises the cost
  VectorProblem p(VectorXd::Zero(1), [](const VectorXd& x) {
    return (VectorXd(2) << x(0) - 1.0, x(0) + 1.0).finished();
  });
  p.set_jacobian([](const VectorXd&) { return MatrixXd::Ones(2, 1); });  // gradient exactly 0
  int accepted = 0;
  const auto accept = p.problem.accept;
  p.problem.accept = [&](const VectorXd& dx) { ++accepted, accept(dx); };
  const Summary s = solve(p.problem);
  EXPECT_EQ(s.termination, Termination::kLambdaCap);
  EXPECT_EQ(s.iterations, 0);
  EXPECT_EQ(accepted, 0);
  EXPECT_GT(s.rejected_steps, 0);
  EXPECT_GT(s.final_lambda, Options{}.max_lambda);
  EXPECT_EQ(p.x(0), 0.0);
  EXPECT_EQ(s.final_cost, 2.0);
}

TEST(RobustLsqTest, StopsAfterMaxIterations) {
  VectorProblem p((VectorXd(2) << -1.2, 1.0).finished(), rosenbrock);
  p.set_jacobian(rosenbrock_jacobian);
  Options o;
  o.max_iterations = 2;
  const Summary s = solve(p.problem, o);
  EXPECT_EQ(s.termination, Termination::kMaxIterations);
  EXPECT_EQ(s.iterations, 2);
  EXPECT_LT(s.final_cost, s.initial_cost);
}

TEST(RobustLsqTest, DoesNothingFromANonFiniteStart) {
  VectorProblem p(VectorXd::Zero(1), [](const VectorXd& x) {
    return VectorXd::Constant(1, x(0) == 0.0 ? std::numeric_limits<double>::quiet_NaN() : 1.0);
  });
  p.problem.accept = [](const VectorXd&) { ADD_FAILURE() << "a step was accepted"; };
  const Summary s = solve(p.problem);
  EXPECT_EQ(s.termination, Termination::kNonFiniteStart);
  EXPECT_EQ(s.iterations, 0);
  EXPECT_TRUE(std::isnan(s.initial_cost));
}

TEST(RobustLsqTest, NeverAcceptsAStepToANonFiniteResidual) {
  // r(x) = x - 5, but undefined (NaN, or infinite) beyond x = 1: the Gauss-Newton step to 5 is
  // rejected and the damped steps creep up to the wall without crossing it.
  for (const double beyond :
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
        -std::numeric_limits<double>::infinity()}) {
    VectorProblem p(VectorXd::Zero(1), [beyond](const VectorXd& x) {
      return VectorXd::Constant(1, x(0) > 1.0 ? beyond : x(0) - 5.0);
    });
    p.set_jacobian([](const VectorXd&) { return MatrixXd::Ones(1, 1); });
    const auto accept = p.problem.accept;
    p.problem.accept = [&](const VectorXd& dx) {
      accept(dx);
      EXPECT_LE(p.x(0), 1.0) << "accepted a step to a non-finite residual";
    };
    Options o;
    o.max_iterations = 100;
    const Summary s = solve(p.problem, o);
    EXPECT_LE(p.x(0), 1.0);
    EXPECT_GT(p.x(0), 0.9);
    EXPECT_TRUE(std::isfinite(s.final_cost));
    EXPECT_GT(s.rejected_steps, 0);
  }
}

TEST(RobustLsqTest, ANonFiniteJacobianGivesNoStep) {
  VectorProblem p(VectorXd::Zero(1), [](const VectorXd& x) { return VectorXd(x.array() - 3.0); });
  p.set_jacobian([](const VectorXd&) {
    return MatrixXd::Constant(1, 1, std::numeric_limits<double>::quiet_NaN());
  });
  const Summary s = solve(p.problem);
  EXPECT_EQ(s.termination, Termination::kLambdaCap);
  EXPECT_EQ(s.iterations, 0);
  EXPECT_EQ(p.x(0), 0.0);
}

TEST(RobustLsqTest, CauchyWeightsFollowTheMedianScale) {
  // Median length 1.177 sigma with sigma = 1: c = 2.385
  const std::vector<double> w = cauchy_weights({1.177, 1.177, 1.177, 0.0, 2.385}, 1e-9);
  ASSERT_EQ(w.size(), 5u);
  EXPECT_NEAR(w[0], 1.0 / (1.0 + std::pow(1.177 / 2.385, 2)), 1e-12);
  EXPECT_EQ(w[3], 1.0);
  EXPECT_NEAR(w[4], 0.5, 1e-12);
  EXPECT_TRUE(cauchy_weights({}, 1.0).empty());
  // All residuals zero: sigma falls back to min_sigma, every weight 1
  for (const double wi : cauchy_weights({0.0, 0.0, 0.0}, 1e-3)) EXPECT_EQ(wi, 1.0);
}

TEST(RobustLsqTest, OptionsValidationNamesTheField) {
  Options o;
  EXPECT_NO_THROW(o.validate());
  o.lambda_up = 0.5;
  try {
    o.validate();
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("lambda_up"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace alight::lsq
