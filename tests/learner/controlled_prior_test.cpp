#include "learner/controlled_prior.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "learner/input_error.hpp"

namespace hbirl {
namespace {

// Two states, two actions (action a moves to state a), three symbols; one controlled
// episode of three steps:
//   t = 0 in (0, 1): symbols 2, 2 (the second one standing for 3 identical ones)
//   t = 1 in (1, 0): no observation (occluded)
//   t = 2 in (0, 1): symbol 0
struct ControlledRun {
  Mdp mdp = make_mdp(2, 2, 1, {{0, 0, 0, 1.0}, {0, 1, 1, 1.0}, {1, 0, 0, 1.0}, {1, 1, 1, 1.0}}, {},
                     Eigen::Vector2d(1, 0), {}, 0.9);
  std::vector<Trajectory> truth{{{0, 1}, {1, 0}, {0, 1}}};
  std::vector<ObservedTrajectory> observed;
  ControlledRun() {
    ObservedTrajectory o;
    o.symbols = {2, 2, 0};
    o.weights = {1.0, 3.0, 1.0};
    o.step_begin = {0, 2, 2, 3};
    observed.push_back(o);
  }
};

// By hand: pair (0, 1) = row 1 saw symbol 2 four times and symbol 0 once in two visits;
// every other row saw nothing. Counts plus the pseudo-count, or per visit.
TEST(ControlledPrior, CountsByHand) {
  const ControlledRun run;
  ControlledPriorOptions options;
  options.pseudo_count = 0.5;
  const Eigen::MatrixXd alpha = controlled_run_prior(run.mdp, run.truth, run.observed, 3, options);
  ASSERT_EQ(alpha.rows(), 4);
  ASSERT_EQ(alpha.cols(), 3);
  Eigen::MatrixXd expected = Eigen::MatrixXd::Constant(4, 3, 0.5);
  expected(1, 2) += 4.0;
  expected(1, 0) += 1.0;
  EXPECT_EQ(alpha, expected);
  options.per_visit = true;
  const Eigen::MatrixXd per_visit = controlled_run_prior(run.mdp, run.truth, run.observed, 3, options);
  expected = Eigen::MatrixXd::Constant(4, 3, 0.5);
  expected(1, 2) += 2.0;
  expected(1, 0) += 0.5;
  EXPECT_EQ(per_visit, expected);  // (1, 0) was visited but saw nothing: the base alone
}

// No controlled run: the prior is the pseudo-count everywhere.
TEST(ControlledPrior, NoRunGivesTheBase) {
  const ControlledRun run;
  const Eigen::MatrixXd alpha = controlled_run_prior(run.mdp, {}, {}, 3);
  EXPECT_EQ(alpha, Eigen::MatrixXd::Ones(4, 3));
}

// Bad input is named: the field, not a crash or a silent out-of-bounds write.
TEST(ControlledPrior, BadRunsAreNamed) {
  const auto field = [](const std::function<void()>& f) {
    try {
      f();
    } catch (const InputError& e) {
      return e.field();
    }
    return std::string("no error");
  };
  ControlledRun run;
  EXPECT_EQ(field([&] { controlled_run_prior(run.mdp, run.truth, {}, 3); }), "ground_truth");
  EXPECT_EQ(field([&] { controlled_run_prior(run.mdp, run.truth, run.observed, 2); }), "observations.symbols");
  EXPECT_EQ(field([&] { controlled_run_prior(run.mdp, run.truth, run.observed, 0); }), "observations.num_symbols");
  ControlledRun short_truth;
  short_truth.truth[0].pop_back();
  EXPECT_EQ(field([&] { controlled_run_prior(short_truth.mdp, short_truth.truth, short_truth.observed, 3); }),
            "ground_truth");
  ControlledRun outside;
  outside.truth[0][1].state = 2;
  EXPECT_EQ(field([&] { controlled_run_prior(outside.mdp, outside.truth, outside.observed, 3); }), "ground_truth");
  outside.truth[0][1] = {1, -1};
  EXPECT_EQ(field([&] { controlled_run_prior(outside.mdp, outside.truth, outside.observed, 3); }), "ground_truth");
  // A malformed layout is refused before anything is read through it.
  const auto with = [&](const std::function<void(ObservedTrajectory&)>& spoil) {
    ControlledRun bad;
    spoil(bad.observed[0]);
    return field([&] { controlled_run_prior(bad.mdp, bad.truth, bad.observed, 3); });
  };
  EXPECT_EQ(with([](ObservedTrajectory& o) { o.step_begin = {1, 2, 2, 3}; }), "observations.step_begin");
  EXPECT_EQ(with([](ObservedTrajectory& o) { o.step_begin = {0, 3, 2, 3}; }), "observations.step_begin");
  EXPECT_EQ(with([](ObservedTrajectory& o) { o.step_begin = {0, 2, 2, 30}; }), "observations.step_begin");
  EXPECT_EQ(with([](ObservedTrajectory& o) { o.weights = {1.0}; }), "observations.weights");
  EXPECT_EQ(with([](ObservedTrajectory& o) { o.weights[1] = -1.0; }), "observations.weights");
  EXPECT_EQ(with([](ObservedTrajectory& o) { o.weights[1] = std::nan(""); }), "observations.weights");
}

// Several episodes add up: the run twice gives twice the counts (and the same per visit).
TEST(ControlledPrior, EpisodesAddUp) {
  const ControlledRun run;
  const std::vector<Trajectory> truth2 = {run.truth[0], run.truth[0]};
  const std::vector<ObservedTrajectory> observed2 = {run.observed[0], run.observed[0]};
  ControlledPriorOptions options;
  options.pseudo_count = 0.0;
  EXPECT_EQ(controlled_run_prior(run.mdp, truth2, observed2, 3, options),
            2.0 * controlled_run_prior(run.mdp, run.truth, run.observed, 3, options));
  options.per_visit = true;
  EXPECT_EQ(controlled_run_prior(run.mdp, truth2, observed2, 3, options),
            controlled_run_prior(run.mdp, run.truth, run.observed, 3, options));
}

}  // namespace
}  // namespace hbirl
