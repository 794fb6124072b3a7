#include "experiments/eta_experiments.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <sstream>

#include "experiments/summary.hpp"
#include "learner/estep_observations.hpp"
#include "learner/hidden_data_em.hpp"
#include "learner/metrics.hpp"
#include "learner/parallel.hpp"

namespace hbirl {

namespace {

// What one learning run gives.
struct Fit {
  double ile = 0.0;
  double ile_relative = 0.0;
  bool goal_recovered = false;
  double label_accuracy = -1.0;
  double subject_eta = -1.0;  // learned eta of context 0 ("pick = subject"), its subject share
  int evaluations = 0;
};

// The prior every method starts from: the subject's from the controlled run, a flat one
// for each listed element, the posterior update (hbirl's default).
ObservationPrior gridworld_prior(const GridworldScenario& s, int listed) {
  ObservationPrior prior;
  prior.num_symbols = 4;
  prior.num_confounders = listed;
  prior.subject_alpha = s.controlled_alpha;
  prior.confounder_alpha = Eigen::MatrixXd::Ones(listed, 4);
  use_alpha_update(prior, AlphaUpdate::kPosterior);
  return prior;
}

// HiddenDataEM on `data` with the Gridworld experiment's schedule (one alpha refinement per
// E-step, SQUAREM), then ILE against the truth and the subject-or-not labels' accuracy
// under the learned model (with learned eta where eta was learned).
Fit fit(const GridworldScenario& s, std::vector<ObservedTrajectory> data, ObservationPrior prior, std::uint64_t seed) {
  const Mdp& mdp = s.task.mdp;
  add_unlisted_source(prior, data);
  ObservationEStepOptions estep_options;
  estep_options.max_alpha_iterations = 1;
  estep_options.alpha_tolerance = 1e-3;
  const ObservationEStep estep(mdp, data, prior, estep_options);  // (it may merge identical observations: keep ours)
  LearnOptions learn;
  learn.seed = seed;
  learn.threads = 1;
  learn.theta_tolerance = 1e-3;
  learn.likelihood_tolerance = 1e-6;
  const LearnResult learned = learn_reward(mdp, estep, learn);
  const RestartResult& best = learned.restarts[static_cast<size_t>(learned.selected_restart)];
  Fit out;
  const InverseLearningError ile = inverse_learning_error(mdp, s.task.true_weights, learned.theta);
  out.ile = ile.ile;
  out.ile_relative = ile.relative();
  Eigen::Index goal = 0;
  learned.theta.maxCoeff(&goal);
  out.goal_recovered = goal == s.task.goal;
  out.evaluations = best.em_evaluations;
  const ObservationPrior& alpha = best.alpha ? *best.alpha : prior;
  // Every observation here has its labeller's context, so learned eta maps back to it.
  if (const std::optional<RowMatrix> eta = estep.learned_eta(alpha)) {
    for (auto& t : data) t = ObservationEStep::with_eta(t, *eta);
    out.subject_eta = (*eta)(0, 0);
  }
  const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(learned.theta));
  out.label_accuracy = subject_label_accuracy(mdp, policy, dirichlet_mean(alpha), data, s.observations.true_sources);
  return out;
}

// The numbers every run row has.
template <typename Run>
void record(const Fit& f, Run& r) {
  r.ile = f.ile;
  r.ile_relative = f.ile_relative;
  r.goal_recovered = f.goal_recovered;
  r.label_accuracy = f.label_accuracy;
  r.em_evaluations = f.evaluations;
}

std::uint64_t run_seed(std::uint64_t seed, int run, int confounders, int cell) {
  return Rng(seed)
      .split(static_cast<std::uint64_t>(run))
      .split(3000 + static_cast<std::uint64_t>(confounders))
      .split(static_cast<std::uint64_t>(cell))
      .next_u64();
}

// Runs `work(i)` for every item on the threads, each failure kept as its item's error.
template <typename Run, typename Work>
void run_items(std::vector<Run>& runs, int threads, const std::function<void(int, int)>& progress, Work work) {
  std::atomic<int> done{0};
  const int total = static_cast<int>(runs.size());
  parallel_for(total, threads, [&](int i) {
    Run& r = runs[static_cast<size_t>(i)];
    const auto start = std::chrono::steady_clock::now();
    try {
      work(r);
    } catch (const std::exception& e) {
      r.error = e.what();  // one failed run must not lose the others
    }
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const int finished = ++done;
    if (progress) progress(finished, total);
  });
}

// The unlisted experiment's labeller (eta_experiments.hpp): it knows the subject and the
// first `told` elements.
void assign_told_eta(GridworldObservations& observations, int told, Rng& rng) {
  const int known = 1 + told;
  for (size_t i = 0; i < observations.trajectories.size(); ++i) {
    ObservedTrajectory& observed = observations.trajectories[i];
    const int n = observed.num_observations();
    observed.eta.resize(n, known);
    observed.contexts.assign(static_cast<size_t>(n), 0);
    for (int row = 0; row < n; ++row) {
      const int source = observations.true_sources[i][static_cast<size_t>(row)];
      const bool recognised = source < known && rng.uniform() < 0.8;
      const int pick = recognised ? source : rng.uniform_int(known);
      if (known == 1) {
        observed.eta(row, 0) = 1.0;
      } else {
        observed.eta.row(row).setConstant(0.4 / told);
        observed.eta(row, pick) = 0.6;
      }
      observed.contexts[static_cast<size_t>(row)] = pick;
    }
  }
}

}  // namespace

std::vector<EtaRun> run_eta_sensitivity(const EtaSensitivityOptions& o) {
  std::vector<EtaRun> runs;
  for (int run = 0; run < o.runs; ++run) {
    for (int e : o.confounders) {
      const auto add = [&](double m, double q, const char* method) {
        EtaRun r;
        r.run = run, r.confounders = e, r.mass = m, r.accuracy = q, r.method = method;
        runs.push_back(r);
      };
      add(1.0, 1.0, "perfect");
      for (double m : o.masses) {
        for (double q : o.accuracies) {
          for (const char* method : {"fixed", "learned"}) add(m, q, method);
        }
      }
    }
  }
  run_items(runs, o.threads, o.progress, [&](EtaRun& r) {
    const GridworldScenario s = make_gridworld_scenario(o.scenario, r.run, r.confounders);
    // The labeller's draws depend on (run, |E|, mass, accuracy): fixed and learned eta see the same eta.
    const int cell = static_cast<int>(std::lround(r.mass * 1000) * 10000 + std::lround(r.accuracy * 1000));
    Rng labeller_rng(run_seed(o.scenario.seed, r.run, r.confounders, cell));
    GridworldObservations observed = s.observations;
    assign_labeller_eta(observed, 1 + r.confounders, Labeller{r.mass, r.accuracy}, labeller_rng);
    ObservationPrior prior = gridworld_prior(s, r.confounders);
    prior.learn_eta = r.method == "learned";
    prior.eta_strength = o.eta_prior_strength;
    const Fit f =
        fit(s, std::move(observed.trajectories), prior, run_seed(o.scenario.seed, r.run, r.confounders, cell + 1));
    record(f, r);
    r.subject_eta = f.subject_eta;
  });
  return runs;
}

std::string eta_runs_csv(const std::vector<EtaRun>& runs) {
  std::ostringstream out;
  out.precision(10);
  out << "run,confounders,mass,accuracy,method,ile,ile_relative,goal_recovered,subject_eta,label_accuracy,em_"
         "evaluations,seconds,error\n";
  for (const auto& r : runs) {
    out << r.run << "," << r.confounders << "," << r.mass << "," << r.accuracy << "," << r.method << "," << r.ile << ","
        << r.ile_relative << "," << (r.goal_recovered ? 1 : 0) << ",";
    if (r.subject_eta >= 0.0) out << r.subject_eta;
    out << "," << r.label_accuracy << "," << r.em_evaluations << "," << r.seconds << "," << csv_text(r.error) << "\n";
  }
  return out.str();
}

std::vector<UnlistedRun> run_unlisted(const UnlistedOptions& o) {
  std::vector<UnlistedRun> runs;
  for (int run = 0; run < o.runs; ++run) {
    for (int e : o.confounders) {
      const auto add = [&](int told, const char* method) {
        UnlistedRun r;
        r.run = run, r.confounders = e, r.told = told, r.method = method;
        runs.push_back(r);
      };
      for (int told : o.told) {
        for (const char* method : {"as_told", "catch_all", "catch_all_learned_eta"}) add(told, method);
      }
      add(e, "oracle");
    }
  }
  run_items(runs, o.threads, o.progress, [&](UnlistedRun& r) {
    const GridworldScenario s = make_gridworld_scenario(o.scenario, r.run, r.confounders);
    Rng labeller_rng(run_seed(o.scenario.seed, r.run, r.confounders, 7000 + r.told));
    GridworldObservations observed = s.observations;
    assign_told_eta(observed, r.told, labeller_rng);
    ObservationPrior prior = gridworld_prior(s, r.told);
    if (r.method != "as_told" && r.method != "oracle") {
      prior.unlisted_eta = o.unlisted_eta;
      prior.learn_eta = r.method == "catch_all_learned_eta";
    }
    record(
        fit(s, std::move(observed.trajectories), prior, run_seed(o.scenario.seed, r.run, r.confounders, 8000 + r.told)),
        r);
  });
  return runs;
}

std::string unlisted_runs_csv(const std::vector<UnlistedRun>& runs) {
  std::ostringstream out;
  out.precision(10);
  out << "run,confounders,told,method,ile,ile_relative,goal_recovered,label_accuracy,em_evaluations,seconds,error\n";
  for (const auto& r : runs) {
    out << r.run << "," << r.confounders << "," << r.told << "," << r.method << "," << r.ile << "," << r.ile_relative
        << "," << (r.goal_recovered ? 1 : 0) << "," << r.label_accuracy << "," << r.em_evaluations << "," << r.seconds
        << "," << csv_text(r.error) << "\n";
  }
  return out.str();
}

}  // namespace hbirl
