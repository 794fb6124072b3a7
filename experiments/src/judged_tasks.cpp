#include "experiments/judged_tasks.hpp"

#include <algorithm>
#include <optional>

#include "experiments/gridworld_experiment.hpp"
#include "experiments/gridworld_scenario.hpp"
#include "experiments/onion_experiment.hpp"
#include "learner/input_error.hpp"
#include "sim_driver/file/random_task.hpp"

namespace hbirl {

namespace {

// The Gridworld figure's confounders, in turn.
const std::vector<int>& gridworld_confounders() {
  static const std::vector<int> confounders = GridworldExperimentOptions{}.confounders;
  return confounders;
}
// The onion figure's most sorts.
int onion_sorts() {
  const std::vector<int> points = onion::OnionExperimentOptions{}.trajectories;
  return *std::max_element(points.begin(), points.end());
}

JudgedTask random_judged_task(const DataSetId& id) {
  RandomTask task = make_random_task(id.seed, id.draw);
  return {std::move(task.mdp), std::move(task.observed.trajectories), std::move(task.prior),
          std::move(task.demonstrations), std::move(task.true_weights)};
}

// The Gridworld figure's default method: plausible eta, the controlled run's prior,
// uninformative priors for the elements.
JudgedTask gridworld_judged_task(const JudgedTaskOptions& o, const DataSetId& id) {
  const int t = static_cast<int>(id.seed - o.first_seed);
  GridworldScenarioOptions options;
  options.seed = o.first_seed;
  GridworldScenario s = make_gridworld_scenario(options, t, id.draw);
  auto [observations, prior] = gridworld_method_data(s, GridworldMethod::kPlausibleEta, o.first_seed, t, id.draw);
  return {std::move(s.task.mdp), std::move(observations.trajectories), std::move(prior), std::move(s.task.trajectories),
          std::move(s.task.true_weights)};
}

onion::OnionExperimentOptions onion_figure_options(const JudgedTaskOptions& o) {
  onion::OnionExperimentOptions options;
  options.seed = o.first_seed;
  return options;
}

}  // namespace

// What every data set of a source shares, made once: the onion's controlled run.
struct JudgedTaskMaker::Shared {
  std::optional<onion::OnionSetup> onion;
};

namespace {

JudgedTask onion_judged_task(const JudgedTaskOptions& o, const onion::OnionSetup& setup, const DataSetId& id) {
  const onion::OnionExperimentOptions figure = onion_figure_options(o);
  onion::OnionDemonstration demo =
      onion::onion_run_demonstration(figure, setup.mdp, static_cast<int>(id.seed - o.first_seed), onion_sorts());
  return {setup.mdp, std::move(demo.observed), onion::onion_prior(setup, figure), std::move(demo.truth),
          onion::expert_weights()};
}

// Each source: its task t's draws, what it shares, and how it makes a data set.
struct Source {
  const char* name;
  const char* label;  // what a summary calls the tasks
  int figure_runs;    // the figure's own number of runs (0: not a figure)
  std::uint64_t figure_seed;
  std::vector<int> (*draws_of)(const JudgedTaskOptions&, int t);
  void (*share)(const JudgedTaskOptions&, JudgedTaskMaker::Shared&);
  JudgedTask (*make)(const JudgedTaskOptions&, const JudgedTaskMaker::Shared&, const DataSetId&);
};

const Source kSources[] = {
    {"random", "Random tasks", 0, 0,
     [](const JudgedTaskOptions& o, int) {
       std::vector<int> draws(static_cast<size_t>(o.draws));
       for (int d = 0; d < o.draws; ++d) draws[static_cast<size_t>(d)] = d;
       return draws;
     },
     [](const JudgedTaskOptions&, JudgedTaskMaker::Shared&) {},
     [](const JudgedTaskOptions&, const JudgedTaskMaker::Shared&, const DataSetId& id) {
       return random_judged_task(id);
     }},
    {"gridworld", "The Gridworld figure's runs (|E| = 0, 1, 3, ..., 15 in turn, plausible eta)",
     GridworldExperimentOptions{}.runs, GridworldExperimentOptions{}.seed,
     [](const JudgedTaskOptions&, int t) {
       const std::vector<int>& all = gridworld_confounders();
       return std::vector<int>{all[static_cast<size_t>(t) % all.size()]};
     },
     [](const JudgedTaskOptions&, JudgedTaskMaker::Shared&) {},
     [](const JudgedTaskOptions& o, const JudgedTaskMaker::Shared&, const DataSetId& id) {
       return gridworld_judged_task(o, id);
     }},
    {"onion", "The onion figure's runs (10 sorts from frames, the labeller's eta)",
     onion::OnionExperimentOptions{}.runs, onion::OnionExperimentOptions{}.seed,
     [](const JudgedTaskOptions&, int) { return std::vector<int>{0}; },
     [](const JudgedTaskOptions& o, JudgedTaskMaker::Shared& shared) {
       shared.onion = onion::onion_setup(onion_figure_options(o));
     },
     [](const JudgedTaskOptions& o, const JudgedTaskMaker::Shared& shared, const DataSetId& id) {
       return onion_judged_task(o, *shared.onion, id);
     }},
};

const Source& source_of(const JudgedTaskOptions& o) {
  for (const Source& s : kSources) {
    if (o.source == s.name) return s;
  }
  throw InputError("tasks_from", "unknown source \"" + o.source + "\" (random, gridworld, onion)");
}

}  // namespace

const std::vector<std::string>& judged_task_sources() {
  static const std::vector<std::string> sources = [] {
    std::vector<std::string> names;
    for (const Source& s : kSources) names.emplace_back(s.name);
    return names;
  }();
  return sources;
}

std::string judged_task_label(const std::string& source) {
  JudgedTaskOptions o;
  o.source = source;
  return source_of(o).label;
}

std::optional<std::uint64_t> figure_seed(const std::string& source) {
  JudgedTaskOptions o;
  o.source = source;
  const Source& s = source_of(o);
  if (s.figure_runs == 0) return std::nullopt;
  return s.figure_seed;
}

std::string judged_task_span(const JudgedTaskOptions& o) {
  const Source& s = source_of(o);
  if (s.figure_runs == 0) {
    return "seeds " + std::to_string(o.first_seed) + "-" +
           std::to_string(o.first_seed + static_cast<std::uint64_t>(o.tasks) - 1) +
           (o.draws > 1 ? " x " + std::to_string(o.draws) + " data sets each" : "");
  }
  return "runs 0-" + std::to_string(o.tasks - 1) + " of the seed " + std::to_string(o.first_seed) +
         " (task t is run t; the figure has " + std::to_string(s.figure_runs) + ")";
}

std::optional<std::string> judged_task_problem_command(const std::string& source) {
  JudgedTaskOptions o;
  o.source = source;
  if (source_of(o).figure_runs != 0) return std::nullopt;
  return "hbirl generate random-task --seed S --draw D --out task.json";
}

std::vector<DataSetId> judged_data_sets(const JudgedTaskOptions& o) {
  const Source& source = source_of(o);
  if (o.tasks < 1) throw InputError("tasks", "need at least one task");
  if (o.draws < 1) throw InputError("draws", "need at least one data set per task");
  std::vector<DataSetId> ids;
  for (int t = 0; t < o.tasks; ++t) {
    for (int draw : source.draws_of(o, t)) ids.push_back({o.first_seed + static_cast<std::uint64_t>(t), draw});
  }
  return ids;
}

JudgedTaskMaker::JudgedTaskMaker(const JudgedTaskOptions& o) : options_(o) {
  auto shared = std::make_unique<Shared>();
  source_of(o).share(o, *shared);
  shared_ = std::move(shared);
}

JudgedTaskMaker::~JudgedTaskMaker() = default;

JudgedTask JudgedTaskMaker::operator()(const DataSetId& id) const {
  return source_of(options_).make(options_, *shared_, id);
}

}  // namespace hbirl
