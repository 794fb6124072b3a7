#pragma once
// HiddenDataEM (paper §II-A, Algorithm 1) with random restarts (docs/MODEL.md "Restarts and selection").
//
// Each restart alternates
//   E-step: N_hat = E[visits | data; theta]             (EStep::expect)
//   M-step: theta = argmax_theta CausalLikelihood(N_hat) (maxcausalent.hpp)
// until theta and the log-likelihood stop changing. With known trajectories the E-step
// does not depend on theta and this is plain MaxCausalEnt IRL (one M-step).
//
// Restarts: restart 0 starts from theta = 0, restart r > 0 from theta ~ U[-1, 1]^K drawn
// from the stream r of the seed, and a warm start (LearnOptions::warm_start) after them. Selection rule: the restart
// with the highest score -- the log-likelihood of the data (with the posterior observation-model update and an
// automatic prior strength, the held-out log-likelihood that chose the strength) --
// minus the L2 penalty when one is set; ties go to the lowest restart index.
//
// When the E-step has a hyper-parameter to choose from the data (the posterior update's
// prior strength), EM runs to convergence, the E-step chooses it there, and EM resumes
// with the new value until the choice stands (at most 4 times). Restarts run in parallel; the result is bit-identical
// for any thread count.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "learner/estep.hpp"
#include "learner/optimize.hpp"

namespace hbirl {

struct LearnOptions {
  OptimizerOptions optimizer;
  double l2 = 0.0;  // penalty on ||theta||^2, per demonstrated step (see CausalLikelihood)
  int restarts = 1;
  std::uint64_t seed = 1;
  int threads = 0;  // 0 = one per core
  int max_em_iterations = 300;
  // EM stops when max|theta change| <= theta_tolerance * max(1, max|theta|), the
  // log-likelihood change <= likelihood_tolerance * max(1, |log-likelihood|), and the
  // E-step reports its observation model converged.
  double theta_tolerance = 1e-4;
  double likelihood_tolerance = 1e-7;
  // Accelerate EM with SQUAREM (same fixed points, far fewer E-steps). Needs a
  // deterministic E-step: turn it off for sampling engines.
  bool accelerate = true;
  SoftViOptions soft_vi;
  // A start point besides the restarts' (the previous estimate, when learning while the
  // demonstrations arrive: app::learn_anytime): EM also runs from it, as restart
  // `restarts`, and the selection rule chooses among all -- so the result is never worse,
  // by that rule, than without it.
  std::optional<Eigen::VectorXd> warm_start;
};

// Called after every accepted EM iterate (from the restart's thread; SQUAREM's rejected
// extrapolations are not iterates): restart index, iterate number (1, 2, ...), objective
// (EStepResult::objective), theta, the E-step's report, and the observation model's
// refined Dirichlet parameters (nullptr when O is not learned).
using IterationReport =
    std::function<void(int, int, double, const Eigen::VectorXd&, const EStepResult&, const ObservationPrior*)>;

struct RestartResult {
  Eigen::VectorXd initial_theta;
  Eigen::VectorXd theta;
  double log_likelihood = 0.0;  // log Pr(data | theta, O) with O the mean of the learned model
  double objective = 0.0;       // EM's objective (EStepResult::objective)
  // The held-out log-likelihood that chose the prior strength (EStep::choose_strength),
  // when one was chosen.
  std::optional<double> held_out_log_likelihood;
  // The selection score: the held-out log-likelihood when there is one, else the
  // objective; minus (l2 / 2) M ||theta||^2.
  double score = 0.0;
  int em_iterations = 0;   // iterates EM kept (those reported to on_iteration)
  int em_evaluations = 0;  // EM map evaluations (E-step + M-step), the cost: SQUAREM's rejected extrapolations too
  int optimizer_iterations = 0;  // summed over M-steps
  bool converged = false;
  std::string optimizer_status;
  std::optional<ObservationPrior> alpha;  // the refined observation-model parameters, if any
};

struct LearnResult {
  Eigen::VectorXd theta;
  double log_likelihood = 0.0;
  double objective = 0.0;
  int selected_restart = 0;
  std::vector<RestartResult> restarts;
};

LearnResult learn_reward(const Mdp& mdp, const EStep& estep, const LearnOptions& options,
                         const IterationReport& on_iteration = nullptr);

}  // namespace hbirl
