#include "learner/optimize.hpp"

#include <lbfgs.h>

#include <cmath>
#include <limits>
#include <new>

namespace hbirl {

namespace {

// See maximize_lbfgs: the gradient size below which a stalled line search counts as
// convergence.
constexpr double kWorkingPrecision = 1e-6;

struct LbfgsContext {
  const Objective* f = nullptr;
  Eigen::VectorXd x;  // the last evaluation: point, value and gradient
  double value = 0.0;
  Eigen::VectorXd gradient;
  int evaluations = 0;
  int iterations = 0;
  double best_value = -std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_x;
};

lbfgsfloatval_t lbfgs_evaluate(void* instance, const lbfgsfloatval_t* x, lbfgsfloatval_t* g, const int n,
                               const lbfgsfloatval_t /*step*/) {
  auto* ctx = static_cast<LbfgsContext*>(instance);
  ctx->x = Eigen::Map<const Eigen::VectorXd>(x, n);
  const double value = (*ctx->f)(ctx->x, ctx->gradient);
  ctx->value = value;
  ++ctx->evaluations;
  if (value > ctx->best_value) {
    ctx->best_value = value;
    ctx->best_x = ctx->x;
  }
  // liblbfgs minimises: hand it -J. A non-finite value makes the line search back off.
  Eigen::Map<Eigen::VectorXd>(g, n) = -ctx->gradient;
  return std::isfinite(value) ? -value : std::numeric_limits<double>::infinity();
}

int lbfgs_progress(void* instance, const lbfgsfloatval_t*, const lbfgsfloatval_t*, const lbfgsfloatval_t,
                   const lbfgsfloatval_t, const lbfgsfloatval_t, const lbfgsfloatval_t, int, int k, int) {
  static_cast<LbfgsContext*>(instance)->iterations = k;
  return 0;
}

const char* lbfgs_status(int code) {
  switch (code) {
    case LBFGS_SUCCESS:
      return "converged";
    case LBFGS_STOP:
      return "converged (objective stopped changing)";
    case LBFGS_ALREADY_MINIMIZED:
      return "converged (start point is optimal)";
    case LBFGSERR_ROUNDING_ERROR:
      return "stopped: rounding errors prevent further progress";
    case LBFGSERR_MAXIMUMLINESEARCH:
      return "stopped: line search reached its limit";
    case LBFGSERR_MINIMUMSTEP:
      return "stopped: line search step became too small";
    case LBFGSERR_MAXIMUMSTEP:
      return "stopped: line search step became too large";
    case LBFGSERR_MAXIMUMITERATION:
      return "stopped: iteration limit";
    case LBFGSERR_INCREASEGRADIENT:
      return "stopped: search direction is not an ascent direction";
    case LBFGSERR_WIDTHTOOSMALL:
      return "stopped: line search interval too small";
    default:
      return "stopped: L-BFGS error";
  }
}

// Fill the value, gradient norm and convergence flag at result.x, from the last
// evaluation when that was at result.x (else by evaluating f there).
void finish(const Objective& f, OptimizeResult& result, const OptimizerOptions& options,
            const LbfgsContext* last = nullptr) {
  if (last != nullptr && last->evaluations > 0 && last->x == result.x) {
    result.value = last->value;
    result.gradient_norm = last->gradient.norm();
  } else {
    Eigen::VectorXd gradient(result.x.size());
    result.value = f(result.x, gradient);
    ++result.evaluations;
    result.gradient_norm = gradient.norm();
  }
  result.converged =
      result.converged || result.gradient_norm <= options.gradient_tolerance * std::max(1.0, result.x.norm());
}

}  // namespace

const char* to_string(OptimizerKind kind) { return kind == OptimizerKind::kLbfgs ? "lbfgs" : "eg"; }

OptimizeResult maximize_lbfgs(const Objective& f, Eigen::VectorXd x0, const OptimizerOptions& options) {
  const int n = static_cast<int>(x0.size());
  OptimizeResult result;
  if (n == 0) {
    result.x = x0;
    result.converged = true;
    result.status = "converged (no parameters)";
    finish(f, result, options);
    return result;
  }
  lbfgs_parameter_t param;
  lbfgs_parameter_init(&param);
  param.epsilon = options.gradient_tolerance;
  param.max_iterations = options.max_iterations;
  param.linesearch = LBFGS_LINESEARCH_MORETHUENTE;
  param.max_linesearch = 40;

  LbfgsContext ctx;
  ctx.f = &f;
  ctx.gradient.resize(n);
  ctx.best_x = x0;
  lbfgsfloatval_t* x = lbfgs_malloc(n);
  if (x == nullptr) throw std::bad_alloc();
  Eigen::Map<Eigen::VectorXd>(x, n) = x0;
  lbfgsfloatval_t fx = 0.0;
  const int code = lbfgs(n, x, &fx, lbfgs_evaluate, lbfgs_progress, &ctx, &param);
  result.x = Eigen::Map<Eigen::VectorXd>(x, n);
  lbfgs_free(x);
  // liblbfgs reverts to the last accepted point on a line-search failure; keep the best
  // point ever evaluated in case that was better still.
  if (ctx.best_value > -fx) result.x = ctx.best_x;
  result.evaluations = ctx.evaluations;
  result.iterations = ctx.iterations;
  result.converged = code == LBFGS_SUCCESS || code == LBFGS_STOP || code == LBFGS_ALREADY_MINIMIZED;
  result.status = lbfgs_status(code);
  finish(f, result, options, &ctx);
  // Near the optimum the objective stops changing in double precision before the
  // gradient reaches a tight tolerance, and the line search gives up. That is the best
  // attainable point when the gradient is already small.
  const bool line_search_stop = code == LBFGSERR_ROUNDING_ERROR || code == LBFGSERR_MINIMUMSTEP ||
                                code == LBFGSERR_MAXIMUMLINESEARCH || code == LBFGSERR_WIDTHTOOSMALL;
  if (!result.converged && line_search_stop &&
      result.gradient_norm <= kWorkingPrecision * std::max(1.0, result.x.norm())) {
    result.converged = true;
    result.status = "converged to working precision (" + result.status + ")";
  }
  return result;
}

OptimizeResult maximize_exponentiated_gradient(const Objective& f, Eigen::VectorXd x0,
                                               const OptimizerOptions& options) {
  const auto k = x0.size();
  const double radius = options.eg_radius;
  const double eta = options.eg_learning_rate;
  OptimizeResult result;
  result.x = x0;
  if (k == 0) {
    result.converged = true;
    result.status = "converged (no parameters)";
    finish(f, result, options);
    return result;
  }
  // Start weights: x0 = radius (w+ - w-) with the slack spread evenly over all experts.
  // A start outside the ball is pulled in to half the radius.
  if (x0.lpNorm<1>() >= radius) x0 *= 0.5 * radius / x0.lpNorm<1>();
  const double slack = (1.0 - x0.lpNorm<1>() / radius) / static_cast<double>(2 * k);
  Eigen::VectorXd beta(2 * k);
  for (Eigen::Index i = 0; i < k; ++i) {
    beta[i] = std::log(slack + std::max(x0[i], 0.0) / radius);
    beta[k + i] = std::log(slack + std::max(-x0[i], 0.0) / radius);
  }
  Eigen::VectorXd hint = Eigen::VectorXd::Zero(2 * k);
  Eigen::VectorXd z(2 * k);
  Eigen::VectorXd gradient(k);
  Eigen::VectorXd x(k);
  double scale = 0.0;
  double best = -std::numeric_limits<double>::infinity();
  result.status = "stopped: iteration limit";
  for (int t = 0; t < options.max_iterations; ++t) {
    Eigen::VectorXd logits = beta - eta * hint;
    logits.array() -= logits.maxCoeff();
    Eigen::VectorXd w = logits.array().exp();
    w /= w.sum();
    x = radius * (w.head(k) - w.tail(k));
    const double value = f(x, gradient);
    ++result.evaluations;
    result.iterations = t + 1;
    if (!std::isfinite(value) || !gradient.allFinite()) {
      result.status = "stopped: objective not finite";
      break;
    }
    if (value > best) {
      best = value;
      result.x = x;
    }
    if (gradient.norm() <= options.gradient_tolerance * std::max(1.0, x.norm())) {
      result.converged = true;
      result.status = "converged";
      break;
    }
    // Loss of expert (i, +) is -radius * g_i, of (i, -) is +radius * g_i.
    z.head(k) = -radius * gradient;
    z.tail(k) = radius * gradient;
    scale = std::max(scale, z.lpNorm<Eigen::Infinity>());
    z /= scale;
    beta -= eta * z + (eta * eta) * (z - hint).cwiseAbs2();
    hint = z;
  }
  finish(f, result, options);
  return result;
}

OptimizeResult maximize(const Objective& f, Eigen::VectorXd x0, const OptimizerOptions& options) {
  return options.kind == OptimizerKind::kLbfgs ? maximize_lbfgs(f, std::move(x0), options)
                                               : maximize_exponentiated_gradient(f, std::move(x0), options);
}

}  // namespace hbirl
