#include "experiments/judged_tasks.hpp"

#include <gtest/gtest.h>

#include "app/learn.hpp"
#include "experiments/calibration_experiment.hpp"
#include "experiments/stopping_experiment.hpp"
#include "learner/input_error.hpp"
#include "learner/metrics.hpp"

namespace hbirl {
namespace {

JudgedTaskOptions source(const std::string& name, int tasks, std::uint64_t first_seed = 1) {
  JudgedTaskOptions o;
  o.source = name;
  o.tasks = tasks;
  o.first_seed = first_seed;
  o.draws = 2;
  return o;
}

// Each source names its data sets as documented: random tasks' draws, the Gridworld
// figure's |E| in turn, one data set per onion run; an unknown source is named.
TEST(JudgedTasks, DataSetsOfEachSource) {
  const std::vector<DataSetId> random = judged_data_sets(source("random", 2, 7));
  ASSERT_EQ(random.size(), 4u);
  EXPECT_EQ(random[3].seed, 8u);
  EXPECT_EQ(random[3].draw, 1);
  const std::vector<DataSetId> grid = judged_data_sets(source("gridworld", 10));
  ASSERT_EQ(grid.size(), 10u);
  EXPECT_EQ(grid[2].draw, 3);
  EXPECT_EQ(grid[9].draw, 0);  // the figure's nine |E|, then again
  EXPECT_EQ(judged_data_sets(source("onion", 3)).size(), 3u);
  try {
    judged_data_sets(source("mars", 1));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "tasks_from");
  }
  EXPECT_EQ(judged_task_sources().size(), 3u);
}

// A figure's task is a whole run of it: the Gridworld's 20 demonstrations with one
// observed trajectory each, |E| elements in the prior; the onion's 10 sorts from frames.
TEST(JudgedTasks, TasksOfTheFigures) {
  const JudgedTaskOptions grid = source("gridworld", 3);
  const JudgedTask g = JudgedTaskMaker(grid)({3, 3});
  EXPECT_EQ(g.truth.size(), 20u);
  EXPECT_EQ(g.observed.size(), 20u);
  EXPECT_EQ(g.prior.num_confounders, 3);
  EXPECT_EQ(g.true_weights.size(), g.mdp.num_features());
  const JudgedTaskOptions onion = source("onion", 1);
  const JudgedTask o = JudgedTaskMaker(onion)({1, 0});
  EXPECT_EQ(o.truth.size(), 10u);
  EXPECT_EQ(o.observed.size(), 10u);
  EXPECT_EQ(o.prior.num_confounders, 3);
}

// Calibration from the first n demonstrations: a run per n and data, each the same as
// hbirl learn on that prefix; a prefix longer than the data set fails its runs, named.
TEST(JudgedTasks, CalibrationOnPrefixes) {
  CalibrationOptions o;
  o.tasks_from = "gridworld";
  o.first_seed = 1;
  o.tasks = 1;
  o.samples = 20;
  o.data = {"observations"};
  o.demonstrations = {1, 3};
  o.threads = 1;
  const std::vector<CalibrationRun> runs = run_calibration(o);
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0].demonstrations, 1);
  EXPECT_EQ(runs[1].demonstrations, 3);
  const JudgedTask task = JudgedTaskMaker(source("gridworld", 1))({1, 0});
  app::LearnSettings settings;
  settings.em.threads = 1;
  settings.em.seed = 1 * 1000003ull + 0;
  settings.posterior.samples = 20;
  const std::vector<ObservedTrajectory> three(task.observed.begin(), task.observed.begin() + 3);
  const app::Learned learned = app::learn(task.mdp, three, task.prior, settings);
  EXPECT_EQ(runs[1].confidence, learned.confidence->near_optimal);
  EXPECT_EQ(runs[1].ile_relative, inverse_learning_error(task.mdp, task.true_weights, learned.em.theta).relative());
  o.demonstrations = {21};
  const std::vector<CalibrationRun> too_many = run_calibration(o);
  ASSERT_EQ(too_many.size(), 1u);
  EXPECT_NE(too_many[0].error.find("demonstrations"), std::string::npos) << too_many[0].error;
}

// Stopping on the Gridworld figure's run: an estimate after each of its 20 demonstrations.
TEST(JudgedTasks, StoppingOnTheGridworld) {
  StoppingOptions o;
  o.tasks_from = "gridworld";
  o.first_seed = 1;
  o.tasks = 1;
  o.samples = 20;
  o.threads = 1;
  const std::vector<StoppingRun> runs = run_stopping(o);
  ASSERT_EQ(runs.size(), 1u);
  EXPECT_EQ(runs[0].error, "");
  EXPECT_EQ(runs[0].confidence.size(), 20u);
  EXPECT_NE(stopping_summary(runs, o, "").find("Gridworld"), std::string::npos);
}

}  // namespace
}  // namespace hbirl
