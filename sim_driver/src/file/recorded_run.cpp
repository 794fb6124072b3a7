// A problem file's demonstration as a run (recorded_run.hpp).
#include "sim_driver/file/recorded_run.hpp"

#include "registry/builtin_domains.hpp"
#include "learner/input_error.hpp"

namespace hbirl {

namespace {

class RecordedRun final : public SensorRun {
 public:
  explicit RecordedRun(const Problem& problem) {
    if (!problem.observation_model)
      throw InputError("observation_model", "missing: there is nothing to publish without symbols");
    num_symbols = problem.observation_model->num_symbols;
    num_sources = 1 + problem.observation_model->num_confounders;
    num_end_symbols = problem.observation_model->num_end_symbols();
    if (problem.true_weights) true_weights = *problem.true_weights;
    std::vector<Trajectory> controlled, demonstrations;
    std::vector<ObservedTrajectory> controlled_seen, seen;
    std::vector<char> ended, demonstration_ended;
    for (size_t i = 0; i < problem.demonstration.size(); ++i) {
      const DemonstratedTrajectory& d = problem.demonstration[i];
      if (!d.steps)
        throw InputError("demonstration[" + std::to_string(i) + "].steps", "missing: a sensor publishes observations");
      // Steps without known truth still need a length: placeholders, never published.
      const Trajectory steps =
          d.truth ? *d.truth : Trajectory(static_cast<size_t>(d.steps->length()), StateAction{0, 0});
      (d.controlled ? controlled : demonstrations).push_back(steps);
      (d.controlled ? controlled_seen : seen).push_back(*d.steps);
      (d.controlled ? ended : demonstration_ended).push_back(d.ends_in_terminal ? 1 : 0);
    }
    for (auto& t : seen) controlled_seen.push_back(std::move(t));
    ended.insert(ended.end(), demonstration_ended.begin(), demonstration_ended.end());
    add_episodes(controlled, demonstrations, std::move(controlled_seen), ended);
    for (auto& e : episodes) e.has_truth = e.controlled;
  }
};

}  // namespace

std::unique_ptr<Simulation> recorded_run(const Problem& problem) { return std::make_unique<RecordedRun>(problem); }

}  // namespace hbirl
