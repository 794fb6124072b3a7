#include "experiments/stopping_experiment.hpp"

#include <gtest/gtest.h>

#include "app/learn.hpp"
#include "learner/input_error.hpp"
#include "sim_driver/file/random_task.hpp"

namespace hbirl {
namespace {

// The rule by hand: k = 2 estimates in a row at or above 0.95; a lower one starts again.
TEST(StopRule, KInARowAtOrAboveP) {
  app::StopRule rule(0.95, 2);
  const std::vector<double> confidence = {0.95, 0.96, 0.5, 0.97, 0.98, 0.99};
  const std::vector<bool> holds = {false, true, false, false, true, true};
  for (size_t i = 0; i < confidence.size(); ++i) EXPECT_EQ(rule.holds_with(confidence[i]), holds[i]) << i;
  app::StopRule once(0.9, 1);
  EXPECT_FALSE(once.holds_with(0.89));
  EXPECT_TRUE(once.holds_with(0.9));
}

// A small run: one estimate per demonstration, each a probability, and the summary counts
// every task once per level.
TEST(StoppingExperiment, AnEstimatePerDemonstration) {
  StoppingOptions o;
  o.tasks = 2;
  o.first_seed = 8006;  // 5 and 7 demonstrations: 12 estimates (8001 and 8002 have 31)
  o.samples = 20;
  o.threads = 2;
  const std::vector<StoppingRun> runs = run_stopping(o);
  ASSERT_EQ(runs.size(), 2u);
  for (const StoppingRun& r : runs) {
    EXPECT_EQ(r.error, "");
    EXPECT_EQ(r.confidence.size(), make_random_task(r.seed, 0).observed.trajectories.size());
    ASSERT_EQ(r.ile_relative.size(), r.confidence.size());
    for (double c : r.confidence) {
      EXPECT_GE(c, 0.0);
      EXPECT_LE(c, 1.0);
    }
  }
  const std::string summary = stopping_summary(runs, o, "");
  EXPECT_NE(summary.find("| 0.90 |"), std::string::npos) << summary;
  EXPECT_NE(summary.find("| 0.95 |"), std::string::npos) << summary;
  const std::string csv = stopping_runs_csv(runs);
  EXPECT_EQ(static_cast<size_t>(std::count(csv.begin(), csv.end(), '\n')),
            1 + runs[0].confidence.size() + runs[1].confidence.size());
  const std::vector<StoppingRun> back = stopping_runs_from_csv(csv);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[1].seed, runs[1].seed);
  ASSERT_EQ(back[1].confidence.size(), runs[1].confidence.size());
  EXPECT_NEAR(back[1].confidence.back(), runs[1].confidence.back(), 1e-9);
  EXPECT_NEAR(back[1].ile_relative.front(), runs[1].ile_relative.front(), 1e-9);
  EXPECT_THROW(stopping_runs_from_csv("seed,draw\n"), InputError);
  EXPECT_THROW(stopping_runs_from_csv(stopping_runs_csv({}) + "1,0,2,0.5,0.1,0,\n"), InputError);  // 2 before 1
}

}  // namespace
}  // namespace hbirl
