#include "experiments/onion_experiment.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "experiments/learning_run.hpp"
#include "experiments/onion_data.hpp"
#include "experiments/summary.hpp"
#include "learner/controlled_prior.hpp"
#include "learner/estep_observations.hpp"
#include "learner/hidden_data_em.hpp"
#include "learner/metrics.hpp"
#include "learner/parallel.hpp"
#include "sim_driver/onion/onion.hpp"

namespace hbirl::onion {

namespace {

std::vector<ObservedTrajectory> first(const std::vector<ObservedTrajectory>& all, int n) {
  return {all.begin(), all.begin() + n};
}

// Per step, the (s, a) whose subject O best explains all of its observations.
std::vector<Trajectory> ml_trajectories(const Mdp& mdp, const Eigen::MatrixXd& subject_o,
                                        const std::vector<ObservedTrajectory>& observed) {
  const Eigen::MatrixXd log_o = subject_o.array().log();
  std::vector<Trajectory> out;
  for (const auto& o : observed) {
    Trajectory t;
    for (int step = 0; step < o.length(); ++step) {
      if (o.observations_at(step) == 0) continue;  // occluded: nothing to go by
      double best = -std::numeric_limits<double>::infinity();
      StateAction pick{-1, -1};
      for (int s = 0; s < mdp.num_states; ++s) {
        if (mdp.is_terminal(s)) continue;
        for (int a = 0; a < mdp.num_actions; ++a) {
          if (!mdp.available(s, a)) continue;
          double ll = 0.0;
          for (int n = o.step_begin[static_cast<size_t>(step)]; n < o.step_begin[static_cast<size_t>(step) + 1]; ++n) {
            ll += o.weight(n) * log_o(mdp.pair(s, a), o.symbols[static_cast<size_t>(n)]);
          }
          if (ll > best) {
            best = ll;
            pick = {s, a};
          }
        }
      }
      t.push_back(pick);
    }
    if (!t.empty()) out.push_back(std::move(t));
  }
  return out;
}

// Only the observations whose eta makes the subject strictly most likely, as the subject's.
std::vector<ObservedTrajectory> ml_observations(const std::vector<ObservedTrajectory>& observed) {
  std::vector<ObservedTrajectory> out;
  for (const auto& o : observed) {
    ObservedTrajectory kept;
    kept.ends_in_terminal = o.ends_in_terminal;
    kept.end_state = o.end_state;
    kept.end_symbols = o.end_symbols;
    for (int t = 0; t < o.length(); ++t) {
      for (int n = o.step_begin[static_cast<size_t>(t)]; n < o.step_begin[static_cast<size_t>(t) + 1]; ++n) {
        const double subject = o.eta(n, 0);
        const bool most_likely = o.eta.cols() == 1 || subject > o.eta.row(n).tail(o.eta.cols() - 1).maxCoeff();
        if (most_likely) kept.symbols.push_back(o.symbols[static_cast<size_t>(n)]);
      }
      kept.step_begin.push_back(static_cast<int>(kept.symbols.size()));
    }
    kept.eta = RowMatrix::Ones(static_cast<Eigen::Index>(kept.symbols.size()), 1);
    out.push_back(std::move(kept));
  }
  return out;
}

std::vector<ObservedTrajectory> with_uniform_eta(std::vector<ObservedTrajectory> observed) {
  for (auto& o : observed) o.eta.setConstant(1.0 / static_cast<double>(o.eta.cols()));
  return observed;
}

}  // namespace

const std::vector<OnionMethod>& all_onion_methods() {
  static const std::vector<OnionMethod> methods = {OnionMethod::kTrueTrajectories, OnionMethod::kMlTrajectories,
                                                   OnionMethod::kMlObservations, OnionMethod::kPlausibleEta,
                                                   OnionMethod::kUniformEta};
  return methods;
}

std::string method_label(OnionMethod m) {
  switch (m) {
    case OnionMethod::kTrueTrajectories:
      return "True Trajectories";
    case OnionMethod::kMlTrajectories:
      return "ML Trajectories";
    case OnionMethod::kMlObservations:
      return "ML Observations";
    case OnionMethod::kPlausibleEta:
      return "Plausible eta";
    case OnionMethod::kUniformEta:
      return "Uniform eta";
  }
  return "?";
}

std::string method_key(OnionMethod m) {
  switch (m) {
    case OnionMethod::kTrueTrajectories:
      return "true_trajectories";
    case OnionMethod::kMlTrajectories:
      return "ml_trajectories";
    case OnionMethod::kMlObservations:
      return "ml_observations";
    case OnionMethod::kPlausibleEta:
      return "plausible_eta";
    case OnionMethod::kUniformEta:
      return "uniform_eta";
  }
  return "?";
}

bool parse_method(const std::string& key, OnionMethod& method) {
  for (OnionMethod m : all_onion_methods()) {
    if (method_key(m) == key) {
      method = m;
      return true;
    }
  }
  return false;
}

RowMatrix miscalibrated(const RowMatrix& eta, double power) {
  RowMatrix out = eta.array().pow(power).matrix();
  for (Eigen::Index n = 0; n < out.rows(); ++n) out.row(n) /= out.row(n).sum();
  return out;
}

namespace {

// The reward `method` learns from the first n sorts of run `run`'s demonstration.
LearnResult learn_onion_method(const OnionSetup& setup, OnionMethod method, const OnionDemonstration& demo, int n,
                               int run, const OnionExperimentOptions& o) {
  const Mdp& mdp = setup.mdp;
  const Eigen::MatrixXd& subject_o = setup.subject_o;
  const LearnOptions learn = learning_run_options(o, run, n);
  ObservationPrior prior = onion_prior(setup, o);
  ObservationEStepOptions estep_options;
  estep_options.max_alpha_iterations = o.max_alpha_iterations;
  estep_options.alpha_tolerance = o.alpha_tolerance;
  const std::vector<ObservedTrajectory> observed = first(demo.observed, n);
  switch (method) {
    case OnionMethod::kTrueTrajectories: {
      const std::vector<Trajectory> truth(demo.truth.begin(), demo.truth.begin() + n);
      return learn_reward(mdp, TruthEStep(mdp, truth), learn);
    }
    case OnionMethod::kMlTrajectories:
      return learn_reward(mdp, TruthEStep(mdp, ml_trajectories(mdp, subject_o, observed)), learn);
    case OnionMethod::kMlObservations:
      prior.num_confounders = 0;
      prior.confounder_alpha = Eigen::MatrixXd::Zero(0, prior.num_symbols);
      return learn_reward(mdp, ObservationEStep(mdp, ml_observations(observed), prior, estep_options), learn);
    case OnionMethod::kPlausibleEta:
    case OnionMethod::kUniformEta:
      return learn_reward(
          mdp,
          ObservationEStep(mdp, method == OnionMethod::kUniformEta ? with_uniform_eta(observed) : observed, prior,
                           estep_options),
          learn);
  }
  return {};  // not reached: every method is a case
}

}  // namespace

OnionSetup onion_setup(const OnionExperimentOptions& o) {
  OnionSetup setup;
  SceneConfig controlled_scene = SceneConfig::controlled();
  controlled_scene.width = o.scene.width;
  controlled_scene.fps = o.scene.fps;
  controlled_scene.step_seconds = o.scene.step_seconds;
  DemonstrationOptions controlled_options;
  controlled_options.sorts = o.controlled_sorts;
  const OnionDemonstration controlled =
      demonstrate(setup.mdp, controlled_scene, controlled_options, Rng(o.seed).split(1u << 30).next_u64());
  setup.subject_alpha = controlled_run_prior(setup.mdp, controlled.truth, controlled.observed, perception::kNumSymbols,
                                             controlled_prior_options());
  setup.subject_o = dirichlet_mean(setup.subject_alpha);
  return setup;
}

OnionDemonstration onion_run_demonstration(const OnionExperimentOptions& o, const Mdp& mdp, int run, int sorts) {
  DemonstrationOptions options;
  options.sorts = sorts;
  options.start_time = 1000.0 * run;  // the confounders' clock: each run sees other moments
  OnionDemonstration demo =
      demonstrate(mdp, o.scene, options, Rng(o.seed).split(static_cast<std::uint64_t>(run)).next_u64());
  if (o.eta_power != 1.0) {
    for (ObservedTrajectory& t : demo.observed) t.eta = miscalibrated(t.eta, o.eta_power);
  }
  return demo;
}

ObservationPrior onion_prior(const OnionSetup& setup, const OnionExperimentOptions& o) {
  ObservationPrior prior;
  prior.num_symbols = perception::kNumSymbols;
  prior.subject_alpha = setup.subject_alpha;
  use_alpha_update(prior, o.update);
  prior.c = o.c;
  prior.num_confounders = perception::kNumSources - 1;
  prior.confounder_alpha = Eigen::MatrixXd::Ones(prior.num_confounders, prior.num_symbols);
  return prior;
}

std::vector<OnionRun> run_onion_experiment(const OnionExperimentOptions& o) {
  const OnionSetup setup = onion_setup(o);
  const Mdp& mdp = setup.mdp;
  const int most = *std::max_element(o.trajectories.begin(), o.trajectories.end());
  const size_t per_run = o.trajectories.size() * o.methods.size();
  std::vector<OnionRun> results(static_cast<size_t>(o.runs) * per_run);
  std::atomic<int> done{0};
  const int total = static_cast<int>(results.size());
  parallel_for(o.runs, o.threads, [&](int run) {
    const OnionDemonstration demo = onion_run_demonstration(o, mdp, run, most);
    for (size_t i = 0; i < o.trajectories.size(); ++i) {
      const int n = o.trajectories[i];
      for (size_t m = 0; m < o.methods.size(); ++m) {
        OnionRun& r = results[static_cast<size_t>(run) * per_run + i * o.methods.size() + m];
        r.run = run;
        r.trajectories = n;
        r.method = o.methods[m];
        const auto start = std::chrono::steady_clock::now();
        try {
          const LearnResult learned = learn_onion_method(setup, r.method, demo, n, run, o);
          const PolicyMetrics metrics = policy_metrics(mdp, expert_weights(), learned.theta);
          r.ile = metrics.ile.ile;
          r.ile_relative = metrics.ile.relative();
          r.policy_agreement = metrics.agreement;
          r.em_evaluations =
              learned.restarts[static_cast<size_t>(learned.selected_restart)].em_evaluations;  // the cost
          r.log_likelihood = learned.log_likelihood;
        } catch (const std::exception& e) {
          r.error = e.what();  // one failed run must not lose the others
        }
        r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        const int finished = ++done;
        if (o.progress) o.progress(finished, total);
      }
    }
  });
  return results;
}

std::string onion_runs_csv(const std::vector<OnionRun>& runs) {
  std::ostringstream out;
  out.precision(10);
  out << "run,method,trajectories,ile,ile_relative,policy_agreement,em_evaluations,log_likelihood,seconds,error\n";
  for (const auto& r : runs) {
    const std::string error = csv_text(r.error);
    out << r.run << "," << method_key(r.method) << "," << r.trajectories << "," << r.ile << "," << r.ile_relative << ","
        << r.policy_agreement << "," << r.em_evaluations << "," << r.log_likelihood << "," << r.seconds << "," << error
        << "\n";
  }
  return out.str();
}

}  // namespace hbirl::onion
