// A domain file (problem/domain_file.hpp) as a domain: its MDP and names, its stated
// observation prior, and a run simulated by the sensor its "sensor" section describes.
#include "registry/builtin_domains.hpp"
#include "sim_driver/registry/simulation_options.hpp"
#include "learner/input_error.hpp"
#include "learner/soft_value_iteration.hpp"
#include "problem/domain_file.hpp"

namespace hbirl {

namespace {

std::vector<std::string> numbered(const std::string& prefix, int count) {
  std::vector<std::string> names;
  for (int i = 0; i < count; ++i) names.push_back(prefix + std::to_string(i));
  return names;
}

EtaKind eta_kind(const std::string& name) {
  if (name == "uniform") return EtaKind::kUniform;
  if (name == "true") return EtaKind::kTrue;
  return EtaKind::kPlausible;
}

// The soft expert of the domain's true weights (docs/MODEL.md "The expert") from
// mdp.start, each trajectory until it enters a terminal state or has `length` steps,
// watched by the sensor: each unoccluded step gives observations_per_step observations,
// each from the subject or an element with equal probability (the controlled run: the
// subject alone, eta all on it).
class SensorSimulation final : public SensorRun {
 public:
  SensorSimulation(const DomainSpec& d, std::uint64_t seed) {
    const SensorSpec& s = *d.sensor;
    const Mdp& mdp = d.mdp;
    num_symbols = d.num_symbols();
    num_sources = d.num_sources();
    true_weights = *d.true_weights;
    step_seconds = s.step_seconds;
    const SoftSolution expert = soft_value_iteration(mdp, mdp.reward(true_weights));
    if (!expert.converged) throw InputError("true_weights", "the soft expert's value iteration did not converge");
    Rng rng(seed);
    Rng expert_rng = rng.split(0), sensor_rng = rng.split(1);
    std::vector<int> entered;  // per episode, the terminal state it entered (-1: cut off)
    const auto demonstrate = [&](int count, std::vector<char>& ended) {
      std::vector<Trajectory> out;
      for (int i = 0; i < count; ++i) {
        bool terminal = false;
        int state = -1;
        out.push_back(sample_trajectory(mdp, expert.policy, s.length, expert_rng, &terminal, &state));
        ended.push_back(terminal ? 1 : 0);
        entered.push_back(state);
      }
      return out;
    };
    std::vector<char> ended;
    const std::vector<Trajectory> controlled = demonstrate(s.controlled_trajectories, ended);
    const std::vector<Trajectory> demonstrations = demonstrate(s.trajectories, ended);

    GridworldObservationOptions alone;
    alone.confounders = 0;
    alone.per_step = s.observations_per_step;
    alone.occlusion = s.occlusion;
    alone.eta = EtaKind::kSubject;
    GridworldObservations run =
        observe_gridworld(mdp, controlled, s.subject_o, Eigen::MatrixXd(0, num_symbols), alone, sensor_rng);
    subject_alone(run.trajectories, num_sources);  // the same sources as the demonstrations
    GridworldObservationOptions watch;
    watch.confounders = num_sources - 1;
    watch.per_step = s.observations_per_step;
    watch.occlusion = s.occlusion;
    watch.eta = eta_kind(s.eta);
    GridworldObservations seen = observe_gridworld(mdp, demonstrations, s.subject_o, s.confounder_o, watch, sensor_rng);
    for (auto& t : seen.trajectories) run.trajectories.push_back(std::move(t));
    report_ends(s, entered, controlled.size(), run.trajectories, rng.split(2));
    add_episodes(controlled, demonstrations, std::move(run.trajectories), ended);
  }

 private:
  // The end sensor's reports of each demonstration that entered a terminal state (its own
  // stream: the rest of the run is the same with or without it).
  void report_ends(const SensorSpec& s, const std::vector<int>& entered, size_t controlled,
                   std::vector<ObservedTrajectory>& observed, Rng rng) {
    num_end_symbols = static_cast<int>(s.end_o.cols());
    if (num_end_symbols == 0) return;
    for (size_t i = controlled; i < observed.size(); ++i) {
      if (entered[i] < 0) continue;
      for (int k = 0; k < s.end_reports; ++k)
        observed[i].end_symbols.push_back(rng.categorical(s.end_o.row(entered[i]).transpose()));
    }
  }
};

class FileDomain final : public Domain {
 public:
  explicit FileDomain(DomainSpec spec) : spec_(std::move(spec)) {}
  const std::string& name() const override { return spec_.name; }
  const Mdp& mdp() const override { return spec_.mdp; }
  int num_symbols() const override { return spec_.num_symbols(); }
  std::optional<Eigen::VectorXd> true_weights() const override { return spec_.true_weights; }
  std::optional<ObservationPrior> stated_prior() const override { return spec_.observation_model; }

  DomainNames names(int num_sources) const override {
    const Mdp& m = spec_.mdp;
    DomainNames n;
    n.states = spec_.state_names.empty() ? numbered("s", m.num_states) : spec_.state_names;
    n.actions = spec_.action_names.empty() ? numbered("a", m.num_actions) : spec_.action_names;
    n.features = spec_.feature_names.empty() ? numbered("feature ", m.num_features()) : spec_.feature_names;
    n.symbols = spec_.symbol_names.empty() ? numbered("symbol ", spec_.num_symbols()) : spec_.symbol_names;
    n.sources = spec_.source_names;
    if (n.sources.empty()) n.sources.push_back("subject (expert)");
    for (int e = static_cast<int>(n.sources.size()); e < num_sources; ++e)
      n.sources.push_back("element " + std::to_string(e));
    n.sources.resize(static_cast<size_t>(std::max(num_sources, 1)));
    n.contexts = spec_.context_names;
    return n;
  }

  // Without a controlled run, the prior the file states (observation_model.subject_alpha).
  Eigen::MatrixXd subject_prior(const std::vector<Trajectory>& truth, const std::vector<ObservedTrajectory>& observed,
                                int symbols) const override {
    if (observed.empty() && spec_.observation_model) {
      if (symbols != spec_.num_symbols()) {
        throw InputError("observations.num_symbols",
                         std::to_string(symbols) + " differs from the domain's " + std::to_string(spec_.num_symbols()));
      }
      return spec_.observation_model->subject_alpha;
    }
    return Domain::subject_prior(truth, observed, symbols);
  }

  std::unique_ptr<Simulation> simulate(const SimulationOptions& options) const override {
    if (!spec_.sensor)
      throw InputError("domain", "'" + spec_.name + "' has no \"sensor\" section: nothing to simulate");
    return std::make_unique<SensorSimulation>(spec_, options.seed);
  }

 private:
  DomainSpec spec_;
};

}  // namespace

std::unique_ptr<Domain> file_domain(const std::string& path, std::vector<std::string>* warnings) {
  DomainSpec spec;
  try {
    spec = read_domain_file(path, warnings);
  } catch (const InputError& e) {
    throw InputError(e.field().empty() ? path : path + ": " + e.field(), e.message());
  }
  if (builtin_domain(spec.name)) {
    throw InputError(path + ": name",
                     "'" + spec.name + "' is a built-in domain's name; give the file another \"name\"");
  }
  return std::make_unique<FileDomain>(std::move(spec));
}

}  // namespace hbirl
