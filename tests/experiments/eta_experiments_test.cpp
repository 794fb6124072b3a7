#include "experiments/eta_experiments.hpp"

#include <gtest/gtest.h>

namespace hbirl {
namespace {

// A miscalibrated labeller (states 0.8, right 40% of the time): learned eta finds its
// calibration for the subject's context and does no worse than fixed eta; the numbers
// do not depend on the thread count.
TEST(EtaSensitivity, LearnedEtaFindsTheCalibrationAndSameBitsForAnyThreads) {
  EtaSensitivityOptions o;
  o.confounders = {3};
  o.masses = {0.8};
  o.accuracies = {0.4};
  o.runs = 2;
  o.threads = 1;
  const std::vector<EtaRun> one = run_eta_sensitivity(o);
  o.threads = 3;
  const std::vector<EtaRun> many = run_eta_sensitivity(o);
  ASSERT_EQ(one.size(), 6u);  // per run: perfect, fixed, learned
  for (size_t i = 0; i < one.size(); ++i) {
    EXPECT_TRUE(one[i].error.empty()) << one[i].error;
    EXPECT_EQ(one[i].ile, many[i].ile) << i;
    EXPECT_EQ(one[i].subject_eta, many[i].subject_eta) << i;
  }
  for (const EtaRun& r : one) {
    if (r.method == "learned") {
      EXPECT_NEAR(r.subject_eta, 0.4, 0.08) << "run " << r.run;
    } else {
      EXPECT_EQ(r.subject_eta, -1.0);
    }
    if (r.method == "perfect") {
      EXPECT_GT(r.label_accuracy, 0.9) << "run " << r.run;
    }
  }
  EXPECT_NE(eta_runs_csv(one).find("run,confounders,mass,accuracy,method,ile"), std::string::npos);
}

// The unlisted experiment's methods run and differ where they should: with every element
// unlisted (told none) and eta = 1 on the subject, "as told" believes every observation
// is the subject's.
TEST(Unlisted, MethodsRunAndTheOracleIsToldEverything) {
  UnlistedOptions o;
  o.confounders = {3};
  o.told = {0};
  o.runs = 1;
  const std::vector<UnlistedRun> runs = run_unlisted(o);
  ASSERT_EQ(runs.size(), 4u);
  for (const UnlistedRun& r : runs) {
    EXPECT_TRUE(r.error.empty()) << r.method << ": " << r.error;
    EXPECT_EQ(r.told, r.method == "oracle" ? 3 : 0);
  }
  EXPECT_EQ(runs[0].method, "as_told");
  EXPECT_NEAR(runs[0].label_accuracy, 0.25, 0.03);  // "subject" for all, right for the subject's quarter
  EXPECT_GT(runs[3].label_accuracy, runs[0].label_accuracy);
}

}  // namespace
}  // namespace hbirl
