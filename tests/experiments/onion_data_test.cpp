#include "experiments/onion_data.hpp"

#include <gtest/gtest.h>

#include "learner/controlled_prior.hpp"
#include "learner/estep_observations.hpp"
#include "learner/hidden_data_em.hpp"
#include "learner/metrics.hpp"
#include "sim_driver/onion/onion.hpp"

namespace hbirl::onion {
namespace {

// The controlled run: one step's worth of observations per (s, a) in the prior, and only
// the subject's symbols where the expert went.
TEST(OnionData, ControlledRunGivesTheSubjectPrior) {
  const Mdp mdp = make_onion_mdp();
  DemonstrationOptions options;
  options.sorts = 4;
  const OnionDemonstration d = demonstrate(mdp, SceneConfig::controlled(), options, 3);
  ASSERT_EQ(d.truth.size(), 4u);
  for (size_t i = 0; i < d.truth.size(); ++i) {
    EXPECT_EQ(d.observed[i].length(), static_cast<int>(d.truth[i].size()));
    EXPECT_TRUE(d.observed[i].ends_in_terminal);
    for (int t = 0; t < d.observed[i].length(); ++t) EXPECT_GT(d.observed[i].observations_at(t), 0);  // never occluded
  }
  const Eigen::MatrixXd alpha =
      controlled_run_prior(mdp, d.truth, d.observed, perception::kNumSymbols, controlled_prior_options());
  ASSERT_EQ(alpha.cols(), perception::kNumSymbols);
  const int r = mdp.pair(index({kUnknown, kGripped, kAtInspection}), kInspect);
  // One frame = one gripper blob and one onion blob: 2 observations x 30 frames per step.
  EXPECT_NEAR(alpha.row(r).sum() - perception::kNumSymbols, 60.0, 1e-9);
  EXPECT_EQ(alpha.minCoeff(), 1.0);
}

// Onion qualities alternate from a random first one, so any two consecutive sorts show
// both; with alternate_quality off they are drawn independently.
TEST(OnionData, QualitiesAlternate) {
  const Mdp mdp = make_onion_mdp();
  DemonstrationOptions options;
  options.sorts = 5;
  int first_blemished = 0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    const OnionDemonstration d = demonstrate(mdp, SceneConfig::controlled(), options, seed);
    for (size_t i = 1; i < d.blemished.size(); ++i) EXPECT_NE(d.blemished[i], d.blemished[i - 1]) << "seed " << seed;
    first_blemished += d.blemished[0];
  }
  EXPECT_GT(first_blemished, 0);  // the first one is random
  EXPECT_LT(first_blemished, 8);
  options.alternate_quality = false;
  options.blemished = 1.0;
  const OnionDemonstration all = demonstrate(mdp, SceneConfig::controlled(), options, 1);
  EXPECT_EQ(std::count(all.blemished.begin(), all.blemished.end(), true), 5);
}

// End to end from frames (paper §Experiments B): 6 sorts in the full scene with the
// labeller's plausible eta; HiddenDataEM learns to keep good onions and bin blemished ones.
TEST(OnionData, LearnsTheSortingRuleFromFramesWithPlausibleEta) {
  const Mdp mdp = make_onion_mdp();
  DemonstrationOptions controlled_options;
  controlled_options.sorts = 10;
  const OnionDemonstration controlled = demonstrate(mdp, SceneConfig::controlled(), controlled_options, 1);
  DemonstrationOptions options;
  options.sorts = 6;
  const OnionDemonstration d = demonstrate(mdp, SceneConfig{}, options, 2);
  ASSERT_TRUE(std::count(d.blemished.begin(), d.blemished.end(), true) > 0 &&
              std::count(d.blemished.begin(), d.blemished.end(), false) > 0);
  ObservationPrior prior;
  prior.num_symbols = perception::kNumSymbols;
  prior.num_confounders = perception::kNumSources - 1;
  prior.subject_alpha = controlled_run_prior(mdp, controlled.truth, controlled.observed, perception::kNumSymbols,
                                             controlled_prior_options());
  prior.confounder_alpha = Eigen::MatrixXd::Ones(prior.num_confounders, prior.num_symbols);
  prior.c = 0.5;
  ObservationEStepOptions estep_options;
  estep_options.max_alpha_iterations = 1;
  estep_options.alpha_tolerance = 1e-3;
  const ObservationEStep estep(mdp, d.observed, prior, estep_options);
  LearnOptions learn;
  learn.theta_tolerance = 1e-3;
  learn.likelihood_tolerance = 1e-6;
  const LearnResult learned = learn_reward(mdp, estep, learn);
  const Eigen::VectorXd& w = learned.theta;
  EXPECT_GT(w[kGoodOnConveyor], w[kGoodInBin]) << w.transpose();
  EXPECT_GT(w[kBlemishedInBin], w[kBlemishedOnConveyor]) << w.transpose();
  EXPECT_LT(inverse_learning_error(mdp, expert_weights(), w).relative(), 1e-6) << w.transpose();
}

}  // namespace
}  // namespace hbirl::onion
