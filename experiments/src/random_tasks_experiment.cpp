#include "experiments/random_tasks_experiment.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <sstream>

#include "experiments/summary.hpp"
#include "learner/estep_observations.hpp"
#include "learner/hidden_data_em.hpp"
#include "learner/input_error.hpp"
#include "learner/metrics.hpp"
#include "learner/observation_model.hpp"
#include "learner/parallel.hpp"
#include "sim_driver/file/random_task.hpp"

namespace hbirl {

namespace {

// Enough EM iterations for the slowest method to converge (the paper's update at c = 0.1
// with one refinement per E-step needs several hundred).
constexpr int kMaxEmIterations = 3000;

// A run is optimal when its greedy policy loses nothing under the true reward.
constexpr double kOptimalTolerance = 1e-8;
// Two answers are the same fixed point when theta agrees to this (relative to max(1, |theta|))
// and the learned policies are equally good.
constexpr double kSameThetaTolerance = 1e-2;

RandomTaskRun describe(const RandomTask& task, const RandomTaskMethod& method) {
  RandomTaskRun r;
  r.seed = task.seed;
  r.draw = task.draw;
  r.method = method.key;
  r.layout = task.layout;
  r.states = task.mdp.num_states;
  r.actions = task.mdp.num_actions;
  r.features = task.mdp.num_features();
  r.goals = task.goals;
  r.traps = task.traps;
  r.symbols = task.num_symbols;
  r.confounders = task.num_confounders;
  r.per_step = task.per_step;
  r.demonstrations = static_cast<int>(task.demonstrations.size());
  r.controlled = static_cast<int>(task.controlled.size());
  r.informativeness = task.informativeness;
  r.decisiveness = task.decisiveness;
  r.subject_share = task.subject_share;
  r.occlusion = task.occlusion;
  r.discount = task.mdp.discount;
  r.eta = eta_kind_name(task.eta);
  return r;
}

// The prior that holds O at the truth while eta is learned (oracle_o): the true O's as
// Dirichlet parameters of 10^6 pseudo-counts a row (what a demonstration's counts move by
// less than 10^-4), every row counted (a base of 0) and weighed as given (strength 1).
// oracle_subject_o and oracle_elements_o hold one of the two (the elements' prior is not
// weighed by the strength: holding them leaves the subject's learning as the default's).
constexpr double kPseudoCounts = 1e6;

// The simulator's source mixture: the subject with probability subject_share, else an
// element chosen evenly.
Eigen::RowVectorXd source_mixture(const RandomTask& task) {
  const int E = task.num_confounders;
  Eigen::RowVectorXd mixture(1 + E);
  mixture[0] = task.subject_share;
  for (int e = 0; e < E; ++e) mixture[1 + e] = (1.0 - task.subject_share) / E;
  return mixture;
}

// The oracles' data (issue 33): what the simulator used, nothing learned -- the true
// subject O and element O's as the prior's fixed means, every observation's eta what its
// stated eta says of the true source under the simulator's own rules (calibrated_eta: the
// source mixture and how the labeller states eta). A first version used the mixture alone,
// which throws away what a plausible eta says: the default, learning eta, beat it.
std::pair<ObservationPrior, std::vector<ObservedTrajectory>> oracle_data(const RandomTask& task) {
  ObservationPrior prior = task.prior;
  prior.subject_alpha = task.subject_o;  // its Dirichlet mean is the true O
  prior.confounder_alpha = task.confounder_o;
  prior.learn = false;
  prior.learn_eta = false;
  const Eigen::RowVectorXd mixture = source_mixture(task);
  std::vector<ObservedTrajectory> observed = task.observed.trajectories;
  for (size_t i = 0; i < observed.size(); ++i) {
    for (Eigen::Index n = 0; n < observed[i].eta.rows(); ++n)
      observed[i].eta.row(n) = calibrated_eta(observed[i].eta.row(n), mixture, task.eta);
  }
  return {std::move(prior), std::move(observed)};
}

// posterior_from_truth: the default's E-step, its first pass at the oracle's values -- the
// true O's, and each context's eta what its stated eta says under the simulator's rules --
// instead of the prior's mean and the stated eta. Everything after is the default's
// learning: does EM stay at the truth, and does the learner's own criterion (the restart
// score) prefer where it ends to where the default ends? EM climbs the posterior, so where
// it leaves the truth the data, with the prior, favour another O (issue 33;
// docs/results.md "Random tasks").
class StartedAtTruth final : public EStep {
 public:
  StartedAtTruth(const ObservationEStep& inner, const RandomTask& task) : inner_(inner), task_(task) {}

  EStepState initial_state(std::uint64_t seed) const override {
    EStepState state = inner_.initial_state(seed);
    ObservationPrior& alpha = *state.alpha;
    alpha.subject_alpha = kPseudoCounts * task_.subject_o;  // a Dirichlet whose mean is the truth
    alpha.confounder_alpha = kPseudoCounts * task_.confounder_o;
    if (inner_.num_contexts() > 0) {
      const Eigen::RowVectorXd mixture = source_mixture(task_);
      for (Eigen::Index c = 0; c < alpha.eta_alpha.rows(); ++c)
        alpha.eta_alpha.row(c) = calibrated_eta(inner_.context_eta().row(c), mixture, task_.eta);
    }
    return state;
  }
  EStepResult expect(const SoftSolution& policy, EStepState& state) const override {
    return inner_.expect(policy, state);
  }
  bool depends_on_policy() const override { return inner_.depends_on_policy(); }
  std::vector<int> trajectory_lengths() const override { return inner_.trajectory_lengths(); }
  EStepResult fixed_model_statistics(const SoftSolution& policy, const EStepState& state) const override {
    return inner_.fixed_model_statistics(policy, state);
  }
  std::optional<StrengthChoice> choose_strength(const SoftSolution& policy, const EStepState& state) const override {
    return inner_.choose_strength(policy, state);
  }

 private:
  const ObservationEStep& inner_;
  const RandomTask& task_;
};

void hold_subject_at_true_o(const RandomTask& task, ObservationPrior& prior) {
  prior.subject_alpha = kPseudoCounts * task.subject_o;
  prior.subject_alpha_base = 0.0;
  prior.automatic_strength = false;
  prior.strength = 1.0;
}

// oracle_seen_subject_o: the true subject O held only on the pairs the controlled run
// visited (rows with counts); the others keep the prior's mean, as the default keeps them.
void hold_seen_subject_at_true_o(const RandomTask& task, ObservationPrior& prior) {
  const Eigen::Array<bool, Eigen::Dynamic, 1> counted = counted_subject_pairs(task.prior);
  for (Eigen::Index r = 0; r < counted.size(); ++r) {
    if (counted[r]) prior.subject_alpha.row(r) = kPseudoCounts * task.subject_o.row(r);
  }
  prior.automatic_strength = false;
  prior.strength = 1.0;
}

// oracle_unseen_subject_o: the complement -- the true subject O held on the pairs the
// controlled run never visited, the others the prior's counts at strength 1.
void hold_unseen_subject_at_true_o(const RandomTask& task, ObservationPrior& prior) {
  const Eigen::Array<bool, Eigen::Dynamic, 1> counted = counted_subject_pairs(task.prior);
  for (Eigen::Index r = 0; r < counted.size(); ++r) {
    if (!counted[r]) prior.subject_alpha.row(r) = kPseudoCounts * task.subject_o.row(r);
  }
  prior.automatic_strength = false;
  prior.strength = 1.0;
}

// A base pseudo-count b in place of the stated one: the counts above the base kept, the
// base b (rows with no counts stay uncounted, so weighed_subject_prior still holds them,
// at 1000 b).
void rebase_subject_prior(ObservationPrior& prior, double b) {
  prior.subject_alpha = (prior.subject_alpha.array() - prior.subject_alpha_base).cwiseMax(0.0) + b;
  prior.subject_alpha_base = b;
}

// posterior_unheld: the pairs the controlled run never visited learned from the
// demonstrations like the others, not held at the prior's mean (weighed_subject_prior's
// rule): each such row is given a count too small to move anything (1e-9 on its first
// symbol: random tasks' base is 1, far from where 1e-9 would round away), which is what
// makes weighed_subject_prior weigh it as counted.
void unhold_unseen_pairs(ObservationPrior& prior) {
  const Eigen::Array<bool, Eigen::Dynamic, 1> counted = counted_subject_pairs(prior);
  for (Eigen::Index r = 0; r < counted.size(); ++r) {
    if (!counted[r]) prior.subject_alpha(r, 0) = prior.subject_alpha_base + 1e-9;
  }
}

void hold_elements_at_true_o(const RandomTask& task, ObservationPrior& prior) {
  prior.confounder_alpha = kPseudoCounts * task.confounder_o;
}

void hold_at_true_o(const RandomTask& task, ObservationPrior& prior) {
  hold_subject_at_true_o(task, prior);
  hold_elements_at_true_o(task, prior);
}

// The prior plus every demonstration's labelled counts (random_tasks_experiment.hpp).
AlphaCounts labelled_o_counts(const RandomTask& task) {
  AlphaCounts all{task.prior.subject_alpha, task.prior.confounder_alpha, {}};
  for (size_t i = 0; i < task.demonstrations.size(); ++i) all += labelled_counts(task, i);
  return all;
}

// Each trajectory judged by an O of its own (oracle_sensor's eta, not learned; one E-step
// per trajectory, their sum the pass), from a prior of the controlled run's counts and,
// with `others_labelled`, every *other* demonstration's labelled counts
// (others_labelled_prior):
//   oracle_sensor_labelled_o_cf     that O held: what the rest of the data, labelled, say
//                                   of O (the labelled O of oracle_sensor_labelled_o also
//                                   counts the trajectory's own symbols at its true pairs,
//                                   which points its posterior at its true path)
//   oracle_sensor_labelled_others   that O as the prior of the trajectory's own O, learned
//                                   from its own observations by the posterior update at
//                                   strength 1
//   oracle_sensor_own_o             the same without the others' labels (the controlled
//                                   run alone): what the others' labels add, all else equal
// The pairs the controlled run never saw are held at the prior's mean, as the default holds
// them (weighed_subject_prior), also where other trajectories' labels counted a few symbols
// of them: unheld, the trajectory's own guesses reshape those rows (posterior_unheld).
// A learned O is refined to convergence from the prior at every evaluation (O profiled
// out: each call a function of theta alone), and the pass is taken at the converged O.
class PerTrajectoryO final : public EStep {
 public:
  PerTrajectoryO(const RandomTask& task, const ObservationPrior& oracle_prior,
                 const std::vector<ObservedTrajectory>& observed, bool others_labelled, bool learn_own) {
    ObservationEStepOptions options;
    options.max_alpha_iterations = kMaxOwnRefinements;
    const Eigen::Array<bool, Eigen::Dynamic, 1> seen = counted_subject_pairs(task.prior);
    for (size_t i = 0; i < observed.size(); ++i) {
      ObservationPrior prior = oracle_prior;
      if (others_labelled) {
        AlphaCounts others = others_labelled_prior(task, i);
        if (learn_own) {
          for (Eigen::Index r = 0; r < seen.size(); ++r) {
            if (!seen[r]) others.subject.row(r) *= ObservationPrior::kMaxStrength;
          }
        }
        prior.subject_alpha = std::move(others.subject);
        prior.confounder_alpha = std::move(others.confounders);
      } else {
        prior.subject_alpha = task.prior.subject_alpha;
        prior.confounder_alpha = task.prior.confounder_alpha;
      }
      prior.learn = learn_own;
      prior.automatic_strength = false;
      prior.strength = 1.0;
      each_.push_back(
          std::make_unique<ObservationEStep>(task.mdp, std::vector<ObservedTrajectory>{observed[i]}, prior, options));
    }
  }
  EStepResult expect(const SoftSolution& policy, EStepState& state) const override {
    EStepResult total;
    for (const auto& estep : each_) {
      EStepState own = estep->initial_state(state.seed);
      EStepResult r = estep->expect(policy, own);  // O refined to convergence (when learned)
      if (own.alpha->learn) {
        const bool converged = r.alpha_converged;
        r = estep->expect(policy, own);  // the objective and the pass at the converged O
        total.alpha_converged = total.alpha_converged && converged && r.alpha_converged;
      }
      total.counts = total.counts.size() == 0 ? r.counts : Eigen::VectorXd(total.counts + r.counts);
      total.log_likelihood += r.log_likelihood;
      total.objective += r.objective;
      total.impossible_trajectories += r.impossible_trajectories;
    }
    ++state.calls;
    return total;
  }
  bool depends_on_policy() const override { return true; }
  std::vector<int> trajectory_lengths() const override {
    std::vector<int> lengths;
    for (const auto& estep : each_) {
      for (int length : estep->trajectory_lengths()) lengths.push_back(length);
    }
    return lengths;
  }

 private:
  static constexpr int kMaxOwnRefinements = 1000;
  std::vector<std::unique_ptr<ObservationEStep>> each_;
};

// oracle_labelled_o: the labelled O's held (as oracle_o holds the true ones), eta learned
// as the default learns it.
void hold_at_labelled_o(const RandomTask& task, ObservationPrior& prior) {
  const AlphaCounts labelled = labelled_o_counts(task);
  prior.subject_alpha = kPseudoCounts * dirichlet_mean(labelled.subject);
  prior.subject_alpha_base = 0.0;
  prior.automatic_strength = false;
  prior.strength = 1.0;
  prior.confounder_alpha = kPseudoCounts * dirichlet_mean(labelled.confounders);
}

// What was seen of each trajectory's end (RandomTaskMethod::End) added to `observed`.
std::vector<ObservedTrajectory> seeing_the_end(const RandomTask& task, RandomTaskMethod::End end,
                                               std::vector<ObservedTrajectory> observed) {
  for (size_t i = 0; i < observed.size(); ++i) {
    if (!observed[i].ends_in_terminal) continue;
    if (end == RandomTaskMethod::End::kState) observed[i].end_state = task.entered[i];
    if (end == RandomTaskMethod::End::kSensor) observed[i].end_symbols = task.end_reports[i];
  }
  return observed;
}

void learn(const RandomTask& task, const RandomTaskMethod& method, RandomTaskRun& r) {
  // One observation-model refinement per E-step, interleaved with the M-steps (the paper
  // experiments' schedule), to hbirl learn's tolerances: the paper experiments' looser
  // 1e-3 / 1e-6 stopped EM short of its fixed point in some tasks (docs/MODEL.md). One
  // thread per run.
  LearnOptions options;
  options.restarts = method.restarts;
  options.seed = task.seed * 1000003ull + static_cast<std::uint64_t>(task.draw);
  options.threads = 1;
  options.max_em_iterations = kMaxEmIterations;
  LearnResult learned;
  if (method.kind == "truth") {
    learned = learn_reward(task.mdp, TruthEStep(task.mdp, task.demonstrations), options);
  } else if (method.kind == "oracle_labelled_cf" || method.kind == "oracle_labelled_others" ||
             method.kind == "oracle_own_o") {
    const auto [prior, observed] = oracle_data(task);
    const bool others_labelled = method.kind != "oracle_own_o";
    const bool learn_own = method.kind != "oracle_labelled_cf";
    learned = learn_reward(task.mdp, PerTrajectoryO(task, prior, observed, others_labelled, learn_own), options);
  } else if (method.kind == "oracle" || method.kind == "oracle_labelled") {
    auto [prior, observed] = oracle_data(task);
    if (method.kind == "oracle_labelled") {
      AlphaCounts labelled = labelled_o_counts(task);  // their means are O
      prior.subject_alpha = std::move(labelled.subject);
      prior.confounder_alpha = std::move(labelled.confounders);
    }
    if (method.end == RandomTaskMethod::End::kSensor) prior.end_alpha = task.end_o;  // its mean is the truth
    const ObservationEStep estep(task.mdp, seeing_the_end(task, method.end, observed), prior, {});
    learned = learn_reward(task.mdp, estep, options);
  } else {
    ObservationPrior prior = task.prior;
    if (method.end == RandomTaskMethod::End::kSensor) prior.end_alpha = task.end_alpha;
    if (method.kind == "oracle_o") hold_at_true_o(task, prior);
    if (method.kind == "labelled_o") hold_at_labelled_o(task, prior);
    if (method.kind == "oracle_subject_o") hold_subject_at_true_o(task, prior);
    if (method.kind == "oracle_elements_o") hold_elements_at_true_o(task, prior);
    if (method.kind == "oracle_seen_subject_o") hold_seen_subject_at_true_o(task, prior);
    if (method.kind == "oracle_unseen_subject_o") hold_unseen_subject_at_true_o(task, prior);
    if (method.base >= 0.0) rebase_subject_prior(prior, method.base);
    if (method.kind == "unheld") unhold_unseen_pairs(prior);
    prior.tie_actions = method.tie;
    prior.confounder_alpha *= method.elements;
    prior.learn = method.kind != "fixed";
    use_alpha_update(prior, method.kind == "paper" ? AlphaUpdate::kPaper : AlphaUpdate::kPosterior);
    prior.c = method.c;
    if (method.strength > 0.0) {
      prior.automatic_strength = false;
      prior.strength = method.strength;
    }
    ObservationEStepOptions estep_options;
    estep_options.max_alpha_iterations = 1;
    estep_options.cross_fit = method.cross_fit;
    const ObservationEStep estep(task.mdp, seeing_the_end(task, method.end, task.observed.trajectories), prior,
                                 estep_options);
    if (method.kind == "from_truth")
      learned = learn_reward(task.mdp, StartedAtTruth(estep, task), options);
    else
      learned = learn_reward(task.mdp, estep, options);
  }
  const RestartResult& best = learned.restarts[static_cast<size_t>(learned.selected_restart)];
  const PolicyMetrics metrics = policy_metrics(task.mdp, task.true_weights, learned.theta);
  r.ile = metrics.ile.ile;
  r.ile_relative = metrics.ile.relative();
  r.optimal = r.ile_relative <= kOptimalTolerance;
  r.policy_agreement = metrics.agreement;
  r.em_evaluations = best.em_evaluations;  // the cost
  r.converged = best.converged;
  r.log_likelihood = learned.log_likelihood;
  if (best.alpha && best.alpha->learn && best.alpha->update == AlphaUpdate::kPosterior)
    r.strength = best.alpha->strength;
  r.score = best.score;
  r.theta.assign(learned.theta.data(), learned.theta.data() + learned.theta.size());
}

// The groups of the breakdown: a name and which runs belong to it.
struct Group {
  std::string name;
  std::function<bool(const RandomTaskRun&)> member;
};

std::vector<Group> breakdown() {
  return {
      {"all", [](const RandomTaskRun&) { return true; }},
      {"|E| = 0", [](const RandomTaskRun& r) { return r.confounders == 0; }},
      {"|E| 1-3", [](const RandomTaskRun& r) { return r.confounders >= 1 && r.confounders <= 3; }},
      {"|E| 4-7", [](const RandomTaskRun& r) { return r.confounders >= 4; }},
      {"occluded < 10%", [](const RandomTaskRun& r) { return r.occlusion < 0.1; }},
      {"occluded 10-20%", [](const RandomTaskRun& r) { return r.occlusion >= 0.1 && r.occlusion < 0.2; }},
      {"occluded 20-30%", [](const RandomTaskRun& r) { return r.occlusion >= 0.2; }},
      {"informativeness < 0.53", [](const RandomTaskRun& r) { return r.informativeness < 0.3 + 0.7 / 3; }},
      {"informativeness 0.53-0.77",
       [](const RandomTaskRun& r) { return r.informativeness >= 0.3 + 0.7 / 3 && r.informativeness < 0.3 + 1.4 / 3; }},
      {"informativeness > 0.77", [](const RandomTaskRun& r) { return r.informativeness >= 0.3 + 1.4 / 3; }},
      {"plausible eta", [](const RandomTaskRun& r) { return r.eta == "plausible"; }},
      {"uniform eta", [](const RandomTaskRun& r) { return r.eta == "uniform"; }},
      {"grid", [](const RandomTaskRun& r) { return r.layout == "grid"; }},
      {"graph", [](const RandomTaskRun& r) { return r.layout == "graph"; }},
      {"with a trap", [](const RandomTaskRun& r) { return r.traps > 0; }},
  };
}

std::vector<std::string> methods_in(const std::vector<RandomTaskRun>& runs) {
  std::vector<std::string> methods;
  for (const auto& m : all_random_task_methods()) {
    if (std::any_of(runs.begin(), runs.end(), [&](const RandomTaskRun& r) { return r.method == m.key; }))
      methods.push_back(m.key);
  }
  return methods;
}

struct Cell {
  int n = 0;
  int optimal = 0;
  int near = 0;             // within 5% of the optimal value
  std::vector<double> ile;  // relative ILE of each run
};

Cell cell(const std::vector<RandomTaskRun>& runs, const std::string& method, const Group& group) {
  Cell c;
  for (const auto& r : runs) {
    if (r.method != method || !r.error.empty() || !group.member(r)) continue;
    ++c.n;
    c.optimal += r.optimal ? 1 : 0;
    c.near += r.ile_relative <= kNearOptimalShare ? 1 : 0;
    c.ile.push_back(r.ile_relative);
  }
  return c;
}

// Runs of two methods on the same (seed, draw), both without error.
template <typename F>
void paired(const std::vector<RandomTaskRun>& runs, const std::string& a, const std::string& b, F&& f) {
  std::map<std::pair<std::uint64_t, int>, const RandomTaskRun*> first;
  for (const auto& r : runs) {
    if (r.method == a && r.error.empty()) first[{r.seed, r.draw}] = &r;
  }
  for (const auto& r : runs) {
    if (r.method != b || !r.error.empty()) continue;
    const auto it = first.find({r.seed, r.draw});
    if (it != first.end()) f(*it->second, r);
  }
}

double theta_difference(const RandomTaskRun& a, const RandomTaskRun& b) {
  double diff = 0.0;
  double scale = 1.0;
  for (size_t k = 0; k < a.theta.size() && k < b.theta.size(); ++k) {
    diff = std::max(diff, std::abs(a.theta[k] - b.theta[k]));
    scale = std::max(scale, std::abs(a.theta[k]));
  }
  return diff / scale;
}

bool same_answer(const RandomTaskRun& a, const RandomTaskRun& b) {
  return std::abs(a.ile_relative - b.ile_relative) <= 1e-6 && a.optimal == b.optimal;
}

std::string percent(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f%%", 100.0 * x);
  return buf;
}

}  // namespace

AlphaCounts others_labelled_prior(const RandomTask& task, size_t i) {
  AlphaCounts prior{task.prior.subject_alpha, task.prior.confounder_alpha, {}};
  for (size_t j = 0; j < task.demonstrations.size(); ++j) {
    if (j != i) prior += labelled_counts(task, j);
  }
  return prior;
}

AlphaCounts labelled_counts(const RandomTask& task, size_t i) {
  AlphaCounts own = AlphaCounts::zero(static_cast<int>(task.prior.subject_alpha.rows()),
                                      static_cast<int>(task.prior.confounder_alpha.rows()),
                                      static_cast<int>(task.prior.subject_alpha.cols()));
  const ObservedTrajectory& observed = task.observed.trajectories[i];
  const std::vector<int>& sources = task.observed.true_sources[i];
  for (int t = 0; t < observed.length(); ++t) {
    const StateAction& step = task.demonstrations[i][static_cast<size_t>(t)];
    for (int n = observed.step_begin[static_cast<size_t>(t)]; n < observed.step_begin[static_cast<size_t>(t) + 1];
         ++n) {
      const int z = sources[static_cast<size_t>(n)];
      const int symbol = observed.symbols[static_cast<size_t>(n)];
      if (z == 0)
        own.subject(task.mdp.pair(step.state, step.action), symbol) += observed.weight(n);
      else
        own.confounders(z - 1, symbol) += observed.weight(n);
    }
  }
  return own;
}

const std::vector<RandomTaskMethod>& all_random_task_methods() {
  static const std::vector<RandomTaskMethod> methods = {
      {"true_trajectories", "truth", 0.1, 1},
      {"fixed_prior", "fixed", 0.1, 1},
      {"paper_c0.5", "paper", 0.5, 1},
      {"paper_c0.1", "paper", 0.1, 1},
      {"posterior", "posterior", 0.1, 1},
      {"posterior_c0.5", "posterior", 0.5, 1},
      {"posterior_c0.02", "posterior", 0.02, 1},
      {"posterior_r4", "posterior", 0.1, 4},
      {"oracle_sensor", "oracle", 0.1, 1},
      {"oracle_sensor_end", "oracle", 0.1, 1, RandomTaskMethod::End::kState},
      {"posterior_end", "posterior", 0.1, 1, RandomTaskMethod::End::kState},
      {"posterior_end_sensor", "posterior", 0.1, 1, RandomTaskMethod::End::kSensor},
      {"oracle_end_sensor", "oracle", 0.1, 1, RandomTaskMethod::End::kSensor},
      {"oracle_o", "oracle_o", 0.1, 1},
      {"oracle_subject_o", "oracle_subject_o", 0.1, 1},
      {"oracle_elements_o", "oracle_elements_o", 0.1, 1},
      {"posterior_s1", "posterior", 0.1, 1, RandomTaskMethod::End::kUnseen, 1.0},
      {"oracle_seen_subject_o", "oracle_seen_subject_o", 0.1, 1},
      {"posterior_s1000", "posterior", 0.1, 1, RandomTaskMethod::End::kUnseen, 1000.0},
      {"posterior_from_truth", "from_truth", 0.1, 1},
      {"oracle_unseen_subject_o", "oracle_unseen_subject_o", 0.1, 1},
      {"posterior_base0.1", "posterior", 0.1, 1, RandomTaskMethod::End::kUnseen, 0.0, 0.1},
      {"posterior_base0.3", "posterior", 0.1, 1, RandomTaskMethod::End::kUnseen, 0.0, 0.3},
      {"posterior_unheld", "unheld", 0.1, 1},
      {"posterior_cross_fit", "posterior", 0.1, 1, RandomTaskMethod::End::kUnseen, 0.0, -1.0, true},
      {"posterior_elements0.1", "posterior", 0.1, 1, RandomTaskMethod::End::kUnseen, 0.0, -1.0, false, 0.1},
      {"posterior_elements10", "posterior", 0.1, 1, RandomTaskMethod::End::kUnseen, 0.0, -1.0, false, 10.0},
      {"posterior_elements100", "posterior", 0.1, 1, RandomTaskMethod::End::kUnseen, 0.0, -1.0, false, 100.0},
      {"posterior_elements1000", "posterior", 0.1, 1, RandomTaskMethod::End::kUnseen, 0.0, -1.0, false, 1000.0},
      {"posterior_tied", "posterior", 0.1, 1, RandomTaskMethod::End::kUnseen, 0.0, -1.0, false, 1.0, true},
      {"oracle_labelled_o", "labelled_o", 0.1, 1},
      {"oracle_sensor_labelled_o", "oracle_labelled", 0.1, 1},
      {"oracle_sensor_labelled_o_cf", "oracle_labelled_cf", 0.1, 1},
      {"oracle_sensor_labelled_others", "oracle_labelled_others", 0.1, 1},
      {"oracle_sensor_own_o", "oracle_own_o", 0.1, 1},
  };
  return methods;
}

std::vector<RandomTaskMethod> parse_random_task_methods(const std::string& keys) {
  if (keys == "all") return all_random_task_methods();
  std::vector<RandomTaskMethod> out;
  std::stringstream in(keys);
  for (std::string key; std::getline(in, key, ',');) {
    const auto& all = all_random_task_methods();
    const auto it = std::find_if(all.begin(), all.end(), [&](const RandomTaskMethod& m) { return m.key == key; });
    if (it == all.end()) {
      std::string known;
      for (const auto& m : all) known += (known.empty() ? "" : ", ") + m.key;
      throw InputError("--methods", "unknown method \"" + key + "\" (" + known + ")");
    }
    out.push_back(*it);
  }
  if (out.empty()) throw InputError("--methods", "is empty");
  return out;
}

std::vector<RandomTaskRun> run_random_tasks(const RandomTasksOptions& o) {
  std::vector<std::uint64_t> seeds = o.seeds;
  if (seeds.empty()) {
    for (int t = 0; t < o.tasks; ++t) seeds.push_back(o.first_seed + static_cast<std::uint64_t>(t));
  }
  if (seeds.empty() || o.draws < 1) throw InputError("tasks", "need at least one task and one draw");
  RandomTaskOverrides overrides;
  overrides.controlled = o.controlled;
  overrides.demonstrations = o.demonstrations;
  std::vector<RandomTaskRun> runs = on_random_data_sets<RandomTaskRun>(
      seeds, o.draws, o.methods.size(), o.threads, o.progress,
      [&](const RandomTask& task, size_t m, RandomTaskRun& run) {
        run = describe(task, o.methods[m]);
        learn(task, o.methods[m], run);
      },
      overrides);
  for (size_t i = 0; i < runs.size(); ++i) runs[i].method = o.methods[i % o.methods.size()].key;  // a failed task's too
  return runs;
}

std::string random_task_runs_csv(const std::vector<RandomTaskRun>& runs) {
  std::ostringstream out;
  out.precision(10);
  out << "seed,draw,method,layout,states,actions,features,goals,traps,symbols,confounders,per_step,demonstrations,"
         "controlled,decisiveness,informativeness,subject_share,occlusion,discount,eta,ile,ile_relative,optimal,policy_"
         "agreement,"
         "em_evaluations,converged,log_likelihood,strength,score,theta,seconds,error\n";
  for (const auto& r : runs) {
    out << r.seed << "," << r.draw << "," << r.method << "," << r.layout << "," << r.states << "," << r.actions << ","
        << r.features << "," << r.goals << "," << r.traps << "," << r.symbols << "," << r.confounders << ","
        << r.per_step << "," << r.demonstrations << "," << r.controlled << "," << r.decisiveness << ","
        << r.informativeness << "," << r.subject_share << "," << r.occlusion << "," << r.discount << "," << r.eta << ","
        << r.ile << "," << r.ile_relative << "," << (r.optimal ? 1 : 0) << "," << r.policy_agreement << ","
        << r.em_evaluations << "," << (r.converged ? 1 : 0) << "," << r.log_likelihood << ",";
    if (r.strength >= 0.0) out << r.strength;
    out << ",";
    if (std::isfinite(r.score)) out << r.score;
    out << ",";
    for (size_t k = 0; k < r.theta.size(); ++k) out << (k ? ";" : "") << r.theta[k];
    const std::string error = csv_text(r.error);
    out << "," << r.seconds << "," << error << "\n";
  }
  return out.str();
}

std::vector<RandomTaskRun> random_task_runs_from_csv(const std::string& csv) {
  std::istringstream in(csv);
  std::string line;
  if (!std::getline(in, line)) throw InputError("runs CSV", "is empty");
  const std::vector<std::string> header = csv_cells(line);
  const std::string expected = random_task_runs_csv({});
  if (line + "\n" != expected) throw InputError("runs CSV", "line 1: not a random_tasks_runs.csv header");
  std::vector<RandomTaskRun> runs;
  for (int number = 2; std::getline(in, line); ++number) {
    const std::vector<std::string> f = csv_cells(line);
    if (f.size() != header.size()) {
      throw InputError("runs CSV", "line " + std::to_string(number) + ": " + std::to_string(f.size()) +
                                       " fields, expected " + std::to_string(header.size()));
    }
    try {
      RandomTaskRun r;
      size_t i = 0;
      r.seed = std::stoull(f[i++]);
      r.draw = std::stoi(f[i++]);
      r.method = f[i++];
      r.layout = f[i++];
      for (int* x : {&r.states, &r.actions, &r.features, &r.goals, &r.traps, &r.symbols, &r.confounders, &r.per_step,
                     &r.demonstrations, &r.controlled}) {
        *x = std::stoi(f[i++]);
      }
      for (double* x : {&r.decisiveness, &r.informativeness, &r.subject_share, &r.occlusion, &r.discount})
        *x = std::stod(f[i++]);
      r.eta = f[i++];
      r.ile = std::stod(f[i++]);
      r.ile_relative = std::stod(f[i++]);
      r.optimal = f[i++] == "1";
      r.policy_agreement = std::stod(f[i++]);
      r.em_evaluations = std::stoi(f[i++]);
      r.converged = f[i++] == "1";
      r.log_likelihood = std::stod(f[i++]);
      const std::string strength = f[i++];
      if (!strength.empty()) r.strength = std::stod(strength);
      const std::string score = f[i++];
      if (!score.empty()) r.score = std::stod(score);
      std::istringstream theta(f[i++]);
      for (std::string x; std::getline(theta, x, ';');) r.theta.push_back(std::stod(x));
      r.seconds = std::stod(f[i++]);
      r.error = f[i++];
      runs.push_back(std::move(r));
    } catch (const std::logic_error&) {
      throw InputError("runs CSV", "line " + std::to_string(number) + ": a field is not a number");
    }
  }
  return runs;
}

namespace {

// Per method and group of tasks: the share of runs with an optimal learned policy, and the relative ILE.
void write_optimal_share_table(std::ostream& out, const std::vector<RandomTaskRun>& runs,
                               const std::vector<std::string>& methods) {
  out << "# Random tasks: share of runs whose learned policy is optimal\n\n";
  out << "Per method and group of tasks: the share of runs whose learned reward's optimal policy is optimal under the "
         "true reward (ILE 0), with its 95% Wilson interval, and the mean ILE relative to ||V*||_1 "
      << "(± 95% CI). n = runs in the group.\n\n";
  out << "| group | n |";
  for (const auto& m : methods) out << " " << m << " |";
  out << "\n|---|---|";
  for (size_t i = 0; i < methods.size(); ++i) out << "---|";
  out << "\n";
  for (const Group& g : breakdown()) {
    const Cell first = cell(runs, methods.empty() ? "" : methods.front(), g);
    out << "| " << g.name << " | " << first.n << " |";
    for (const auto& m : methods) {
      const Cell c = cell(runs, m, g);
      if (c.n == 0) {
        out << " |";
        continue;
      }
      const auto [lo, hi] = wilson(c.optimal, c.n);
      const SummaryRow ile = mean_and_ci(c.ile);
      char buf[160];
      std::snprintf(buf, sizeof buf, " **%.1f%%** [%.1f, %.1f]<br>ILE %.3f ± %.3f |", 100.0 * c.optimal / c.n,
                    100.0 * lo, 100.0 * hi, ile.mean, ile.ci95);
      out << buf;
    }
    out << "\n";
  }
}

// Per method: the share of runs within 5% of the optimal value.
void write_near_optimal_shares(std::ostream& out, const std::vector<RandomTaskRun>& runs,
                               const std::vector<std::string>& methods) {
  out << "\nWithin 5% of the optimal value (ILE <= 0.05 ||V*||_1), all runs:";
  for (const auto& m : methods) {
    const Cell c = cell(runs, m, breakdown().front());
    if (c.n == 0) continue;
    const auto [lo, hi] = wilson(c.near, c.n);
    char buf[160];
    std::snprintf(buf, sizeof buf, " %s %.1f%% [%.1f, %.1f];", m.c_str(), 100.0 * c.near / c.n, 100.0 * lo, 100.0 * hi);
    out << buf;
  }
  out << "\n";
}

// Paired comparisons on the same data: which of two methods found an optimal policy.
void write_paired_comparisons(std::ostream& out, const std::vector<RandomTaskRun>& runs) {
  auto compare = [&](const std::string& a, const std::string& b) {
    int both = 0, only_a = 0, only_b = 0, neither = 0;
    paired(runs, a, b, [&](const RandomTaskRun& x, const RandomTaskRun& y) {
      if (x.optimal && y.optimal)
        ++both;
      else if (x.optimal)
        ++only_a;
      else if (y.optimal)
        ++only_b;
      else
        ++neither;
    });
    if (both + only_a + only_b + neither == 0) return;
    out << "| " << a << " vs " << b << " | " << both << " | " << only_a << " | " << only_b << " | " << neither
        << " |\n";
  };
  out << "\n## Paired: the same data, two methods\n\n| methods (a vs b) | both optimal | only a | only b | neither "
         "|\n|---|---|---|---|---|\n";
  compare("posterior", "fixed_prior");
  compare("posterior", "paper_c0.5");
  compare("posterior", "paper_c0.1");
  compare("posterior", "true_trajectories");
  compare("fixed_prior", "true_trajectories");
  compare("posterior", "oracle_sensor");
  compare("oracle_sensor", "oracle_sensor_end");
  compare("posterior", "posterior_end");
  compare("posterior_end", "oracle_sensor_end");
  compare("oracle_sensor_end", "true_trajectories");
  compare("posterior", "posterior_end_sensor");
  compare("posterior_end_sensor", "posterior_end");
  compare("posterior_end_sensor", "oracle_end_sensor");
  compare("posterior", "oracle_o");
  compare("oracle_o", "oracle_sensor");
  compare("posterior", "oracle_subject_o");
  compare("posterior", "oracle_elements_o");
  compare("posterior", "posterior_from_truth");
  compare("posterior_from_truth", "oracle_sensor");
  compare("posterior_s1", "oracle_seen_subject_o");
  compare("posterior_s1", "oracle_unseen_subject_o");
  compare("posterior", "posterior_unheld");
  compare("posterior", "posterior_base0.1");
  compare("posterior", "posterior_base0.3");
  compare("posterior", "posterior_cross_fit");
  compare("posterior", "posterior_elements100");
  compare("posterior", "posterior_elements1000");
  compare("posterior", "posterior_tied");
  compare("oracle_elements_o", "posterior_elements1000");
  compare("posterior", "oracle_labelled_o");
  compare("oracle_labelled_o", "oracle_o");
  compare("oracle_sensor_labelled_o", "oracle_sensor");
  compare("oracle_sensor_labelled_o_cf", "oracle_sensor");
  compare("posterior", "oracle_sensor_labelled_o_cf");
  compare("posterior", "oracle_sensor_labelled_others");
  compare("oracle_sensor_labelled_others", "oracle_sensor");
  compare("oracle_sensor_own_o", "oracle_sensor_labelled_others");
}

// Does the default's answer depend on c?
void write_c_dependence(std::ostream& out, const std::vector<RandomTaskRun>& runs) {
  out << "\n## Does the default's answer depend on c?\n\n";
  for (const std::string other : {"posterior_c0.5", "posterior_c0.02"}) {
    int n = 0, identical = 0, same_theta = 0, same = 0, unconverged = 0;
    paired(runs, "posterior", other, [&](const RandomTaskRun& x, const RandomTaskRun& y) {
      ++n;
      identical += x.theta == y.theta ? 1 : 0;
      same_theta += theta_difference(x, y) <= kSameThetaTolerance ? 1 : 0;
      same += same_answer(x, y) ? 1 : 0;
      unconverged += (!x.converged || !y.converged) ? 1 : 0;
    });
    if (n == 0) continue;
    out << "- posterior (c = 0.1) vs " << other << ": the same theta (as written) in " << identical << " of " << n
        << " runs; the same learned policy value (relative ILE within 1e-6) in " << same << " ("
        << percent(static_cast<double>(same) / n) << "); theta within " << kSameThetaTolerance
        << " (relative to max(1, |theta|)) in " << same_theta << " (" << percent(static_cast<double>(same_theta) / n)
        << "); " << unconverged << " pairs with a run that hit the EM iteration limit.\n";
  }
}

// Do more restarts change the answer?
void write_restart_effect(std::ostream& out, const std::vector<RandomTaskRun>& runs) {
  int n = 0, changed = 0, better = 0, worse = 0, theta_changed = 0;
  paired(runs, "posterior", "posterior_r4", [&](const RandomTaskRun& one, const RandomTaskRun& four) {
    ++n;
    theta_changed += theta_difference(one, four) > kSameThetaTolerance ? 1 : 0;
    if (!same_answer(one, four)) {
      ++changed;
      if (four.ile_relative < one.ile_relative)
        ++better;
      else
        ++worse;
    }
  });
  if (n > 0) {
    out << "\n## Do more restarts change the answer?\n\n- posterior with 4 restarts vs 1: theta moved by more than "
        << kSameThetaTolerance << " in " << theta_changed << " of " << n
        << " runs; the learned policy's value changed in " << changed << " ("
        << percent(static_cast<double>(changed) / n) << "): better in " << better << ", worse in " << worse << ".\n";
  }
}

// posterior_from_truth against the default (issue 33): where EM started at the oracle's
// values ends, and which end the learner's own criterion (the restart score) prefers.
void write_truth_start(std::ostream& out, const std::vector<RandomTaskRun>& runs) {
  int n = 0, same = 0, only_default = 0, only_truth = 0, both = 0, neither = 0;
  int truth_scores_higher = 0, default_scores_higher = 0, near_truth_scores_higher = 0, near_truth_differs = 0;
  int near_by_score = 0;  // within 5% when the end with the higher score is kept
  paired(runs, "posterior", "posterior_from_truth", [&](const RandomTaskRun& d, const RandomTaskRun& t) {
    ++n;
    const bool dn = d.ile_relative <= kNearOptimalShare;
    const bool tn = t.ile_relative <= kNearOptimalShare;
    both += dn && tn ? 1 : 0;
    only_default += dn && !tn ? 1 : 0;
    only_truth += tn && !dn ? 1 : 0;
    neither += !dn && !tn ? 1 : 0;
    if (same_answer(d, t)) {
      ++same;
      near_by_score += dn ? 1 : 0;
      return;
    }
    if (!std::isfinite(d.score) || !std::isfinite(t.score)) return;  // runs from before the score was recorded
    near_by_score += (t.score > d.score ? tn : dn) ? 1 : 0;
    (t.score > d.score ? truth_scores_higher : default_scores_higher) += 1;
    if (tn && !dn) {
      ++near_truth_differs;
      near_truth_scores_higher += t.score > d.score ? 1 : 0;
    }
  });
  if (n == 0) return;
  out << "\n## Does EM started at the truth stay there?\n\n"
      << "posterior_from_truth starts the default's EM at oracle_sensor's O's and eta. Of " << n
      << " data sets, it ends at the default's answer (the same learned policy value) in " << same << " ("
      << percent(static_cast<double>(same) / n) << "). Within 5% of the optimal value: both " << both
      << ", only the default " << only_default << ", only from the truth " << only_truth << ", neither " << neither
      << ". Where the two ends differ, the learner's own criterion for choosing between answers (the restart "
         "score: the held-out likelihood that chose the prior's strength) is higher at the end from the truth in "
      << truth_scores_higher << " and at the default's in " << default_scores_higher
      << "; of the data sets where only the end from the truth is within 5%, it scores higher in "
      << near_truth_scores_higher << " of " << near_truth_differs
      << ". Keeping, of the two, the end the criterion prefers: " << near_by_score << " within 5% ("
      << percent(static_cast<double>(near_by_score) / n) << ").\n";
}

// Per method: how often EM converged, its median evaluations and seconds; and the failed runs.
void write_em_table(std::ostream& out, const std::vector<RandomTaskRun>& runs,
                    const std::vector<std::string>& methods) {
  out << "\n## EM\n\n| method | runs | converged | median EM evaluations | median seconds |\n|---|---|---|---|---|\n";
  for (const auto& m : methods) {
    std::vector<double> iterations;
    std::vector<double> seconds;
    int converged = 0;
    for (const auto& r : runs) {
      if (r.method != m || !r.error.empty()) continue;
      iterations.push_back(r.em_evaluations);
      seconds.push_back(r.seconds);
      converged += r.converged ? 1 : 0;
    }
    if (iterations.empty()) continue;
    auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v[v.size() / 2];
    };
    char buf[200];
    std::snprintf(buf, sizeof buf, "| %s | %zu | %d (%.1f%%) | %.0f | %.3f |\n", m.c_str(), iterations.size(),
                  converged, 100.0 * converged / static_cast<double>(iterations.size()), median(iterations),
                  median(seconds));
    out << buf;
  }
  int failed = 0;
  for (const auto& r : runs) failed += r.error.empty() ? 0 : 1;
  if (failed > 0) out << "\n" << failed << " runs failed (see the error column of the runs CSV).\n";
}

}  // namespace

std::string random_tasks_summary(const std::vector<RandomTaskRun>& runs, const std::string& footer) {
  const std::vector<std::string> methods = methods_in(runs);
  std::ostringstream out;
  write_optimal_share_table(out, runs, methods);
  write_near_optimal_shares(out, runs, methods);
  write_paired_comparisons(out, runs);
  write_c_dependence(out, runs);
  write_restart_effect(out, runs);
  write_truth_start(out, runs);
  write_em_table(out, runs, methods);
  out << "\n" << footer << "\n";
  return out.str();
}

std::string draw_random_tasks_figure(const std::vector<RandomTaskRun>& runs, const std::string& path_stem) {
  // The main methods (the c and restart variants are in the summary's tables).
  std::vector<std::string> methods;
  for (const std::string m :
       {"true_trajectories", "oracle_sensor_end", "posterior_end", "oracle_end_sensor", "posterior_end_sensor",
        "oracle_sensor", "fixed_prior", "paper_c0.5", "paper_c0.1", "posterior"}) {
    if (std::any_of(runs.begin(), runs.end(), [&](const RandomTaskRun& r) { return r.method == m; }))
      methods.push_back(m);
  }
  // Per group: share optimal and share within 5% of the optimal value, each with its
  // Wilson interval (gnuplot data strings take double quotes).
  std::ostringstream data;
  for (const char* block : {"$optimal", "$near"}) {
    data << block << " << EOD\n";
    for (const Group& g : breakdown()) {
      data << '"' << g.name << '"';
      for (const auto& m : methods) {
        const Cell c = cell(runs, m, g);
        const int k = std::string(block) == "$optimal" ? c.optimal : c.near;
        const auto [lo, hi] = wilson(k, c.n);
        data << " " << (c.n ? 100.0 * k / c.n : 0.0) << " " << 100.0 * lo << " " << 100.0 * hi;
      }
      data << "\n";
    }
    data << "EOD\n";
  }
  data << "set style data histograms\nset style histogram errorbars gap 2 lw 1\nset style fill solid 0.85 border -1\n"
       << "set boxwidth 0.9\nset xtics rotate by -30 left\nset grid ytics\nset key outside right top\nset yrange "
          "[0:105]\n"
       << "set ylabel '% of runs'\nset bmargin 7\n";
  const char* colours[] = {"#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e",
                           "#e6ab02", "#a6761d", "#666666", "#1f78b4", "#b2df8a"};
  auto panel = [&](const std::string& block, const std::string& title) {
    std::ostringstream plot;
    plot << "set title " << gnuplot_quoted(title) << "\nplot ";
    for (size_t m = 0; m < methods.size(); ++m) {
      if (m) plot << ", \\\n     ";
      plot << block << " using " << 2 + 3 * m << ":" << 3 + 3 * m << ":" << 4 + 3 * m << (m == 0 ? ":xtic(1)" : "")
           << " title " << gnuplot_quoted(methods[m]) << " lc rgb '" << colours[m % 10] << "'";
    }
    return plot.str() + "\n";
  };
  const std::string plot =
      "set multiplot layout 2,1\n" +
      panel("$optimal", "Random tasks: runs whose learned policy is optimal (ILE 0; 95% Wilson interval)") +
      panel("$near", "Runs within 5% of the optimal value (ILE <= 0.05 ||V*||_1)") + "unset multiplot\n";
  return run_gnuplot(path_stem, data.str(), plot, 1400, 1100);
}

}  // namespace hbirl
