// What a person reads of a learned reward (output.hpp).
#include "app/output.hpp"

#include "learner/soft_value_iteration.hpp"
#include "learner/value_iteration.hpp"

namespace hbirl::app {

std::vector<PolicyStep> learned_policy(const Mdp& mdp, const Eigen::VectorXd& weights) {
  const Eigen::VectorXd reward = mdp.reward(weights);
  const OptimalPolicy optimal = value_iteration(mdp, reward);
  const SoftSolution soft = soft_value_iteration(mdp, reward);
  std::vector<PolicyStep> out;
  for (int s = 0; s < mdp.num_states; ++s) {
    const int a = optimal.actions[static_cast<size_t>(s)];
    if (mdp.is_terminal(s) || a < 0) continue;
    PolicyStep step;
    step.state = s;
    step.action = a;
    step.probability = soft.policy[mdp.pair(s, a)];
    out.push_back(step);
  }
  return out;
}

}  // namespace hbirl::app
