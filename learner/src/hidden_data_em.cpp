#include "learner/hidden_data_em.hpp"

#include <cmath>

#include "learner/input_error.hpp"
#include "learner/maxcausalent.hpp"
#include "learner/parallel.hpp"

namespace hbirl {

namespace {

RestartResult run_restart(const Mdp& mdp, const EStep& estep, const LearnOptions& options,
                          Eigen::VectorXd theta, std::uint64_t seed, int index) {
  RestartResult result;
  result.initial_theta = theta;
  SoftBellmanSolver solver(mdp, options.soft_vi);
  EStepState state = estep.initial_state(seed);
  EStepResult expected = estep.expect(solver.solve(mdp.reward(theta)), state);
  double total = expected.counts.sum();
  for (int it = 1; it <= options.max_em_iterations; ++it) {
    CausalLikelihood objective(mdp, expected.counts, options.l2, options.soft_vi);
    const Objective f = [&objective](const Eigen::VectorXd& x, Eigen::VectorXd& g) {
      return objective.evaluate(x, &g);
    };
    const OptimizeResult m_step = maximize(f, theta, options.optimizer);
    result.optimizer_iterations += m_step.iterations;
    result.optimizer_status = m_step.status;
    result.em_iterations = it;
    const double theta_change = (m_step.x - theta).lpNorm<Eigen::Infinity>();
    theta = m_step.x;
    const double previous_ll = expected.log_likelihood;
    expected = estep.expect(solver.solve(mdp.reward(theta)), state);
    total = expected.counts.sum();
    if (options.on_iteration) options.on_iteration(index, it, expected.log_likelihood, theta, expected);
    if (!estep.depends_on_policy()) {
      result.converged = m_step.converged;
      break;
    }
    if (expected.alpha_converged &&
        theta_change <= options.theta_tolerance * std::max(1.0, theta.lpNorm<Eigen::Infinity>()) &&
        std::abs(expected.log_likelihood - previous_ll) <=
            options.likelihood_tolerance * std::max(1.0, std::abs(expected.log_likelihood))) {
      result.converged = true;
      break;
    }
  }
  result.theta = theta;
  result.log_likelihood = expected.log_likelihood;
  result.alpha = state.alpha;
  result.score = expected.log_likelihood - 0.5 * options.l2 * total * theta.squaredNorm();
  return result;
}

}  // namespace

LearnResult learn_reward(const Mdp& mdp, const EStep& estep, const LearnOptions& options) {
  if (options.restarts < 1) throw InputError("restarts", "must be at least 1");
  const int k = mdp.num_features();
  // Draw every start point up front, each restart from its own stream.
  std::vector<Eigen::VectorXd> starts;
  const Rng root(options.seed);
  for (int r = 0; r < options.restarts; ++r) {
    Eigen::VectorXd theta = Eigen::VectorXd::Zero(k);
    if (r > 0) {
      Rng rng = root.split(static_cast<std::uint64_t>(r));
      for (int i = 0; i < k; ++i) theta[i] = rng.uniform(-1.0, 1.0);
    }
    starts.push_back(std::move(theta));
  }
  LearnResult result;
  result.restarts.resize(static_cast<size_t>(options.restarts));
  parallel_for(options.restarts, options.threads, [&](int r) {
    result.restarts[static_cast<size_t>(r)] =
        run_restart(mdp, estep, options, starts[static_cast<size_t>(r)],
                    root.split(0x5EED0000ull + static_cast<std::uint64_t>(r)).next_u64(), r);
  });
  for (int r = 1; r < options.restarts; ++r) {
    if (result.restarts[static_cast<size_t>(r)].score >
        result.restarts[static_cast<size_t>(result.selected_restart)].score) {
      result.selected_restart = r;
    }
  }
  const RestartResult& best = result.restarts[static_cast<size_t>(result.selected_restart)];
  result.theta = best.theta;
  result.log_likelihood = best.log_likelihood;
  return result;
}

}  // namespace hbirl
