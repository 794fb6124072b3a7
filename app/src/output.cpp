// What a person reads of a learned reward (output.hpp).
#include "app/output.hpp"

namespace hbirl::app {

std::vector<PolicyStep> learned_policy(const Mdp& mdp, const OptimalPolicy& optimal,
                                       const Eigen::VectorXd& soft_policy) {
  std::vector<PolicyStep> out;
  for (int s = 0; s < mdp.num_states; ++s) {
    const int a = optimal.actions[static_cast<size_t>(s)];
    if (mdp.is_terminal(s) || a < 0) continue;
    PolicyStep step;
    step.state = s;
    step.action = a;
    step.probability = soft_policy[mdp.pair(s, a)];
    out.push_back(step);
  }
  return out;
}

}  // namespace hbirl::app
