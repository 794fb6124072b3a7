#pragma once
// What the learner sees in the paper's Gridworld (paper §Experiments A): 4 symbols, one per corner.
// The subject's true O makes symbol k exponentially more likely as the agent nears corner
// k, O_s(k) ∝ exp(-decay * manhattan(s, corner k)), whatever the action; each
// confounding element has a random observation function (a Dirichlet(1) draw). At each
// timestep `per_step` observations are made, each from the subject or one of the
// elements with equal probability, and labelled with a source distribution eta.
#include "learner/observations.hpp"
#include "learner/rng.hpp"
#include "learner/trajectory.hpp"
#include "sim_driver/gridworld/gridworld.hpp"

namespace hbirl {

enum class EtaKind {
  kUniform,    // eta = 1 / (1 + |E|) for every source
  kPlausible,  // with probability 0.8 the true source gets 0.6, else a random source does; the rest evenly
  kSubject,    // eta = (1, 0, ..., 0): every observation treated as the subject's ("Ignore CE")
  kTrue,       // all of eta on the true source (a perfect labeller)
};

struct GridworldObservationOptions {
  int confounders = 3;
  int per_step = 40;
  double decay = 1.0;
  EtaKind eta = EtaKind::kPlausible;
  double occlusion = 0.0;  // chance that a step has no observations (no draw when 0)
};

// The subject's true O, one row per (s, a) pair (identical across actions).
Eigen::MatrixXd gridworld_subject_observation_model(int size, double decay);
// Random observation functions for the confounding elements, one row each.
Eigen::MatrixXd random_confounder_observation_model(int confounders, Rng& rng);

struct GridworldObservations {
  std::vector<ObservedTrajectory> trajectories;
  std::vector<std::vector<int>> true_sources;  // per trajectory, per observation: 0 subject, e + 1 element e
};

// Observes trajectories: each step is occluded with probability options.occlusion, else
// `per_step` observations are made; each observation's source is drawn uniformly from the subject and
// the elements; the symbol from that source's O. eta by `options.eta` (kSubject makes eta
// a single entry, as for a model without confounders).
GridworldObservations observe_gridworld(const Mdp& mdp, const std::vector<Trajectory>& trajectories,
                                        const Eigen::MatrixXd& subject_o, const Eigen::MatrixXd& confounder_o,
                                        const GridworldObservationOptions& options, Rng& rng);

// Replaces the source distributions of observations whose true sources are known, by
// `kind` over `sources` = 1 + |E| sources (kSubject: a single column). Draws from `rng`
// only for kPlausible.
void assign_eta(GridworldObservations& observations, int sources, EtaKind kind, Rng& rng);

// What an eta that assign_eta stated says of the true source, when the sources are drawn
// from `mixture` (1 + |E| entries): Pr(source | stated eta), by Bayes' rule over assign_eta's
// own draw (kPlausible: the favoured source is the true one with probability 0.8, else any
// source evenly; kUniform says nothing; kTrue everything). The most a learner could read
// from the labeller: the oracles' eta (random_tasks_experiment.hpp).
Eigen::RowVectorXd calibrated_eta(const Eigen::RowVectorXd& stated, const Eigen::RowVectorXd& mixture, EtaKind kind);

// A labeller that claims more (or less) than it knows (docs/results/eta_sensitivity): it
// picks the true source with probability `accuracy`, else one of the other sources evenly,
// and gives its pick `mass` of eta and the other sources the rest evenly. The pick is the
// observation's context (the labeller's "rule"). With equally likely sources, among the
// observations it labels z the true source is z with probability `accuracy` and each other
// one with (1 - accuracy) / |E|: its true calibration, which it states as `mass`.
struct Labeller {
  double mass = 0.8;
  double accuracy = 0.8;
};
// The true source distribution of the context "pick = z" over `sources` sources.
Eigen::VectorXd labeller_calibration(const Labeller& labeller, int sources, int pick);
void assign_labeller_eta(GridworldObservations& observations, int sources, const Labeller& labeller, Rng& rng);

// The informative subject prior (paper §Experiments A): symbol counts per (s, a) from a controlled run
// (the subject alone, true states known), plus `pseudo_count` everywhere.
Eigen::MatrixXd controlled_run_alpha(const Mdp& mdp, const std::vector<Trajectory>& trajectories,
                                     const Eigen::MatrixXd& subject_o, int per_step, double pseudo_count, Rng& rng);

}  // namespace hbirl
