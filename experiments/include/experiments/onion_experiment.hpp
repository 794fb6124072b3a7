#pragma once
// The paper's onion-sorting experiment (paper §Experiments B, Fig. 4; docs/results.md "Results"): ILE of
// five methods as the number of demonstrated sorts grows, all from rendered frames.
//
// One controlled run (no confounding elements, no mirror, true states known) gives the
// subject prior for every run (onion_data.hpp). A run r renders, perceives and labels
// max(trajectories) sorts in the scene of `scene` (by default all three confounding
// elements and the mirror);
// the point at n trajectories learns from its first n sorts.
//   True Trajectories   MaxCausalEnt on the true (s, a).
//   ML trajectories     per step the (s, a) whose subject O (the controlled prior's mean)
//                       best explains all of the step's observations, then MaxCausalEnt;
//                       occluded steps are left out.
//   ML observations     only the observations whose eta makes the subject most likely,
//                       as the subject's, in the model without confounding elements.
//   Plausible eta       the partially-controlled model with the labeller's eta.
//   Uniform eta         the same with eta uniform over the four sources.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "experiments/onion_data.hpp"
#include "learner/observations.hpp"
#include "sim_driver/onion/onion.hpp"
#include "sim_driver/onion/scene.hpp"

namespace hbirl::onion {

enum class OnionMethod { kTrueTrajectories, kMlTrajectories, kMlObservations, kPlausibleEta, kUniformEta };

const std::vector<OnionMethod>& all_onion_methods();
std::string method_label(OnionMethod method);  // as in the paper's legend
std::string method_key(OnionMethod method);
bool parse_method(const std::string& key, OnionMethod& method);

struct OnionExperimentOptions {
  std::vector<int> trajectories = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
  std::vector<OnionMethod> methods = all_onion_methods();
  int runs = 100;
  std::uint64_t seed = 1;
  int controlled_sorts = 20;
  SceneConfig scene;  // the demonstrations' scene (width, fps, which elements)
  // The labeller's eta raised to this power and renormalised: 1 as it states, > 1 an
  // overconfident labeller (its favoured source gets more than it knows), < 1 a timid one.
  double eta_power = 1.0;
  AlphaUpdate update = AlphaUpdate::kPosterior;  // observation-model refinement (observation_model.hpp)
  double c = 0.5;
  int max_alpha_iterations = 1;
  double alpha_tolerance = 1e-3;
  double theta_tolerance = 1e-3;
  double likelihood_tolerance = 1e-6;
  int restarts = 1;
  int threads = 0;
  std::function<void(int done, int total)> progress;  // called from worker threads
};

struct OnionRun {
  int run = 0;
  int trajectories = 0;
  OnionMethod method = OnionMethod::kTrueTrajectories;
  double ile = 0.0;
  double ile_relative = 0.0;
  double policy_agreement = 0.0;
  int em_evaluations = 0;
  double log_likelihood = 0.0;
  double seconds = 0.0;
  std::string error;
};

std::vector<OnionRun> run_onion_experiment(const OnionExperimentOptions& options);

// What every run learns with: the MDP, and the subject prior from a controlled run of
// options.controlled_sorts sorts (its alpha, and its mean O for ML Trajectories).
struct OnionSetup {
  Mdp mdp = make_onion_mdp();
  Eigen::MatrixXd subject_alpha;
  Eigen::MatrixXd subject_o;
};
OnionSetup onion_setup(const OnionExperimentOptions& options);
// Run `run`'s demonstration: `sorts` sorts rendered, perceived and labelled in options.scene
// (eta miscalibrated by options.eta_power); the figure's point at n learns from its first n.
OnionDemonstration onion_run_demonstration(const OnionExperimentOptions& options, const Mdp& mdp, int run, int sorts);
// The partially-controlled model's prior (Plausible and Uniform eta): the subject's from the
// controlled run, the three confounding elements' flat.
ObservationPrior onion_prior(const OnionSetup& setup, const OnionExperimentOptions& options);
// Each row of eta raised to `power` and renormalised (OnionExperimentOptions::eta_power).
RowMatrix miscalibrated(const RowMatrix& eta, double power);
std::string onion_runs_csv(const std::vector<OnionRun>& runs);

}  // namespace hbirl::onion
