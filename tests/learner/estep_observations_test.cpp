#include "learner/estep_observations.hpp"

#include <gtest/gtest.h>

#include "learner/hidden_data_em.hpp"
#include "tiny_observed_problem.hpp"
#include "sim_driver/gridworld_observations.hpp"

namespace hbirl {
namespace {

struct ObservedGridworld {
  GridworldTask task;
  GridworldObservations observations;
  ObservationPrior prior;
};

ObservedGridworld observed_gridworld(std::uint64_t seed, int confounders, int per_step, EtaKind eta) {
  Rng rng(seed);
  ObservedGridworld g{make_gridworld_task({}, 20, 10, rng), {}, {}};
  const Eigen::MatrixXd subject = gridworld_subject_observation_model(5, 1.0);
  const Eigen::MatrixXd elements = random_confounder_observation_model(confounders, rng);
  GridworldObservationOptions options;
  options.confounders = confounders;
  options.per_step = per_step;
  options.eta = eta;
  g.observations = observe_gridworld(g.task.mdp, g.task.trajectories, subject, elements, options, rng);
  const std::vector<Trajectory> controlled = soft_expert_demonstration(g.task.mdp, g.task.true_weights, 20, 10, rng);
  g.prior.num_symbols = 4;
  g.prior.num_confounders = confounders;
  g.prior.subject_alpha = controlled_run_alpha(g.task.mdp, controlled, subject, per_step, 1.0, rng);
  g.prior.confounder_alpha = Eigen::MatrixXd::Ones(confounders, 4);
  g.prior.c = 0.5;
  return g;
}

// SPEC §3 / issue: EM on a small gridworld with 3 confounding elements and plausible
// eta recovers the goal corner.
TEST(HiddenDataEm, GridworldWithThreeConfoundersAndPlausibleEtaRecoversTheGoal) {
  for (std::uint64_t seed : {1, 2}) {
    const ObservedGridworld g = observed_gridworld(seed, 3, 20, EtaKind::kPlausible);
    const ObservationEStep estep(g.task.mdp, g.observations.trajectories, g.prior);
    LearnOptions options;
    options.seed = seed;
    const LearnResult learned = learn_reward(g.task.mdp, estep, options);
    Eigen::Index best = 0;
    learned.theta.maxCoeff(&best);
    EXPECT_EQ(best, g.task.goal) << "seed " << seed << ": " << learned.theta.transpose();
    EXPECT_TRUE(learned.restarts[0].converged) << "seed " << seed;
  }
}

// SQUAREM keeps EM's fixed points but gets there in fewer EM steps; its safeguard never
// lets the likelihood end below plain EM's.
TEST(HiddenDataEm, AccelerationConvergesFasterToNoWorseLikelihood) {
  const ObservedGridworld g = observed_gridworld(3, 5, 20, EtaKind::kUniform);
  const ObservationEStep estep(g.task.mdp, g.observations.trajectories, g.prior);
  LearnOptions options;
  options.theta_tolerance = 1e-3;
  options.likelihood_tolerance = 1e-6;
  options.accelerate = false;
  const LearnResult plain = learn_reward(g.task.mdp, estep, options);
  options.accelerate = true;
  const LearnResult fast = learn_reward(g.task.mdp, estep, options);
  ASSERT_TRUE(plain.restarts[0].converged);
  ASSERT_TRUE(fast.restarts[0].converged);
  EXPECT_LT(fast.restarts[0].em_iterations, plain.restarts[0].em_iterations);
  EXPECT_GE(fast.log_likelihood, plain.log_likelihood - 1e-6 * std::abs(plain.log_likelihood));
}

TEST(ObservationEStep, SameBitsWhateverTheThreadCount) {
  const ObservedGridworld g = observed_gridworld(3, 2, 10, EtaKind::kUniform);
  const SoftSolution policy = soft_value_iteration(g.task.mdp, g.task.mdp.reward(Eigen::Vector4d(0.3, 0, 0, 0.2)));
  ObservationEStepOptions one;
  ObservationEStepOptions two;
  two.threads = 2;
  const ObservationEStep a(g.task.mdp, g.observations.trajectories, g.prior, one);
  const ObservationEStep b(g.task.mdp, g.observations.trajectories, g.prior, two);
  const EStepStatistics x = a.statistics(policy, dirichlet_mean(g.prior), 7);
  const EStepStatistics y = b.statistics(policy, dirichlet_mean(g.prior), 7);
  EXPECT_EQ(x.log_likelihood, y.log_likelihood);
  EXPECT_EQ(x.counts, y.counts);
  EXPECT_EQ(x.alpha_dot.subject, y.alpha_dot.subject);
}

// Merging identical observations is an exact rewrite of the emission product.
TEST(ObservationEStep, MergingIdenticalObservationsChangesNothing) {
  const ObservedGridworld g = observed_gridworld(4, 2, 12, EtaKind::kUniform);
  const SoftSolution policy = soft_value_iteration(g.task.mdp, g.task.mdp.reward(Eigen::Vector4d(0.5, 0, 0.1, 0)));
  const ObservationModel model = dirichlet_mean(g.prior);
  ExactEngine engine(g.task.mdp);
  const ObservedTrajectory& raw = g.observations.trajectories[0];
  const ObservedTrajectory merged = merge_identical_observations(raw);
  EXPECT_LT(merged.num_observations(), raw.num_observations());
  EStepStatistics a = EStepStatistics::zero(g.task.mdp.num_pairs(), 2, 4);
  EStepStatistics b = a;
  engine.accumulate(policy, model, raw, a);
  engine.accumulate(policy, model, merged, b);
  EXPECT_NEAR(a.log_likelihood, b.log_likelihood, 1e-9);
  EXPECT_LT((a.counts - b.counts).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_LT((a.alpha_dot.subject - b.alpha_dot.subject).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_LT((a.alpha_dot.confounders - b.alpha_dot.confounders).cwiseAbs().maxCoeff(), 1e-10);
}

void expect_same_statistics(const EStepStatistics& a, const EStepStatistics& b, const std::string& what) {
  const double scale = std::max(1.0, std::abs(a.log_likelihood));
  EXPECT_NEAR(a.log_likelihood, b.log_likelihood, 1e-11 * scale) << what;
  EXPECT_EQ(a.impossible, b.impossible) << what;
  EXPECT_LT((a.counts - b.counts).cwiseAbs().maxCoeff(), 1e-10) << what;
  EXPECT_LT((a.alpha_dot.subject - b.alpha_dot.subject).cwiseAbs().maxCoeff(), 1e-10) << what;
  if (a.alpha_dot.confounders.size() > 0) {
    EXPECT_LT((a.alpha_dot.confounders - b.alpha_dot.confounders).cwiseAbs().maxCoeff(), 1e-10) << what;
  }
}

// The emission table per observation kind (each distinct (symbol, eta) once per pass) is
// the per-observation computation regrouped: same statistics to rounding, on the
// Gridworld (uniform and plausible eta).
TEST(ObservationEStep, KindTableGivesThePerObservationStatistics) {
  for (EtaKind eta : {EtaKind::kUniform, EtaKind::kPlausible}) {
    const ObservedGridworld g = observed_gridworld(6, 3, 20, eta);
    const SoftSolution policy = soft_value_iteration(g.task.mdp, g.task.mdp.reward(Eigen::Vector4d(0.2, -0.3, 0, 0.6)));
    ObservationEStepOptions per_observation;
    per_observation.max_kinds = 0;
    const ObservationEStep table(g.task.mdp, g.observations.trajectories, g.prior);
    const ObservationEStep plain(g.task.mdp, g.observations.trajectories, g.prior, per_observation);
    ASSERT_TRUE(table.uses_kind_table());
    ASSERT_FALSE(plain.uses_kind_table());
    const ObservationModel model = dirichlet_mean(g.prior);
    expect_same_statistics(table.statistics(policy, model, 1), plain.statistics(policy, model, 1),
                           eta == EtaKind::kUniform ? "uniform eta" : "plausible eta");
  }
}

// The same on the tiny problems of the brute-force tests (terminal states, impossible
// actions, deterministic transitions, occluded steps, eta with zeros), each trajectory
// repeated so that the data have few kinds.
TEST(ObservationEStep, KindTableAgreesOnTinyProblems) {
  Rng rng(77);
  int used = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const testing::TinyProblem p = testing::tiny_problem(trial, rng);
    if (p.trajectory.num_observations() == 0) continue;
    ObservationPrior prior;
    prior.num_symbols = p.model.num_symbols();
    prior.num_confounders = p.model.num_confounders();
    prior.subject_alpha = p.model.subject;  // normalised rows: the Dirichlet mean is the model
    prior.confounder_alpha = p.model.confounders;
    prior.learn = false;
    const std::vector<ObservedTrajectory> data(8, p.trajectory);
    ObservationEStepOptions per_observation;
    per_observation.max_kinds = 0;
    const ObservationEStep table(p.mdp, data, prior);
    const ObservationEStep plain(p.mdp, data, prior, per_observation);
    if (!table.uses_kind_table()) continue;
    ++used;
    expect_same_statistics(table.statistics(p.policy, p.model, 1), plain.statistics(p.policy, p.model, 1),
                           "trial " + std::to_string(trial));
  }
  EXPECT_GT(used, 20);
}

// With learn = false the observation model stays the prior's mean and the E-step makes no
// refinement; with learn = true alpha moves and is carried in the state.
TEST(ObservationEStep, AlphaRefinementIsCarriedInTheState) {
  ObservedGridworld g = observed_gridworld(5, 1, 8, EtaKind::kPlausible);
  const SoftSolution policy = soft_value_iteration(g.task.mdp, g.task.mdp.reward(Eigen::Vector4d::Zero()));
  g.prior.learn = false;
  const ObservationEStep fixed(g.task.mdp, g.observations.trajectories, g.prior);
  EStepState state = fixed.initial_state(1);
  EXPECT_EQ(fixed.expect(policy, state).alpha_iterations, 0);
  EXPECT_EQ(state.alpha->subject_alpha, g.prior.subject_alpha);
  g.prior.learn = true;
  const ObservationEStep learning(g.task.mdp, g.observations.trajectories, g.prior);
  state = learning.initial_state(1);
  const EStepResult r = learning.expect(policy, state);
  EXPECT_GT(r.alpha_iterations, 0);
  EXPECT_NE(state.alpha->subject_alpha, g.prior.subject_alpha);
  EXPECT_NEAR(r.counts.sum(), 200.0, 1e-9);  // 20 trajectories x 10 steps
}

}  // namespace
}  // namespace hbirl
