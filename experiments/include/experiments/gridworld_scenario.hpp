#pragma once
// One run of the paper's Gridworld as the experiments watch it (paper §Experiments A): the
// task, the sensor and what it saw, shared by the methods of a run and by the experiments
// built on it (gridworld_experiment.hpp, eta_experiments.hpp).
//
// The task (goal corner, soft-expert demonstrations, the controlled run that gives the
// subject prior) depends on (seed, run) only, so every |E| sees the same expert; the
// elements' observation functions and the observations depend on (seed, run, |E|). The
// observations keep their true sources; eta is assigned per method.
#include <cstdint>

#include "learner/estep_exact.hpp"
#include "sim_driver/gridworld/observations.hpp"

namespace hbirl {

struct GridworldScenarioOptions {
  std::uint64_t seed = 1;
  int size = 5;
  int trajectories = 20;
  int length = 10;
  int per_step = 40;
};

struct GridworldScenario {
  GridworldTask task;
  Eigen::MatrixXd subject_o;
  Eigen::MatrixXd confounder_o;
  Eigen::MatrixXd controlled_alpha;  // the subject's Dirichlet prior from the controlled run
  GridworldObservations observations;
};

GridworldScenario make_gridworld_scenario(const GridworldScenarioOptions& o, int run, int confounders);

// The share of observations whose most probable source under (policy, model) is the true
// one; -1 when there are none.
double source_accuracy(const Mdp& mdp, const SoftSolution& policy, const ObservationModel& model,
                       const GridworldObservations& observations);

// The same, for subject-or-not only: the posterior's subject share above 1/2 and the true
// source the subject, or neither (comparable between models with different source sets).
double subject_label_accuracy(const Mdp& mdp, const SoftSolution& policy, const ObservationModel& model,
                              const std::vector<ObservedTrajectory>& trajectories,
                              const std::vector<std::vector<int>>& true_sources);

}  // namespace hbirl
