// A recorded run as a problem (recorded_problem.hpp).
#include "app/recorded_problem.hpp"

#include "learner/input_error.hpp"
#include "services/learning.hpp"

namespace hbirl::app {

namespace {

// The demonstrations as the optimiser received them; an episode's true steps when the run
// published them for every step. Moved out of `data` (its demonstrations are left empty):
// the observations are held once, not twice (docs/BENCHMARKS.md "Scale to the limit").
std::vector<DemonstratedTrajectory> take_demonstrations(services::Dataset& data) {
  std::vector<DemonstratedTrajectory> out;
  out.reserve(data.observed.size());
  for (size_t i = 0; i < data.observed.size(); ++i) {
    DemonstratedTrajectory t;
    t.ends_in_terminal = data.observed[i].ends_in_terminal;
    if (i < data.truth.size() && data.truth[i].size() == static_cast<size_t>(data.observed[i].length())) {
      t.truth = std::move(data.truth[i]);
    }
    t.steps = std::move(data.observed[i]);
    out.push_back(std::move(t));
  }
  data.observed.clear();
  data.truth.clear();
  return out;
}

}  // namespace

RecordedProblem read_recorded_problem(const services::RecordedRun& run, std::shared_ptr<const Domain> given,
                                      const LearnSettings& prior, const std::string& reader) {
  services::Counters counters;
  counters.service = reader;
  counters.quiet = true;
  services::OptimiserResult r = services::collect_from_log(run, counters);
  const bool on_a_file = given != nullptr;  // a domain file's name is one a problem file may carry
  const std::shared_ptr<const Domain> domain = services::domain_of(r.data, std::move(given));
  if (r.data.observed.empty()) throw InputError(run.path, "the log holds no demonstrations");
  RecordedProblem out;
  Problem& problem = out.problem;
  // hbirl publish of the file then marks its episodes as the run's. Not a built-in domain's
  // ("onion", "gridworld:7"): a problem file may not take those names.
  if (on_a_file) problem.name = domain->name();
  problem.mdp = domain->mdp();
  const DomainNames names = domain->names(r.data.num_sources);
  problem.state_names = names.states;
  problem.action_names = names.actions;
  problem.feature_names = names.features;
  problem.context_names = names.contexts;
  problem.observation_model = services::observation_prior(*domain, r.data);
  apply_to_prior(prior, *problem.observation_model);
  problem.true_weights = services::true_weights_of(*domain, r.data);
  problem.demonstration = take_demonstrations(r.data);
  out.domain = domain->name();
  out.source_names = names.sources;
  out.controlled_episodes = static_cast<int>(r.data.controlled_observed.size());
  out.missing_frames = r.missing_frames;
  out.bad_messages = counters.bad_messages;
  return out;
}

}  // namespace hbirl::app
