#pragma once
// The paper's Gridworld experiment (paper §Experiments A, Fig. 3; docs/results.md "Results"): ILE of five
// methods as the number of confounding elements |E| grows.
//
// A run r at |E| = E: the task (goal corner, 20 soft-expert trajectories of 10 steps,
// and the controlled run that gives the subject prior) depends on r only, so every |E|
// sees the same expert; the elements' observation functions and the 40 observations per
// step depend on (r, E); and the five methods of a run see the same observations.
//   True Trajectories        MaxCausalEnt on the true (s, a).
//   True Observation Function O of subject and elements known (not learned), eta uniform.
//   Uniform eta              O learned: subject prior from the controlled run, symmetric
//                            prior for the elements, eta uniform.
//   Plausible eta            as Uniform, but with probability 0.8 the true source gets 0.6
//                            of eta, otherwise a random source does; the rest evenly.
//   Ignore CE                every observation treated as the subject's (no elements).
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "experiments/gridworld_scenario.hpp"
#include "learner/observations.hpp"

namespace hbirl {

enum class GridworldMethod { kTrueTrajectories, kTrueObservationFunction, kUniformEta, kPlausibleEta, kIgnoreCE };

const std::vector<GridworldMethod>& all_gridworld_methods();
std::string method_label(GridworldMethod method);  // "Plausible eta" (as in the paper's legend)
std::string method_key(GridworldMethod method);    // "plausible_eta"
bool parse_method(const std::string& key, GridworldMethod& method);

struct GridworldExperimentOptions {
  std::vector<int> confounders = {0, 1, 3, 5, 7, 9, 11, 13, 15};
  std::vector<GridworldMethod> methods = all_gridworld_methods();
  int runs = 65;
  std::uint64_t seed = 1;
  int size = 5;
  int trajectories = 20;
  int length = 10;
  int per_step = 40;
  // EM schedule. One alpha refinement per E-step, interleaved with the M-steps (same
  // fixed point as refining to convergence inside every E-step, ~4x fewer passes), and
  // tolerances that left the greedy policy -- hence ILE -- unchanged when they were chosen
  // (not re-measured with the exact posterior step: docs/MODEL.md).
  AlphaUpdate update = AlphaUpdate::kPosterior;  // observation-model refinement (observation_model.hpp)
  double c = 0.5;                                // the paper's step size (Algorithm 1; update paper only)
  int max_alpha_iterations = 1;                  // alpha refinements per E-step (see ObservationEStepOptions)
  double alpha_tolerance = 1e-3;
  double theta_tolerance = 1e-3;  // EM stopping rule, see LearnOptions
  double likelihood_tolerance = 1e-6;
  bool accelerate = true;  // SQUAREM-accelerated EM (see LearnOptions; converges properly)
  int restarts = 1;
  bool tie_actions = false;  // the subject prior tied across a state's actions (ObservationPrior::tie_actions)
  int threads = 0;           // over (run, |E|, method) items; results do not depend on it
  std::function<void(int done, int total)> progress;  // called from worker threads
};

struct GridworldRun {
  int run = 0;
  int confounders = 0;
  GridworldMethod method = GridworldMethod::kTrueTrajectories;
  int goal = 0;
  double ile = 0.0;
  double ile_relative = 0.0;
  bool goal_recovered = false;
  int em_evaluations = 0;
  double log_likelihood = 0.0;    // of the data at the learned weights (observations or true steps)
  double source_accuracy = -1.0;  // share of observations whose most probable source is the true one; -1 if n/a
  double strength = -1.0;         // the posterior update's chosen subject prior strength; -1 if n/a
  double seconds = 0.0;
  std::string error;  // non-empty if the run failed (then the numbers above are meaningless)
};

std::vector<GridworldRun> run_gridworld_experiment(const GridworldExperimentOptions& options);

// What a method of the figure learns from in run `run` of the seed `seed` with `confounders`
// elements: the scenario's observations with the method's eta, and its observation prior
// (the observation-model update and c left at their defaults).
struct GridworldMethodData {
  GridworldObservations observations;
  ObservationPrior prior;
};
GridworldMethodData gridworld_method_data(const GridworldScenario& s, GridworldMethod method, std::uint64_t seed,
                                          int run, int confounders);

std::string gridworld_runs_csv(const std::vector<GridworldRun>& runs);

}  // namespace hbirl
