#include "experiments/calibration_experiment.hpp"

#include <gtest/gtest.h>

#include "learner/input_error.hpp"

namespace hbirl {
namespace {

// By hand. Confidences 0.95, 0.95, 0.85, 0.3, 0.05 with outcomes right, wrong, right,
// wrong, right:
//   Brier = (0.05^2 + 0.95^2 + 0.15^2 + 0.3^2 + 0.95^2) / 5 = 1.92 / 5 = 0.384;
//   bins: [0.9, 1] 2 runs, mean 0.95, right 1/2 -> |0.95 - 0.5| = 0.45; [0.8, 0.9) 0.85 vs 1
//   -> 0.15; [0.3, 0.4) 0.3 vs 0 -> 0.3; [0, 0.1) 0.05 vs 1 -> 0.95;
//   ECE = (2 * 0.45 + 0.15 + 0.3 + 0.95) / 5 = 2.3 / 5 = 0.46;
//   AUROC: right {0.95, 0.85, 0.05} against wrong {0.95, 0.3}: pairs won 0.5 + 1 (0.95),
//   0 + 1 (0.85), 0 + 0 (0.05) = 2.5 of 6.
TEST(CalibrationScore, ByHand) {
  const CalibrationScore s = calibration_score({0.95, 0.95, 0.85, 0.3, 0.05}, {true, false, true, false, true});
  EXPECT_EQ(s.runs, 5);
  EXPECT_EQ(s.right, 3);
  EXPECT_NEAR(s.brier, 0.384, 1e-12);
  EXPECT_NEAR(s.ece, 0.46, 1e-12);
  EXPECT_NEAR(s.auroc, 2.5 / 6.0, 1e-12);
  EXPECT_EQ(s.confident, 2);
  EXPECT_EQ(s.confident_right, 1);
  ASSERT_EQ(s.bins.size(), 10u);
  EXPECT_EQ(s.bins[9].runs, 2);
  EXPECT_EQ(s.bins[8].right, 1);
  EXPECT_NEAR(s.mean_confidence, 0.62, 1e-12);
}

// A confidence that orders every right run above every wrong one has AUROC 1; a perfect
// and sure one has ECE and Brier 0; one outcome only: AUROC says nothing (0.5).
TEST(CalibrationScore, Extremes) {
  const CalibrationScore sure = calibration_score({1.0, 1.0, 0.0}, {true, true, false});
  EXPECT_EQ(sure.auroc, 1.0);
  EXPECT_EQ(sure.ece, 0.0);
  EXPECT_EQ(sure.brier, 0.0);
  EXPECT_EQ(calibration_score({0.2, 0.9}, {true, true}).auroc, 0.5);
  EXPECT_EQ(calibration_score({}, {}).runs, 0);
}

// A small run end to end: every run scored, and the CSV reads back what it wrote.
TEST(CalibrationExperiment, RunsAndReadsBack) {
  CalibrationOptions o;
  o.tasks = 2;
  o.draws = 1;
  o.samples = 20;
  o.threads = 2;
  const std::vector<CalibrationRun> runs = run_calibration(o);
  ASSERT_EQ(runs.size(), 4u);
  for (const CalibrationRun& r : runs) {
    EXPECT_EQ(r.error, "");
    EXPECT_GE(r.confidence, 0.0);
    EXPECT_LE(r.confidence, 1.0);
    EXPECT_EQ(r.right, r.ile_relative <= 0.05);
  }
  const std::vector<CalibrationRun> back = calibration_runs_from_csv(calibration_runs_csv(runs));
  ASSERT_EQ(back.size(), runs.size());
  EXPECT_EQ(back[3].data, runs[3].data);
  EXPECT_EQ(back[3].right, runs[3].right);
  EXPECT_NEAR(back[3].confidence, runs[3].confidence, 1e-9);
  EXPECT_NE(calibration_summary(runs, "").find("| truth | 2 |"), std::string::npos);
  EXPECT_THROW(calibration_runs_from_csv("seed,draw\n"), InputError);
}

// The Gridworld figure's runs as tasks: |E| in the figure's order, each learned from
// observations and truth; an unknown source of tasks is named.
TEST(CalibrationExperiment, OnTheGridworldFiguresRuns) {
  CalibrationOptions o;
  o.tasks_from = "gridworld";
  o.first_seed = 1;
  o.tasks = 2;
  o.samples = 20;
  o.threads = 2;
  const std::vector<CalibrationRun> runs = run_calibration(o);
  ASSERT_EQ(runs.size(), 4u);
  for (const CalibrationRun& r : runs) EXPECT_EQ(r.error, "");
  EXPECT_EQ(runs[0].draw, 0);  // |E| = 0, then 1
  EXPECT_EQ(runs[2].draw, 1);
  EXPECT_EQ(runs[1].data, "truth");
  o.tasks_from = "mars";
  EXPECT_THROW(run_calibration(o), InputError);
}

}  // namespace
}  // namespace hbirl
