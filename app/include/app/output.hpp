#pragma once
// What a person reads of a learned reward, the same in hbirl learn's output,
// hbirl-optimiser's result.json and hbirl learn --log's: the policy a robot would follow,
// by state and action names. (hbirl learn --anytime's one line per estimate keeps the
// policy as action numbers, one per state: short lines for a stream.)
#include <string>
#include <vector>

#include "learner/mdp.hpp"
#include "learner/value_iteration.hpp"

namespace hbirl::app {

// The learned reward's policy in one state that is not terminal: the action its optimal
// policy takes (value iteration; the lowest-numbered among ties, as the ILE metric's) and
// the probability the soft policy -- MaxCausalEnt's model of the expert -- gives it.
struct PolicyStep {
  int state = 0;
  int action = 0;
  double probability = 0.0;
};
// From the learned reward's optimal policy and soft policy (one probability per pair),
// which the caller has computed for its metrics and output anyway: nothing is planned here.
std::vector<PolicyStep> learned_policy(const Mdp& mdp, const OptimalPolicy& optimal,
                                       const Eigen::VectorXd& soft_policy);

// The policy as [{"state": s, "action": a, "probability": p}, ...], states and actions by
// name when `state_names` / `action_names` give them (empty: by number). Json:
// nlohmann::json or ordered_json.
template <class Json>
Json policy_json(const std::vector<PolicyStep>& policy, const std::vector<std::string>& state_names,
                 const std::vector<std::string>& action_names) {
  const auto name = [](const std::vector<std::string>& names, int i) {
    return static_cast<size_t>(i) < names.size() ? Json(names[static_cast<size_t>(i)]) : Json(i);
  };
  Json out = Json::array();
  for (const PolicyStep& p : policy) {
    Json step = Json::object();
    step["state"] = name(state_names, p.state);
    step["action"] = name(action_names, p.action);
    step["probability"] = p.probability;
    out.push_back(std::move(step));
  }
  return out;
}

}  // namespace hbirl::app
