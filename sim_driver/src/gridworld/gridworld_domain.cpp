// The paper's Gridworld (paper §Experiments A) as a domain, any size: a goal corner
// drawn from the seed, and a run simulated by the paper's sensor (no camera).
#include "registry/builtin_domains.hpp"
#include "sim_driver/registry/simulation_options.hpp"
#include "learner/input_error.hpp"
#include "sim_driver/gridworld/gridworld.hpp"

namespace hbirl {

namespace {

// The controlled run's observations are the subject's alone (eta all on the subject);
// the demonstrations' are drawn equally from the subject and each confounding element
// and labelled with eta as options.eta says.
class GridworldSimulation final : public SensorRun {
 public:
  GridworldSimulation(int size, const SimulationOptions& g) {
    if (g.confounders < 0 || g.confounders > 1000) throw InputError("confounders", "must be in [0, 1000]");
    if (g.per_step < 0 || g.per_step > 100000) throw InputError("per_step", "must be in [0, 100000]");
    if (g.trajectories < 1 || g.controlled_trajectories < 1) throw InputError("trajectories", "must be at least 1");
    if (g.length < 1) throw InputError("length", "must be at least 1");
    if (g.eta == EtaKind::kSubject) throw InputError("eta", "must be uniform, plausible or true");
    if (!(g.step_seconds > 0.0)) throw InputError("step_seconds", "must be positive");
    GridworldOptions grid;
    grid.size = size;
    num_symbols = 4;
    num_sources = 1 + g.confounders;
    Rng task_rng = Rng(g.seed).split(0);
    const GridworldTask task = make_gridworld_task(grid, g.trajectories, g.length, task_rng);
    const std::vector<Trajectory> controlled =
        soft_expert_demonstration(task.mdp, task.true_weights, g.controlled_trajectories, g.length, task_rng);
    const Eigen::MatrixXd subject_o = gridworld_subject_observation_model(size, 1.0);
    Rng obs_rng = task_rng.split(1000 + static_cast<std::uint64_t>(g.confounders));
    const Eigen::MatrixXd confounder_o = random_confounder_observation_model(g.confounders, obs_rng);
    GridworldObservationOptions alone;
    alone.confounders = 0;
    alone.per_step = g.per_step;
    alone.eta = EtaKind::kSubject;
    GridworldObservations run =
        observe_gridworld(task.mdp, controlled, subject_o, Eigen::MatrixXd(0, 4), alone, obs_rng);
    subject_alone(run.trajectories, num_sources);  // the same sources as the demonstrations
    GridworldObservationOptions observe;
    observe.confounders = g.confounders;
    observe.per_step = g.per_step;
    observe.eta = g.eta;
    GridworldObservations demonstrations =
        observe_gridworld(task.mdp, task.trajectories, subject_o, confounder_o, observe, obs_rng);
    for (auto& t : demonstrations.trajectories) run.trajectories.push_back(std::move(t));
    frames_per_step = 1;
    step_seconds = g.step_seconds;
    true_weights = task.true_weights;
    // No terminal states: every trajectory is cut off.
    add_episodes(controlled, task.trajectories, std::move(run.trajectories),
                 std::vector<char>(controlled.size() + task.trajectories.size(), 0));
  }
};

class GridworldDomain final : public Domain {
 public:
  explicit GridworldDomain(int size)
      : size_(size), name_(size == 5 ? std::string("gridworld") : "gridworld:" + std::to_string(size)) {
    GridworldOptions options;
    options.size = size;
    mdp_ = make_gridworld(options);
  }
  const std::string& name() const override { return name_; }
  const Mdp& mdp() const override { return mdp_; }
  int num_symbols() const override { return 4; }

  // Symbols: one per corner, likelier the nearer the subject is to it.
  DomainNames names(int num_sources) const override {
    DomainNames n;
    n.states = gridworld_state_names(size_);
    n.actions = gridworld_action_names();
    n.features = gridworld_feature_names();
    for (const auto& f : n.features) n.symbols.push_back("near " + f);
    n.sources = {"subject (expert)"};
    for (int e = 1; e < num_sources; ++e) n.sources.push_back("element " + std::to_string(e));
    return n;
  }

  std::unique_ptr<Simulation> simulate(const SimulationOptions& options) const override {
    return std::make_unique<GridworldSimulation>(size_, options);
  }

 private:
  int size_;
  std::string name_;
  Mdp mdp_;
};

}  // namespace

std::unique_ptr<Domain> make_gridworld_domain(int size) { return std::make_unique<GridworldDomain>(size); }

}  // namespace hbirl
