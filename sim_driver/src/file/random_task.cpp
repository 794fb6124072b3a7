#include "sim_driver/file/random_task.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "learner/input_error.hpp"
#include "learner/metrics.hpp"
#include "learner/soft_value_iteration.hpp"
#include "learner/value_iteration.hpp"

namespace hbirl {

namespace {

constexpr int kGridMoves[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};  // up, down, left, right

int uniform_between(Rng& rng, int lo, int hi) { return lo + rng.uniform_int(hi - lo + 1); }

double standard_normal(Rng& rng) {
  const double u = 1.0 - rng.uniform();  // (0, 1]
  return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * M_PI * rng.uniform());
}

// A Dirichlet(1/2) draw (normalised Gamma(1/2) variates: squares of normals) or a
// Dirichlet(1) draw (normalised exponentials).
Eigen::RowVectorXd dirichlet_half(int n, Rng& rng) {
  Eigen::RowVectorXd x(n);
  for (int i = 0; i < n; ++i) {
    const double z = standard_normal(rng);
    x[i] = z * z + 1e-12;
  }
  return x / x.sum();
}

Eigen::RowVectorXd dirichlet_one(int n, Rng& rng) {
  Eigen::RowVectorXd x(n);
  for (int i = 0; i < n; ++i) x[i] = -std::log(1.0 - rng.uniform());
  return x / x.sum();
}

struct Layout {
  std::string name;
  int states = 0;
  int actions = 0;
  std::vector<TransitionEntry> transitions;  // over every state; entries out of terminal states are dropped later
  std::vector<std::string> state_names, action_names;
};

Layout random_grid(Rng& rng) {
  Layout g;
  g.name = "grid";
  const int n = uniform_between(rng, 3, 10);
  g.states = n * n;
  g.actions = rng.uniform() < 0.5 ? 4 : 5;
  const double slip = rng.uniform(0.0, 0.3);
  for (int s = 0; s < g.states; ++s) {
    g.state_names.push_back("r" + std::to_string(s / n) + "c" + std::to_string(s % n));
    for (int a = 0; a < g.actions; ++a) {
      if (a == 4) {
        g.transitions.push_back({s, a, s, 1.0});
        continue;
      }
      for (int m = 0; m < 4; ++m) {
        const double p = m == a ? 1.0 - slip : slip / 3.0;
        if (p == 0.0) continue;
        int row = s / n + kGridMoves[m][0];
        int col = s % n + kGridMoves[m][1];
        if (row < 0 || row >= n || col < 0 || col >= n) {
          row = s / n;
          col = s % n;
        }
        g.transitions.push_back({s, a, row * n + col, p});
      }
    }
  }
  g.action_names = {"up", "down", "left", "right"};
  if (g.actions == 5) g.action_names.push_back("stay");
  return g;
}

Layout random_graph(Rng& rng) {
  Layout g;
  g.name = "graph";
  g.states = uniform_between(rng, 9, 100);
  g.actions = uniform_between(rng, 2, 6);
  std::vector<int> ring(static_cast<size_t>(g.states));
  for (int i = 0; i < g.states; ++i) ring[static_cast<size_t>(i)] = i;
  for (int i = g.states - 1; i > 0; --i)
    std::swap(ring[static_cast<size_t>(i)], ring[static_cast<size_t>(rng.uniform_int(i + 1))]);
  std::vector<int> next(static_cast<size_t>(g.states));
  for (int i = 0; i < g.states; ++i)
    next[static_cast<size_t>(ring[static_cast<size_t>(i)])] = ring[static_cast<size_t>((i + 1) % g.states)];
  for (int s = 0; s < g.states; ++s) {
    g.state_names.push_back("s" + std::to_string(s));
    for (int a = 0; a < g.actions; ++a) {
      // Action 0 follows the ring (every state reaches every other); the others jump.
      const int main = a == 0 ? next[static_cast<size_t>(s)] : rng.uniform_int(g.states);
      const double p = rng.uniform() < 0.3 ? 1.0 : rng.uniform(0.6, 0.95);
      g.transitions.push_back({s, a, main, p});
      if (p < 1.0) {
        const int others = uniform_between(rng, 1, 2);
        for (int k = 0; k < others; ++k) g.transitions.push_back({s, a, rng.uniform_int(g.states), (1.0 - p) / others});
      }
    }
  }
  for (int a = 0; a < g.actions; ++a) g.action_names.push_back(a == 0 ? "next" : "jump" + std::to_string(a));
  return g;
}

// Every (s, a) entry of a feature from its value per pair.
void add_feature(std::vector<FeatureEntry>& features, const Eigen::VectorXd& per_pair, int actions, int k) {
  for (Eigen::Index r = 0; r < per_pair.size(); ++r) {
    if (per_pair[r] != 0.0)
      features.push_back({static_cast<int>(r) / actions, static_cast<int>(r) % actions, k, per_pair[r]});
  }
}

// The optimal policy is not trivial: it uses at least two actions, and always taking
// action 0 (the greedy policy of a zero reward) loses at least 5% of the optimal value.
bool nontrivial(const Mdp& mdp, const Eigen::VectorXd& theta) {
  const OptimalPolicy optimal = value_iteration(mdp, mdp.reward(theta));
  int first = -1;
  bool several = false;
  for (int s = 0; s < mdp.num_states; ++s) {
    const int a = optimal.actions[static_cast<size_t>(s)];
    if (a < 0) continue;
    if (first < 0) first = a;
    several = several || a != first;
  }
  return several && inverse_learning_error(mdp, theta, Eigen::VectorXd::Zero(theta.size())).relative() >= 0.05;
}

// theta scaled so that the soft expert takes an optimal action with probability
// `decisiveness` on average over the non-terminal states (the scale changes how sure the
// expert is, not what is optimal), by bisection on the log of the scale in [1/4, 10]: a
// target out of that range gives its end (the expert's realised decisiveness is
// reported). Larger scales make rewards of thousands, which no data set pins down.
double decisiveness_of(const Mdp& mdp, const Eigen::VectorXd& theta) {
  const OptimalPolicy optimal = value_iteration(mdp, mdp.reward(theta));
  const double tie = 1e-9 * std::max(1.0, optimal.value.lpNorm<Eigen::Infinity>());
  const SoftSolution soft = soft_value_iteration(mdp, mdp.reward(theta));
  double total = 0.0;
  int states = 0;
  for (int s = 0; s < mdp.num_states; ++s) {
    if (mdp.is_terminal(s)) continue;
    ++states;
    for (int a = 0; a < mdp.num_actions; ++a) {
      if (mdp.available(s, a) && optimal.q[mdp.pair(s, a)] >= optimal.value[s] - tie)
        total += soft.policy[mdp.pair(s, a)];
    }
  }
  return total / states;
}

Eigen::VectorXd decisive(const Mdp& mdp, const Eigen::VectorXd& theta, double decisiveness) {
  double lo = std::log(0.25);
  double hi = std::log(10.0);
  for (int i = 0; i < 30; ++i) {
    const double mid = 0.5 * (lo + hi);
    (decisiveness_of(mdp, std::exp(mid) * theta) < decisiveness ? lo : hi) = mid;
  }
  return std::exp(0.5 * (lo + hi)) * theta;
}

// The MDP, features, names and a non-trivial true theta; false if no theta of 200 draws
// was non-trivial on this MDP (the caller draws another).
bool make_world(RandomTask& task, Rng& rng) {
  Layout layout = rng.uniform() < 0.5 ? random_grid(rng) : random_graph(rng);
  const int S = layout.states;
  const int A = layout.actions;
  task.goals = uniform_between(rng, 1, 2);
  task.traps = rng.uniform_int(4 - task.goals);
  std::vector<int> order(static_cast<size_t>(S));
  for (int i = 0; i < S; ++i) order[static_cast<size_t>(i)] = i;
  for (int i = 0; i < task.goals + task.traps; ++i) {
    std::swap(order[static_cast<size_t>(i)], order[static_cast<size_t>(i + rng.uniform_int(S - i))]);
  }
  const std::vector<int> goals(order.begin(), order.begin() + task.goals);
  const std::vector<int> traps(order.begin() + task.goals, order.begin() + task.goals + task.traps);
  std::vector<int> terminal = goals;
  terminal.insert(terminal.end(), traps.begin(), traps.end());
  for (int g : goals) layout.state_names[static_cast<size_t>(g)] += "_goal";
  for (int t : traps) layout.state_names[static_cast<size_t>(t)] += "_trap";
  std::vector<TransitionEntry> transitions;
  for (const auto& e : layout.transitions) {
    if (std::find(terminal.begin(), terminal.end(), e.state) == terminal.end()) transitions.push_back(e);
  }
  Eigen::VectorXd start = Eigen::VectorXd::Constant(S, 1.0 / (S - static_cast<double>(terminal.size())));
  for (int t : terminal) start[t] = 0.0;

  // Features: step cost, entering a goal, entering a trap, terrain.
  const int base = 2 + (task.traps > 0 ? 1 : 0);
  const int K = std::max(base, uniform_between(rng, 2, 5));
  Eigen::MatrixXd phi = Eigen::MatrixXd::Zero(S * A, K);
  task.feature_names = {"step", "goal"};
  if (task.traps > 0) task.feature_names.push_back("trap");
  for (const auto& e : transitions) {
    const int r = e.state * A + e.action;
    phi(r, 0) = 1.0;
    if (std::find(goals.begin(), goals.end(), e.next_state) != goals.end()) phi(r, 1) += e.probability;
    if (std::find(traps.begin(), traps.end(), e.next_state) != traps.end()) phi(r, 2) += e.probability;
  }
  for (int k = base; k < K; ++k) {
    task.feature_names.push_back("terrain" + std::to_string(k - base + 1));
    for (int s = 0; s < S; ++s) {
      if (rng.uniform() >= 1.0 / 3.0) continue;
      for (int a = 0; a < A; ++a) phi(s * A + a, k) = phi(s * A + a, 0);  // only where an action exists
    }
  }
  std::vector<FeatureEntry> features;
  for (int k = 0; k < K; ++k) add_feature(features, phi.col(k), A, k);
  task.mdp = make_mdp(S, A, K, transitions, features, start, terminal, rng.uniform(0.9, 0.97));
  task.mdp.validate();
  task.layout = layout.name;
  task.state_names = std::move(layout.state_names);
  task.action_names = std::move(layout.action_names);

  for (int attempt = 0; attempt < 200; ++attempt) {
    Eigen::VectorXd theta(K);
    theta[0] = -rng.uniform(0.05, 0.5);
    theta[1] = rng.uniform(1.0, 5.0);
    if (task.traps > 0) theta[2] = -rng.uniform(1.0, 5.0);
    for (int k = base; k < K; ++k) theta[k] = rng.uniform(-1.0, 1.0);
    if (nontrivial(task.mdp, theta)) {
      task.true_weights = decisive(task.mdp, theta, rng.uniform(0.5, 0.9));
      task.decisiveness = decisiveness_of(task.mdp, task.true_weights);
      return true;
    }
  }
  return false;
}

void make_sensor(RandomTask& task, const RandomTaskOverrides& o, Rng& rng) {
  const int P = task.mdp.num_pairs();
  const int A = task.mdp.num_actions;
  const int W = task.num_symbols = uniform_between(rng, 4, 24);
  const double k = task.informativeness = o.informativeness >= 0.0 ? o.informativeness : rng.uniform(0.3, 1.0);
  task.num_confounders = o.confounders >= 0 ? o.confounders : rng.uniform_int(8);
  task.subject_o.resize(P, W);
  for (int s = 0; s < task.mdp.num_states; ++s) {
    const Eigen::RowVectorXd state = dirichlet_half(W, rng);
    for (int a = 0; a < A; ++a) {
      task.subject_o.row(s * A + a) = (1.0 - k) / W + k * (0.75 * state + 0.25 * dirichlet_half(W, rng)).array();
    }
  }
  task.confounder_o.resize(task.num_confounders, W);
  for (int e = 0; e < task.num_confounders; ++e) task.confounder_o.row(e) = dirichlet_one(W, rng);
  task.subject_share = task.num_confounders > 0 ? rng.uniform(0.25, 0.75) : 1.0;
  const bool plausible = rng.uniform() < 0.5;
  task.eta = o.eta.empty() ? (plausible ? EtaKind::kPlausible : EtaKind::kUniform)
                           : (o.eta == "uniform" ? EtaKind::kUniform : EtaKind::kPlausible);
  task.occlusion = o.occlusion >= 0.0 ? o.occlusion : rng.uniform(0.0, 0.3);
  task.per_step = uniform_between(rng, 4, 20);
  task.length = uniform_between(rng, 8, 25);
}

// Watches `trajectories` through the task's sensor (true sources kept; eta assigned later).
void observe(RandomTask& task, const std::vector<char>& ended, Rng& rng) {
  const int E = task.num_confounders;
  for (size_t i = 0; i < task.demonstrations.size(); ++i) {
    ObservedTrajectory observed;
    observed.ends_in_terminal = ended[i] != 0;
    std::vector<int> sources;
    for (const StateAction& step : task.demonstrations[i]) {
      if (rng.uniform() >= task.occlusion) {
        for (int n = 0; n < task.per_step; ++n) {
          const int z = E == 0 || rng.uniform() < task.subject_share ? 0 : 1 + rng.uniform_int(E);
          const Eigen::VectorXd o = z == 0 ? task.subject_o.row(task.mdp.pair(step.state, step.action)).transpose()
                                           : task.confounder_o.row(z - 1).transpose();
          observed.symbols.push_back(rng.categorical(o));
          sources.push_back(z);
        }
      }
      observed.step_begin.push_back(static_cast<int>(observed.symbols.size()));
    }
    task.observed.trajectories.push_back(std::move(observed));
    task.observed.true_sources.push_back(std::move(sources));
  }
}

}  // namespace

// The end sensor (random_task.hpp "end"): its truth, the demonstrations' reports and the
// prior its calibration gives.
void sense_ends(RandomTask& task, Rng world, Rng data) {
  const int S = task.mdp.num_states;
  std::vector<int> symbol_of(static_cast<size_t>(S), -1);
  int K = 0;
  for (int s = 0; s < S; ++s) {
    if (task.mdp.is_terminal(s)) symbol_of[static_cast<size_t>(s)] = K++;
  }
  task.end_accuracy = world.uniform(0.55, 0.95);
  task.end_o = Eigen::MatrixXd::Zero(S, K);
  for (int s = 0; s < S; ++s) {
    const int own = symbol_of[static_cast<size_t>(s)];
    if (own < 0) continue;
    task.end_o.row(s).setConstant(K == 1 ? 1.0 : (1.0 - task.end_accuracy) / (K - 1));
    if (K > 1) task.end_o(s, own) = task.end_accuracy;
  }
  auto reports = [&](int entered) {
    std::vector<int> out;
    if (entered < 0) return out;
    for (int k = uniform_between(data, 1, 3); k > 0; --k)
      out.push_back(data.categorical(task.end_o.row(entered).transpose()));
    return out;
  };
  for (int entered : task.entered) task.end_reports.push_back(reports(entered));
  task.end_alpha = Eigen::MatrixXd::Zero(S, K);
  for (int s = 0; s < S; ++s) {
    if (symbol_of[static_cast<size_t>(s)] >= 0) task.end_alpha.row(s).setOnes();
  }
  task.end_calibration = uniform_between(data, 2, 10);
  for (int s = 0; s < S; ++s) {
    if (symbol_of[static_cast<size_t>(s)] < 0) continue;
    for (int k = 0; k < task.end_calibration; ++k)
      task.end_alpha(s, data.categorical(task.end_o.row(s).transpose())) += 1.0;
  }
}

const char* eta_kind_name(EtaKind kind) {
  switch (kind) {
    case EtaKind::kUniform:
      return "uniform";
    case EtaKind::kPlausible:
      return "plausible";
    case EtaKind::kSubject:
      return "subject";
    case EtaKind::kTrue:
      return "true";
  }
  return "?";
}

RandomTask make_random_task(std::uint64_t seed, int draw, const RandomTaskOverrides& overrides) {
  if (draw < 0) throw InputError("draw", "must be 0 or more");
  if (!overrides.eta.empty() && overrides.eta != "plausible" && overrides.eta != "uniform") {
    throw InputError("eta", "expected plausible or uniform, got \"" + overrides.eta + "\"");
  }
  RandomTask task;
  task.seed = seed;
  task.draw = draw;
  const Rng root(seed);
  for (std::uint64_t attempt = 0;; ++attempt) {
    Rng world = root.split(attempt);
    if (make_world(task, world)) {
      make_sensor(task, overrides, world);
      break;
    }
    if (attempt == 100) throw std::runtime_error("no random task with a non-trivial reward from this seed");
  }
  // The data: the same task watched again for every draw.
  Rng data = root.split(0xDA7A0000ull + static_cast<std::uint64_t>(draw));
  const int demonstrations = overrides.demonstrations > 0 ? overrides.demonstrations : uniform_between(data, 5, 40);
  const int drawn_controlled = uniform_between(data, 5, 30);  // (drawn either way: the same stream)
  const int controlled = overrides.controlled > 0 ? overrides.controlled : drawn_controlled;
  const SoftSolution expert = soft_value_iteration(task.mdp, task.mdp.reward(task.true_weights));
  if (!expert.converged) throw std::runtime_error("soft value iteration did not converge");
  std::vector<char> ended;
  for (int i = 0; i < demonstrations; ++i) {
    bool terminal = false;
    int entered = -1;
    task.demonstrations.push_back(sample_trajectory(task.mdp, expert.policy, task.length, data, &terminal, &entered));
    ended.push_back(terminal ? 1 : 0);
    task.entered.push_back(entered);
  }
  observe(task, ended, data);
  Rng eta_rng = data.split(1);
  assign_eta(task.observed, 1 + task.num_confounders, task.eta, eta_rng);
  for (int i = 0; i < controlled; ++i)
    task.controlled.push_back(sample_trajectory(task.mdp, expert.policy, task.length, data));
  task.prior.num_symbols = task.num_symbols;
  task.prior.num_confounders = task.num_confounders;
  task.prior.subject_alpha = controlled_run_alpha(task.mdp, task.controlled, task.subject_o, task.per_step, 1.0, data);
  task.prior.confounder_alpha = Eigen::MatrixXd::Ones(task.num_confounders, task.num_symbols);
  sense_ends(task, root.split(0xE4D5E450ull), root.split(0xE4D0A700ull + static_cast<std::uint64_t>(draw)));
  return task;
}

}  // namespace hbirl
