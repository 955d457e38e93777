// Levenberg-Marquardt with IRLS; see robust_lsq.hpp for the conventions and their sources.
#include "common/robust_lsq.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <stdexcept>
#include <string>

#include "common/median.hpp"

namespace alight::lsq {
namespace {

double weighted_cost(const Eigen::VectorXd& r, const Eigen::VectorXd& w) {
  return w.size() == 0 ? r.squaredNorm() : (w.array() * r.array().square()).sum();
}

void require(bool ok, const char* field, double value, const char* what) {
  if (!ok)
    throw std::invalid_argument(std::string("lsq::Options::") + field + " = " +
                                std::to_string(value) + ": " + what);
}

}  // namespace

void Options::validate() const {
  require(max_iterations >= 0, "max_iterations", max_iterations, "must be >= 0");
  require(initial_lambda >= 0, "initial_lambda", initial_lambda, "must be >= 0");
  require(lambda_up > 1, "lambda_up", lambda_up, "must be > 1");
  require(lambda_down > 0 && lambda_down <= 1, "lambda_down", lambda_down, "must be in (0, 1]");
  require(min_lambda > 0, "min_lambda", min_lambda, "must be > 0");
  require(max_lambda >= min_lambda, "max_lambda", max_lambda, "must be >= min_lambda");
  require(diagonal_floor >= 0, "diagonal_floor", diagonal_floor, "must be >= 0");
  require(relative_decrease >= 0, "relative_decrease", relative_decrease, "must be >= 0");
  require(step_tolerance >= 0, "step_tolerance", step_tolerance, "must be >= 0");
  require(fd_step > 0, "fd_step", fd_step, "must be > 0");
}

const char* to_string(Termination t) {
  switch (t) {
    case Termination::kNonFiniteStart:
      return "non-finite start";
    case Termination::kCostConverged:
      return "cost converged";
    case Termination::kSmallStep:
      return "small step";
    case Termination::kLambdaCap:
      return "lambda cap";
    case Termination::kMaxIterations:
      return "max iterations";
  }
  return "?";
}

void forward_difference_jacobian(const Problem& problem, const Eigen::VectorXd& r, double h,
                                 Eigen::MatrixXd& J) {
  const int n = problem.num_parameters;
  J.resize(r.size(), n);
  Eigen::VectorXd dx = Eigen::VectorXd::Zero(n), rk;
  for (int k = 0; k < n; ++k) {
    dx(k) = h;
    problem.residuals(dx, rk);
    assert(rk.size() == r.size());
    J.col(k) = (rk - r) / h;
    dx(k) = 0.0;
  }
}

Summary solve(const Problem& problem, const Options& options) {
  assert(problem.num_parameters > 0 && problem.residuals && problem.accept);
  const int n = problem.num_parameters;
  Summary summary;
  Eigen::VectorXd r, w, r_trial, dx, zero = Eigen::VectorXd::Zero(n);
  Eigen::MatrixXd J, A(n, n);
  Eigen::VectorXd g(n), D(n);
  Eigen::LDLT<Eigen::MatrixXd> ldlt(n);

  problem.residuals(zero, r);
  if (problem.weights) problem.weights(r, w);
  assert(w.size() == 0 || w.size() == r.size());
  double cost = weighted_cost(r, w);
  summary.initial_cost = summary.final_cost = cost;
  summary.final_lambda = options.initial_lambda;
  if (!std::isfinite(cost)) {
    summary.termination = Termination::kNonFiniteStart;
    return summary;
  }

  double lambda = options.initial_lambda;
  summary.termination = Termination::kMaxIterations;
  while (summary.iterations < options.max_iterations) {
    // Normal equations of the weighted linearisation at x.
    if (problem.jacobian)
      problem.jacobian(r, J);
    else
      forward_difference_jacobian(problem, r, options.fd_step, J);
    assert(J.rows() == r.size() && J.cols() == n);
    if (w.size() == 0) {
      A.noalias() = J.transpose() * J;
      g.noalias() = J.transpose() * r;
    } else {
      A.noalias() = J.transpose() * (w.asDiagonal() * J);
      g.noalias() = J.transpose() * w.cwiseProduct(r);
    }
    D = A.diagonal().array() + options.diagonal_floor;

    bool accepted = false;
    double cost_trial = cost;
    while (true) {
      Eigen::MatrixXd A_damped = A;
      A_damped.diagonal() += lambda * D;
      ldlt.compute(A_damped);
      dx = ldlt.solve(-g);
      if (dx.allFinite()) {
        problem.residuals(dx, r_trial);
        cost_trial = weighted_cost(r_trial, w);
        accepted = std::isfinite(cost_trial) && cost_trial < cost;
      }
      if (accepted) break;
      ++summary.rejected_steps;
      lambda = std::max(lambda, options.min_lambda) * options.lambda_up;
      if (lambda > options.max_lambda) break;
    }
    if (!accepted) {
      summary.termination = Termination::kLambdaCap;
      break;
    }

    problem.accept(dx);
    ++summary.iterations;
    lambda = std::max(lambda * options.lambda_down, options.min_lambda);
    const double decrease = cost - cost_trial;
    cost = cost_trial;
    r.swap(r_trial);
    if (decrease <= options.relative_decrease * (cost + decrease) || cost == 0.0) {
      summary.termination = Termination::kCostConverged;
      break;
    }
    if (dx.norm() <= options.step_tolerance) {
      summary.termination = Termination::kSmallStep;
      break;
    }
    if (problem.weights && summary.iterations < options.max_iterations) {
      problem.weights(r, w);  // IRLS: the weights follow the new residuals
      cost = weighted_cost(r, w);
    }
  }
  summary.final_cost = cost;
  summary.final_lambda = lambda;
  return summary;
}

std::vector<double> cauchy_weights(const std::vector<double>& e, double min_sigma) {
  if (e.empty()) return {};
  const double sigma = std::max(upper_median(e) / 1.177, min_sigma);
  const double c = 2.385 * sigma;
  std::vector<double> w(e.size());
  for (size_t k = 0; k < e.size(); ++k) w[k] = 1.0 / (1.0 + (e[k] / c) * (e[k] / c));
  return w;
}

}  // namespace alight::lsq
