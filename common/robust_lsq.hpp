#pragma once
// Robust nonlinear least squares: Levenberg-Marquardt with iteratively reweighted residuals.
//
// Minimises sum_i w_i r_i(x)^2 over a state x that the caller holds and moves by x <- x [+] dx,
// dx in R^n (a plain sum, or a retraction on a manifold such as R exp([w]x)).
//
// Damping (Marquardt 1963, "An algorithm for least-squares estimation of nonlinear parameters",
// SIAM J. Appl. Math. 11(2); Nocedal & Wright, "Numerical Optimization", 2nd ed., ch. 10.3):
// each step solves (J^T W J + lambda D) dx = -J^T W r with Marquardt's scaling
// D = diag(J^T W J) + diagonal_floor, so the damping is invariant to the scale of each
// parameter. A step is accepted when the cost at x [+] dx is finite and lower than at x; then
// lambda <- max(lambda * lambda_down, min_lambda) and the problem is linearised again.
// Otherwise lambda <- max(lambda, min_lambda) * lambda_up and the step is solved again from the
// same linearisation; a non-finite step or cost is a rejected step, never an accepted one.
//
// Iteratively reweighted least squares (Holland & Welsch 1977, "Robust regression using
// iteratively reweighted least-squares", Commun. Stat. Theory Methods 6(9)): when the problem
// has a weights hook, the weights w are evaluated from the residuals at the start and again
// after every accepted step, and the cost is re-evaluated under the new weights, so an M-estimator
// (e.g. Cauchy, cauchy_weights below) is minimised as a sequence of weighted least squares.
//
// Stop rule, checked in this order (Summary::termination says which one ended the solve):
//   - the initial cost is not finite: nothing is done (kNonFiniteStart);
//   - after an accepted step, cost_before - cost_after <= relative_decrease * cost_before or
//     cost_after = 0 (kCostConverged), or |dx| <= step_tolerance (kSmallStep);
//   - lambda would exceed max_lambda without an accepted step: no step from x lowers the cost
//     (kLambdaCap);
//   - max_iterations accepted steps (kMaxIterations). An iteration is one linearisation: the
//     retries with a larger lambda belong to the iteration they retry.
// The weights are not re-evaluated after the step that ends the solve.

#include <Eigen/Core>
#include <functional>
#include <vector>

namespace alight::lsq {

struct Options {
  int max_iterations = 15;           ///< accepted steps (linearisations) at most [-]
  double initial_lambda = 1e-4;      ///< damping of the first step, relative to D (0: Gauss-Newton)
  double lambda_up = 10.0;           ///< factor on lambda after a rejected step [-]
  double lambda_down = 0.1;          ///< factor on lambda after an accepted step [-]
  double min_lambda = 1e-9;          ///< lambda never falls below this [-]
  double max_lambda = 1e6;           ///< no accepted step before lambda exceeds this: stop [-]
  double diagonal_floor = 1e-12;     ///< added to diag(J^T W J) in D, for parameters it misses
  double relative_decrease = 1e-10;  ///< stop when an accepted step lowers the cost less [-]
  double step_tolerance = 0.0;       ///< stop when an accepted |dx| is at most this (0: off)
  double fd_step = 1e-7;             ///< forward-difference step when the problem has no Jacobian
  void validate() const;             ///< throws std::invalid_argument naming the field and value
};

/// A least-squares problem over a state the caller holds (captured by the functions).
struct Problem {
  int num_parameters = 0;  ///< n, the length of dx
  /// r(x [+] dx) into r (resized by the callee); dx = 0 is the current state. Must not move x.
  /// Non-finite values are allowed: such a point is never accepted.
  std::function<void(const Eigen::VectorXd& dx, Eigen::VectorXd& r)> residuals;
  /// Optional: J = d r(x [+] dx) / d dx at dx = 0 (rows: residuals), given r = r(x). Without
  /// it, forward differences of residuals (forward_difference_jacobian) with Options::fd_step.
  std::function<void(const Eigen::VectorXd& r, Eigen::MatrixXd& J)> jacobian;
  /// x <- x [+] dx (an accepted step).
  std::function<void(const Eigen::VectorXd& dx)> accept;
  /// Optional IRLS hook: the weight of each residual from r = r(x) (w resized by the callee).
  /// Without it, every weight is 1 (plain least squares).
  std::function<void(const Eigen::VectorXd& r, Eigen::VectorXd& w)> weights;
};

enum class Termination {
  kNonFiniteStart,  ///< the cost at the start was not finite; x unchanged
  kCostConverged,   ///< an accepted step lowered the cost by at most relative_decrease
  kSmallStep,       ///< an accepted step was at most step_tolerance long
  kLambdaCap,       ///< no step lowered the cost before lambda exceeded max_lambda
  kMaxIterations,   ///< max_iterations accepted steps
};

const char* to_string(Termination t);

struct Summary {
  int iterations = 0;         ///< accepted steps
  int rejected_steps = 0;     ///< trial steps not accepted (cost not lower, or not finite)
  double initial_cost = 0.0;  ///< sum w r^2 at the start, initial weights
  double final_cost = 0.0;    ///< sum w r^2 at the end, with the weights of the last step
  double final_lambda = 0.0;
  Termination termination = Termination::kMaxIterations;
};

/// Levenberg-Marquardt (with IRLS when problem.weights is set) from the caller's current state.
Summary solve(const Problem& problem, const Options& options = {});

/// Forward differences J.col(k) = (r(x [+] h e_k) - r) / h, given r = r(x).
void forward_difference_jacobian(const Problem& problem, const Eigen::VectorXd& r, double h,
                                 Eigen::MatrixXd& J);

/// IRLS weights of residual lengths e (one per 2-D residual) under a Cauchy loss,
/// w = 1 / (1 + (e / c)^2), with c = 2.385 sigma (95 % efficiency under Gaussian noise;
/// Holland & Welsch 1977) and sigma from the median length (a 2-D Gaussian residual has median
/// length 1.177 sigma), at least min_sigma. Empty e: empty weights.
std::vector<double> cauchy_weights(const std::vector<double>& e, double min_sigma);

}  // namespace alight::lsq
