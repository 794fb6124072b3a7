#include "learner/observation_support.hpp"

#include <gtest/gtest.h>

#include "learner/brute_force_posterior.hpp"
#include "learner/random_mdp.hpp"
#include "learner/soft_value_iteration.hpp"

namespace hbirl {
namespace {

using testing::brute_force;
using testing::random_mdp;

// An alpha matrix with many zeros (each row keeps at least one positive entry, as a
// Dirichlet prior must): the support the check reasons about.
Eigen::MatrixXd sparse_alpha(int rows, int symbols, Rng& rng) {
  Eigen::MatrixXd alpha = Eigen::MatrixXd::Zero(rows, symbols);
  for (int r = 0; r < rows; ++r) {
    for (int w = 0; w < symbols; ++w) alpha(r, w) = rng.uniform() < 0.5 ? 0.0 : 0.5 + rng.uniform();
    if (alpha.row(r).sum() == 0.0) alpha(r, rng.uniform_int(symbols)) = 1.0;
  }
  return alpha;
}

// Against independent truth: a trajectory's probability, summed by brute force over every
// state-action sequence and every labelling of its observations, is 0 exactly when the
// check names one of its observations (or steps) -- on 400 random tasks with terminal
// states, impossible actions, deterministic moves, zeros in alpha and in eta.
TEST(ObservationSupport, ImpossibleExactlyWhenTheBruteForceLikelihoodIsZero) {
  Rng rng(17);
  int impossible = 0, possible = 0, seen_ends = 0, only_by_end = 0, reported_ends = 0, only_by_report = 0;
  for (int trial = 0; trial < 400; ++trial) {
    testing::RandomMdpOptions o = testing::varied_options(trial);
    o.states = std::min(o.states, 4);
    o.successors = std::min(o.successors, o.states);
    o.actions = std::min(o.actions, 2);
    o.terminal = std::min(o.terminal, o.states - 1);
    if (trial % 5 == 3) {  // two terminal states, few successors: which one was entered matters
      o.states = 4;
      o.terminal = 2;
      o.successors = 2;
    }
    const Mdp mdp = random_mdp(o, rng);
    ObservationPrior prior;
    prior.num_symbols = 2 + trial % 2;
    prior.num_confounders = trial % 3 == 0 ? 0 : 1;
    prior.subject_alpha = sparse_alpha(mdp.num_pairs(), prior.num_symbols, rng);
    prior.confounder_alpha = sparse_alpha(prior.num_confounders, prior.num_symbols, rng);
    ObservedTrajectory t;
    const int length = 1 + rng.uniform_int(3);
    std::vector<double> eta;
    for (int step = 0; step < length; ++step) {
      const int n = rng.uniform_int(3);
      for (int k = 0; k < n; ++k) {
        t.symbols.push_back(rng.uniform_int(prior.num_symbols));
        const double subject = prior.num_confounders == 0 ? 1.0
                                                          : (rng.uniform() < 0.3   ? 1.0
                                                             : rng.uniform() < 0.3 ? 0.0
                                                                                   : 0.5);
        eta.push_back(subject);
        if (prior.num_confounders == 1) eta.push_back(1.0 - subject);
      }
      t.step_begin.push_back(static_cast<int>(t.symbols.size()));
    }
    t.eta =
        Eigen::Map<const RowMatrix>(eta.data(), static_cast<Eigen::Index>(t.symbols.size()), 1 + prior.num_confounders);
    t.ends_in_terminal = o.terminal > 0 && rng.uniform() < 0.5;
    // Now and then the terminal state entered was seen: one of them (the last o.terminal states).
    if (t.ends_in_terminal && rng.uniform() < 0.5) t.end_state = o.states - 1 - rng.uniform_int(o.terminal);
    // Now and then an end sensor reported on it, with zeros in its prior (its own stream).
    Rng end_rng(static_cast<std::uint64_t>(trial));
    if (t.ends_in_terminal && t.end_state < 0 && end_rng.uniform() < 0.6) {
      prior.end_alpha = sparse_alpha(mdp.num_states, 2, end_rng);
      for (int k = 1 + end_rng.uniform_int(2); k > 0; --k) t.end_symbols.push_back(end_rng.uniform_int(2));
    }
    ObservationModel model;
    model.subject = prior.subject_alpha.array().colwise() / prior.subject_alpha.rowwise().sum().array();
    model.confounders = prior.confounder_alpha;
    if (prior.num_confounders > 0) {
      model.confounders = prior.confounder_alpha.array().colwise() / prior.confounder_alpha.rowwise().sum().array();
    }
    if (prior.end_alpha.size() > 0)
      model.end = prior.end_alpha.array().colwise() / prior.end_alpha.rowwise().sum().array();
    const SoftSolution policy = soft_value_iteration(mdp, Eigen::VectorXd::Zero(mdp.num_pairs()));  // full support
    const bool zero = brute_force(mdp, policy, model, t).likelihood == 0.0;
    const auto found = first_impossible_observation(mdp, {t}, prior);
    EXPECT_EQ(found.has_value(), zero) << "trial " << trial << (found ? ": " + found->why : "");
    (zero ? impossible : possible) += 1;
    seen_ends += t.end_state >= 0;
    if (zero && t.end_state >= 0) {  // impossible only because of which terminal state was entered?
      ObservedTrajectory unseen = t;
      unseen.end_state = -1;
      only_by_end += brute_force(mdp, policy, model, unseen).likelihood > 0.0;
    }
    reported_ends += !t.end_symbols.empty();
    if (zero && !t.end_symbols.empty()) {  // impossible only because of what the end sensor said?
      ObservedTrajectory unreported = t;
      unreported.end_symbols.clear();
      only_by_report += brute_force(mdp, policy, model, unreported).likelihood > 0.0;
    }
  }
  // Both kinds were met often enough for the agreement to mean something.
  EXPECT_GT(seen_ends, 20);
  EXPECT_GE(only_by_end, 1);
  EXPECT_GT(reported_ends, 20);
  EXPECT_GE(only_by_report, 1);
  RecordProperty("only_by_report", only_by_report);
  EXPECT_GT(impossible, 40);
  EXPECT_GT(possible, 40);
}

// An end_state that is not a terminal state, or on a trajectory that did not end in one,
// is named, not learned from.
TEST(ObservationSupport, NamesAnEndStateThatCannotBe) {
  Rng rng(5);
  testing::RandomMdpOptions o;
  o.states = 4;
  o.terminal = 1;
  const Mdp mdp = random_mdp(o, rng);
  ObservationPrior prior;
  prior.num_symbols = 2;
  prior.subject_alpha = Eigen::MatrixXd::Ones(mdp.num_pairs(), 2);
  prior.confounder_alpha = Eigen::MatrixXd::Zero(0, 2);
  ObservedTrajectory t;
  t.step_begin = {0, 0};
  t.eta = RowMatrix(0, 1);
  t.ends_in_terminal = true;
  t.end_state = 0;  // not terminal
  auto found = first_impossible_observation(mdp, {t}, prior);
  ASSERT_TRUE(found.has_value());
  EXPECT_NE(found->why.find("end_state 0 is not a terminal state"), std::string::npos) << found->why;
  t.end_state = 3;
  t.ends_in_terminal = false;
  found = first_impossible_observation(mdp, {t}, prior);
  ASSERT_TRUE(found.has_value());
  EXPECT_NE(found->why.find("does not end in a terminal state"), std::string::npos) << found->why;
}

}  // namespace
}  // namespace hbirl
