#include "learner/estep_observations.hpp"

#include <gtest/gtest.h>

#include "brute_force_posterior.hpp"
#include "learner/hidden_data_em.hpp"
#include "learner/input_error.hpp"
#include "learner/soft_value_iteration.hpp"
#include "random_mdp.hpp"
#include "tiny_observed_problem.hpp"
#include "sim_driver/gridworld/observations.hpp"

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

// O known (a prior of 1e9 pseudo-counts on the truth): only eta moves, with strength kappa.
ObservationPrior known_o_prior(const Eigen::MatrixXd& subject, const Eigen::MatrixXd& elements, double kappa) {
  ObservationPrior prior;
  prior.num_symbols = static_cast<int>(subject.cols());
  prior.num_confounders = static_cast<int>(elements.rows());
  prior.subject_alpha = 1e9 * subject;
  prior.confounder_alpha = 1e9 * elements;
  prior.automatic_strength = false;
  prior.eta_strength = kappa;
  return prior;
}

// Paper §Experiments A: EM on a small gridworld with 3 confounding elements and plausible
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
  EXPECT_LT(fast.restarts[0].em_evaluations, plain.restarts[0].em_evaluations);
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

// An E-step that takes its trajectories over (a sampler worker's, which holds its share
// once) computes what one that copies them computes, bit for bit, with learned eta's
// contexts too; refused, it leaves them as they were; and take_trajectories() gives back
// what it holds, which makes the same E-step again.
TEST(ObservationEStep, TakingTheTrajectoriesOverIsCopyingThem) {
  ObservedGridworld g = observed_gridworld(3, 2, 10, EtaKind::kPlausible);
  g.prior.learn_eta = true;
  const SoftSolution policy = soft_value_iteration(g.task.mdp, g.task.mdp.reward(Eigen::Vector4d(0.3, 0, 0, 0.2)));
  const ObservationEStep copied(g.task.mdp, g.observations.trajectories, g.prior);
  std::vector<ObservedTrajectory> data = g.observations.trajectories;
  ObservationEStep taken(g.task.mdp, std::move(data), g.prior);
  const auto same = [&](const ObservationEStep& a, const ObservationEStep& b) {
    const RowMatrix eta = a.context_eta();
    ASSERT_EQ(eta, b.context_eta());
    const EStepStatistics x = a.statistics(policy, dirichlet_mean(g.prior), 7, &eta);
    const EStepStatistics y = b.statistics(policy, dirichlet_mean(g.prior), 7, &eta);
    EXPECT_EQ(x.log_likelihood, y.log_likelihood);
    EXPECT_EQ(x.counts, y.counts);
    EXPECT_EQ(x.alpha_dot.subject, y.alpha_dot.subject);
    EXPECT_EQ(x.source_counts, y.source_counts);
  };
  same(copied, taken);
  std::vector<ObservedTrajectory> back = std::move(taken).take_trajectories();
  ASSERT_EQ(back.size(), g.observations.trajectories.size());
  const ObservationEStep again(g.task.mdp, std::move(back), g.prior);
  same(copied, again);
  // Refused (an eta of the wrong width): thrown before anything is taken.
  std::vector<ObservedTrajectory> bad = g.observations.trajectories;
  bad.back().eta.conservativeResize(Eigen::NoChange, 1);
  const std::vector<ObservedTrajectory> before = bad;
  EXPECT_THROW(ObservationEStep(g.task.mdp, std::move(bad), g.prior), InputError);
  ASSERT_EQ(bad.size(), before.size());
  for (size_t i = 0; i < bad.size(); ++i) {
    EXPECT_EQ(bad[i].symbols, before[i].symbols) << i;
    EXPECT_EQ(bad[i].eta, before[i].eta) << i;
  }
}

// A watched trajectory's posterior comes out of the E-step's pass, with the kinds table
// and without it (max_kinds 0), equal to the engine's posterior of that trajectory
// computed alone; watching changes none of the sums.
TEST(ObservationEStep, WatchedTrajectoryIsThePosteriorOfThatTrajectory) {
  const ObservedGridworld g = observed_gridworld(3, 2, 10, EtaKind::kPlausible);
  ObservationPrior fixed = g.prior;
  fixed.learn = false;  // one pass, at the prior's mean
  fixed.learn_eta = false;
  const SoftSolution policy = soft_value_iteration(g.task.mdp, g.task.mdp.reward(Eigen::Vector4d(0.3, 0, 0, 0.2)));
  const ObservationModel model = dirichlet_mean(fixed);
  const int watched = 17;
  const TrajectoryPosterior alone =
      ExactEngine(g.task.mdp).posterior(policy, model, g.observations.trajectories[watched]);
  for (int max_kinds : {1024, 0}) {
    ObservationEStepOptions plain, watching;
    plain.max_kinds = watching.max_kinds = max_kinds;
    watching.watch = watched;
    const ObservationEStep a(g.task.mdp, g.observations.trajectories, fixed, plain);
    const ObservationEStep b(g.task.mdp, g.observations.trajectories, fixed, watching);
    EStepState sa, sb;
    const EStepResult x = a.expect(policy, sa), y = b.expect(policy, sb);
    EXPECT_EQ(x.counts, y.counts);
    EXPECT_EQ(x.log_likelihood, y.log_likelihood);
    EXPECT_EQ(x.watched.rows(), 0);
    ASSERT_EQ(y.watched.rows(), alone.marginals.rows()) << max_kinds;
    ASSERT_EQ(y.watched.cols(), g.task.mdp.num_pairs());
    EXPECT_LT((y.watched - alone.marginals).cwiseAbs().maxCoeff(), 1e-12) << max_kinds;
    EXPECT_NEAR(y.watched_log_likelihood, alone.log_likelihood, 1e-9 * std::abs(alone.log_likelihood));
  }
  ObservationEStepOptions outside;
  outside.watch = static_cast<int>(g.observations.trajectories.size());
  EXPECT_THROW(ObservationEStep(g.task.mdp, g.observations.trajectories, fixed, outside), InputError);
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

// The E-step keeps each trajectory's seen end through merging identical observations: its
// statistics are the engine's with the end (which differ from the unseen end's where the
// end says something); an end_state that is not terminal is named at construction.
TEST(ObservationEStep, KeepsTheSeenEnd) {
  Rng rng(6);
  int differ = 0;
  for (int trial = 0; trial < 12; ++trial) {
    testing::TinyProblem p = testing::two_exits(trial, rng);
    ObservationPrior prior = testing::prior_at(p.model);  // its mean is the model
    prior.learn = false;
    ExactEngine engine(p.mdp);
    const double unseen = engine.posterior(p.policy, p.model, p.trajectory).log_likelihood;
    p.trajectory.end_state = 2 + trial % 2;
    const TrajectoryPosterior direct = engine.posterior(p.policy, p.model, p.trajectory);
    if (!std::isfinite(direct.log_likelihood)) continue;
    const ObservationEStep estep(p.mdp, {p.trajectory}, prior, {});
    const EStepStatistics s = estep.statistics(p.policy, p.model, 1);
    EXPECT_NEAR(s.log_likelihood, direct.log_likelihood, 1e-9) << "trial " << trial;
    differ += std::abs(unseen - direct.log_likelihood) > 1e-3;
  }
  EXPECT_GE(differ, 5);
  testing::TinyProblem p = testing::two_exits(0, rng);
  ObservationPrior prior = testing::prior_at(p.model);  // its mean is the model
  p.trajectory.end_state = 0;                           // not terminal
  try {
    ObservationEStep(p.mdp, {p.trajectory}, prior, {});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "demonstration[0].end_state");
  }
}

// The end sensor is learned as the elements are (docs/MODEL.md "Sensors that see the end"):
// one refinement of the posterior update is its prior plus the exact engine's expected end
// counts under the prior's mean; reports the model cannot read are named at construction.
TEST(ObservationEStep, LearnsTheEndSensor) {
  Rng rng(61);
  int learned = 0;
  for (int trial = 0; trial < 12; ++trial) {
    testing::TinyProblem p = testing::two_exits(trial, rng);
    ObservationPrior prior = testing::prior_at(p.model);  // its mean is the model
    prior.end_alpha = 1.0 + 3.0 * testing::random_distributions(p.mdp.num_states, 2, rng).array();
    prior.automatic_strength = false;
    prior.learn_eta = false;
    p.trajectory.end_symbols = {trial % 2, 1, 0};
    const ObservationModel start = dirichlet_mean(prior);
    ExactEngine engine(p.mdp);
    EStepStatistics direct = EStepStatistics::zero(p.mdp.num_pairs(), start.num_confounders(), start.num_symbols());
    engine.accumulate(p.policy, start, p.trajectory, direct);
    if (direct.impossible > 0) continue;
    ObservationEStepOptions options;
    options.max_alpha_iterations = 1;
    const ObservationEStep estep(p.mdp, {p.trajectory}, prior, options);
    EStepState state = estep.initial_state(1);
    const EStepResult r = estep.expect(p.policy, state);
    EXPECT_NEAR(r.log_likelihood, direct.log_likelihood, 1e-9) << "trial " << trial;
    const Eigen::MatrixXd expected = prior.end_alpha + direct.alpha_dot.end;
    EXPECT_LT((state.alpha->end_alpha - expected).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
    EXPECT_NEAR(state.alpha->end_alpha.sum() - prior.end_alpha.sum(), 3.0, 1e-9);
    ++learned;
  }
  EXPECT_GE(learned, 8);
  testing::TinyProblem p = testing::two_exits(0, rng);
  ObservationPrior prior = testing::prior_at(p.model);  // its mean is the model
  auto refused = [&](const ObservationPrior& with, const std::string& field) {
    try {
      ObservationEStep(p.mdp, {p.trajectory}, with, {});
      ADD_FAILURE() << field;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), field) << e.what();
    }
  };
  p.trajectory.end_symbols = {0};
  refused(prior, "demonstration[0].end_symbols");  // no end sensor
  prior.end_alpha = Eigen::MatrixXd::Ones(p.mdp.num_states, 2);
  p.trajectory.end_symbols = {2};
  refused(prior, "demonstration[0].end_symbols");  // not a symbol of it
  p.trajectory.end_symbols = {1};
  p.trajectory.ends_in_terminal = false;
  refused(prior, "demonstration[0].end_symbols");  // the trajectory was cut off
  prior.end_alpha = Eigen::MatrixXd::Ones(2, 2);
  refused(prior, "end_alpha");
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
    ObservationPrior prior = testing::prior_at(p.model);  // its mean is the model
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

// Random observed data on a random MDP: `n` trajectories of up to 8 steps under a soft
// policy, 0-3 observations per step of 3 symbols, each with one of `etas` source
// distributions over 1 + 2 sources (few kinds: the kind table is used) or, with etas = 0,
// a fresh one per observation (too many kinds for it).
std::vector<ObservedTrajectory> random_observed(const Mdp& mdp, const SoftSolution& policy, int n, int etas, Rng& rng) {
  std::vector<Eigen::RowVector3d> table;
  for (int k = 0; k < etas; ++k) {
    const Eigen::RowVector3d e(0.1 + rng.uniform(), 0.1 + rng.uniform(), 0.1 + rng.uniform());
    table.push_back(e / e.sum());
  }
  std::vector<ObservedTrajectory> out;
  for (int i = 0; i < n; ++i) {
    bool terminal = false;
    const Trajectory steps = sample_trajectory(mdp, policy.policy, 1 + rng.uniform_int(8), rng, &terminal);
    ObservedTrajectory t;
    std::vector<Eigen::RowVector3d> rows;
    for (size_t step = 0; step < steps.size(); ++step) {
      for (int k = rng.uniform_int(4); k > 0; --k) {
        t.symbols.push_back(rng.uniform_int(3));
        Eigen::RowVector3d e(0.1 + rng.uniform(), 0.1 + rng.uniform(), 0.1 + rng.uniform());
        rows.push_back(etas > 0 ? table[static_cast<size_t>(rng.uniform_int(etas))] : Eigen::RowVector3d(e / e.sum()));
      }
      t.step_begin.push_back(static_cast<int>(t.symbols.size()));
    }
    t.eta.resize(static_cast<Eigen::Index>(rows.size()), 3);
    for (size_t r = 0; r < rows.size(); ++r) t.eta.row(static_cast<Eigen::Index>(r)) = rows[r];
    t.ends_in_terminal = terminal;
    out.push_back(std::move(t));
  }
  return out;
}

// A sampler worker holds only its share of the blocks (services/sampler_worker.hpp): an
// E-step over the trajectories of some blocks, as the whole data set's E-step holds them
// (merged, with its contexts), told whether that E-step uses the kind table, gives each of
// those blocks' statistics bit for bit -- on random MDPs of odd and even sizes (the kind
// table's rows then start at other alignments), with the kind table and without, stated
// and learned eta, and the watched trajectory inside the share.
TEST(ObservationEStep, AShareOfTheBlocksGivesTheirStatisticsBitForBit) {
  Rng rng(2024);
  int tables = 0, plain = 0;
  for (int trial = 0; trial < 12; ++trial) {
    testing::RandomMdpOptions o;
    o.states = 5 + trial;
    o.actions = 2 + trial % 3;
    o.terminal = trial % 2;
    o.impossible = trial % 3 == 1;
    const Mdp mdp = testing::random_mdp(o, rng);
    const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(Eigen::VectorXd::Random(o.features)));
    const int n = ObservationEStep::kBlockSize * 5 + 7;  // six blocks, the last one short
    const std::vector<ObservedTrajectory> data = random_observed(mdp, policy, n, trial % 4 == 3 ? 0 : 4, rng);
    ObservationPrior prior;
    prior.num_symbols = 3;
    prior.num_confounders = 2;
    prior.subject_alpha =
        Eigen::MatrixXd::Constant(mdp.num_pairs(), 3, 1.0) + Eigen::MatrixXd::Random(mdp.num_pairs(), 3).cwiseAbs();
    prior.confounder_alpha = Eigen::MatrixXd::Ones(2, 3);
    prior.learn_eta = trial % 2 == 0;
    ObservationEStepOptions options;
    options.watch = ObservationEStep::kBlockSize * (trial % 6) + 3;
    const ObservationEStep whole(mdp, data, prior, options);
    (whole.uses_kind_table() ? tables : plain)++;
    const ObservationModel model = dirichlet_mean(prior);
    const std::optional<RowMatrix> eta = whole.learned_eta(whole.initial_state(1).alpha.value());
    ASSERT_EQ(eta.has_value(), prior.learn_eta);
    RowMatrix moved;  // learned eta away from the stated one, as after some EM iterations
    if (eta) moved = (eta->array() + 0.2 * Eigen::ArrayXXd::Random(eta->rows(), eta->cols()).abs()).matrix();
    for (const std::vector<int>& share :
         std::vector<std::vector<int>>{{0}, {5}, {1, 3}, {2, 4, 5}, {0, 1, 2, 3, 4, 5}}) {
      std::vector<ObservedTrajectory> held;
      int watch = -1;
      for (int b : share) {
        for (int i = b * ObservationEStep::kBlockSize; i < std::min(n, (b + 1) * ObservationEStep::kBlockSize); ++i) {
          if (i == options.watch) watch = static_cast<int>(held.size());
          held.push_back(whole.trajectories()[static_cast<size_t>(i)]);
        }
      }
      ObservationPrior shape = prior;
      ObservationEStepOptions share_options;
      share_options.kind_table = whole.uses_kind_table();
      share_options.watch = watch;
      const ObservationEStep part(mdp, held, shape, share_options);
      std::vector<int> local(share.size());
      for (size_t k = 0; k < share.size(); ++k) local[k] = static_cast<int>(k);
      const RowMatrix* with = eta ? &moved : nullptr;
      const std::vector<EStepStatistics> expected = whole.block_statistics(policy, model, 9, share, 1, with);
      const std::vector<EStepStatistics> got = part.block_statistics(policy, model, 9, local, 1, with);
      for (size_t k = 0; k < share.size(); ++k) {
        const std::string what = "trial " + std::to_string(trial) + ", block " + std::to_string(share[k]);
        const EStepStatistics& a = expected[k];
        const EStepStatistics& b = got[k];
        EXPECT_EQ(a.counts, b.counts) << what;
        EXPECT_EQ(a.alpha_dot.subject, b.alpha_dot.subject) << what;
        EXPECT_EQ(a.alpha_dot.confounders, b.alpha_dot.confounders) << what;
        EXPECT_EQ(a.log_likelihood, b.log_likelihood) << what;
        EXPECT_EQ(a.impossible, b.impossible) << what;
        EXPECT_EQ(a.watched, b.watched) << what;
        // The share numbers no context it does not hold: compare the rows it has.
        ASSERT_LE(b.source_counts.rows(), a.source_counts.rows()) << what;
        EXPECT_EQ(a.source_counts.topRows(b.source_counts.rows()), b.source_counts) << what;
        if (b.source_counts.rows() < a.source_counts.rows()) {
          EXPECT_TRUE(
              (a.source_counts.bottomRows(a.source_counts.rows() - b.source_counts.rows()).array() == 0.0).all())
              << what;
        }
      }
    }
  }
  EXPECT_GT(tables, 4);
  EXPECT_GT(plain, 1);
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

// One refinement of the posterior update with c = 1 gives the weighed prior plus the
// expected counts, the counts checked against brute-force enumeration of every
// trajectory and labelling (tiny problems), for strengths on and off the grid.
TEST(ObservationEStep, PosteriorUpdateIsThePriorPlusBruteForceCounts) {
  Rng rng(17);
  int checked = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const testing::TinyProblem p = testing::tiny_problem(trial, rng);
    const testing::BruteForce truth = testing::brute_force(p.mdp, p.policy, p.model, p.trajectory);
    if (!(truth.likelihood > 0.0)) continue;
    ++checked;
    ObservationPrior prior;
    prior.num_symbols = p.model.num_symbols();
    prior.num_confounders = p.model.num_confounders();
    // The prior's mean is the problem's model: alpha = 1 + 4 O (every pair has counts).
    prior.subject_alpha = 1.0 + 4.0 * p.model.subject.array();
    prior.confounder_alpha = 1.0 + 4.0 * p.model.confounders.array();
    prior.c = 1.0;
    prior.learn_eta = false;
    prior.automatic_strength = false;
    prior.strength = trial % 2 == 0 ? 1.0 : 0.37;
    ObservationEStepOptions options;
    options.max_alpha_iterations = 1;
    const ObservationEStep estep(p.mdp, {p.trajectory}, prior, options);
    EStepState state = estep.initial_state(1);
    // The E-step computes with the prior's mean; give it the same model as brute force.
    state.alpha->subject_alpha = p.model.subject;
    state.alpha->confounder_alpha = p.model.confounders;
    estep.expect(p.policy, state);
    const Eigen::MatrixXd subject = weighed_subject_prior(prior, prior.strength) + truth.stats.alpha_dot.subject;
    const Eigen::MatrixXd elements = prior.confounder_alpha + truth.stats.alpha_dot.confounders;
    EXPECT_LT((state.alpha->subject_alpha - subject).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
    if (elements.size() > 0) {
      EXPECT_LT((state.alpha->confounder_alpha - elements).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
    }
  }
  EXPECT_GT(checked, 20);
}

// tie_actions: the posterior update's E-step ties the prior as tie_subject_prior_across_actions
// does (the Gridworld's sensor sees the state alone, so the share is large), starts EM at the
// tied prior's mean and, with O held, holds it there; the paper's update is left untied.
TEST(ObservationEStep, TiesThePriorAcrossAStatesActionsWhenAsked) {
  ObservedGridworld g = observed_gridworld(5, 1, 8, EtaKind::kPlausible);
  g.prior.tie_actions = true;
  g.prior.automatic_strength = false;
  g.prior.strength = 0.5;
  ObservationPrior by_hand = g.prior;
  tie_subject_prior_across_actions(by_hand, g.task.mdp.num_actions);
  ASSERT_GT(by_hand.subject_tie, 0.5);
  const Eigen::MatrixXd tied_mean = dirichlet_mean(weighed_subject_prior(by_hand, 0.5));
  const SoftSolution policy = soft_value_iteration(g.task.mdp, g.task.mdp.reward(Eigen::Vector4d::Zero()));
  ObservationEStepOptions one;
  one.max_alpha_iterations = 1;
  Eigen::VectorXd visits[2];
  for (bool learn : {true, false}) {
    ObservationPrior prior = g.prior;
    prior.learn = learn;
    const ObservationEStep estep(g.task.mdp, g.observations.trajectories, prior, one);
    EStepState state = estep.initial_state(1);
    EXPECT_EQ(state.alpha->subject_tie, by_hand.subject_tie);
    EXPECT_EQ(state.alpha->subject_base_shape, by_hand.subject_base_shape);
    EXPECT_LT((dirichlet_mean(state.alpha->subject_alpha) - tied_mean).cwiseAbs().maxCoeff(), 1e-12) << learn;
    const EStepResult r = estep.expect(policy, state);
    visits[learn ? 0 : 1] = r.counts;
    if (learn) {  // one refinement: the tied weighed prior plus the subject's expected counts
      const Eigen::MatrixXd added = state.alpha->subject_alpha - weighed_subject_prior(by_hand, 0.5);
      EXPECT_GT(added.minCoeff(), -1e-9);
      EXPECT_GT(added.sum(), 100.0);  // of 20 x 10 x 8 observations, the subject's share
      EXPECT_LT(added.sum(), 1600.0 + 1e-9);
    } else {
      EXPECT_LT((dirichlet_mean(state.alpha->subject_alpha) - tied_mean).cwiseAbs().maxCoeff(), 1e-12);  // held
    }
  }
  EXPECT_LT((visits[0] - visits[1]).cwiseAbs().maxCoeff(), 1e-9);  // the same first O, learned or held
  ObservationPrior paper = g.prior;
  use_alpha_update(paper, AlphaUpdate::kPaper);
  const ObservationEStep untied(g.task.mdp, g.observations.trajectories, paper);
  EXPECT_EQ(untied.initial_state(1).alpha->subject_tie, 0.0);
  EXPECT_EQ(untied.initial_state(1).alpha->subject_base_shape.size(), 0);
  EXPECT_EQ(untied.initial_state(1).alpha->subject_alpha, g.prior.subject_alpha);
}

// Pairs the prior has no counts for keep its mean whatever the strength, as long as some
// pair has counts; with no counts anywhere the demonstration alone sets O.
TEST(ObservationEStep, PairsWithoutCountsKeepTheirPriorMean) {
  ObservationPrior prior;
  prior.num_symbols = 2;
  prior.subject_alpha = Eigen::MatrixXd::Ones(3, 2);
  prior.subject_alpha.row(0) << 9, 1;
  prior.confounder_alpha = Eigen::MatrixXd::Zero(0, 2);
  for (double s : {0.01, 1.0, 100.0}) {
    const Eigen::MatrixXd w = weighed_subject_prior(prior, s);
    EXPECT_DOUBLE_EQ(w(0, 0), 1.0 + s * 8.0);
    EXPECT_DOUBLE_EQ(w(0, 1), 1.0);
    EXPECT_DOUBLE_EQ(w(1, 0), ObservationPrior::kMaxStrength);
    EXPECT_DOUBLE_EQ(w(2, 1), ObservationPrior::kMaxStrength);
  }
  prior.subject_alpha.row(0) << 1, 1;
  EXPECT_EQ(weighed_subject_prior(prior, 5.0), Eigen::MatrixXd::Ones(3, 2));
}

// The held-out score of choose_strength, by hand: each trajectory's own expected counts
// from the exact engine, its log-likelihood under the posterior mean of the prior and
// the other trajectories' counts.
TEST(ObservationEStep, HeldOutLikelihoodByHand) {
  ObservedGridworld g = observed_gridworld(9, 2, 6, EtaKind::kPlausible);
  g.prior.learn_eta = false;
  g.prior.strength = std::sqrt(10.0);
  std::vector<ObservedTrajectory> data(g.observations.trajectories.begin(), g.observations.trajectories.begin() + 4);
  const ObservationEStep estep(g.task.mdp, data, g.prior);
  const SoftSolution policy = soft_value_iteration(g.task.mdp, g.task.mdp.reward(g.task.true_weights));
  EStepState state = estep.initial_state(1);
  estep.expect(policy, state);  // away from the prior
  const std::optional<StrengthChoice> choice = estep.choose_strength(policy, state);
  ASSERT_TRUE(choice);
  const ObservationModel model = dirichlet_mean(*state.alpha);
  ExactEngine engine(g.task.mdp);
  std::vector<EStepStatistics> own;
  AlphaCounts all = AlphaCounts::zero(g.task.mdp.num_pairs(), 2, 4);
  for (const ObservedTrajectory& t : estep.trajectories()) {
    own.push_back(EStepStatistics::zero(g.task.mdp.num_pairs(), 2, 4));
    engine.accumulate(policy, model, t, own.back());
    all += own.back().alpha_dot;
  }
  double held_out = 0.0;
  for (size_t i = 0; i < own.size(); ++i) {
    AlphaCounts others = all;
    others.subject -= own[i].alpha_dot.subject;
    others.confounders -= own[i].alpha_dot.confounders;
    const AlphaCounts posterior = dirichlet_posterior(g.prior, g.prior.strength, others);
    held_out +=
        engine.log_likelihood(policy, {dirichlet_mean(posterior.subject), dirichlet_mean(posterior.confounders), {}},
                              estep.trajectories()[i]);
  }
  EXPECT_NEAR(choice->current_score, held_out, 1e-8 * std::abs(held_out));
  EXPECT_GE(choice->best_score, choice->current_score);
  // Not automatic: nothing to choose.
  g.prior.automatic_strength = false;
  const ObservationEStep fixed(g.task.mdp, data, g.prior);
  EXPECT_FALSE(fixed.choose_strength(policy, fixed.initial_state(1)));
}

// A cross-fitted pass by hand (ObservationEStepOptions::cross_fit): every trajectory's
// expected counts under the current O, each one's own, O_{-i} the Dirichlet posterior at
// the state's strength from the others' counts, and the trajectory's posterior under it.
// The strength is changed after the last refinement, as HiddenDataEM does when it chooses
// another: O_{-i} is the posterior at the new strength, not alpha less the own counts.
TEST(ObservationEStep, CrossFittedPassByHand) {
  ObservedGridworld g = observed_gridworld(9, 2, 6, EtaKind::kPlausible);
  g.prior.learn_eta = false;
  g.prior.automatic_strength = false;
  g.prior.strength = std::sqrt(10.0);
  std::vector<ObservedTrajectory> data(g.observations.trajectories.begin(), g.observations.trajectories.begin() + 4);
  ObservationEStepOptions options;
  options.max_alpha_iterations = 1;
  const ObservationEStep plain(g.task.mdp, data, g.prior, options);
  options.cross_fit = true;
  const ObservationEStep cross(g.task.mdp, data, g.prior, options);
  const SoftSolution policy = soft_value_iteration(g.task.mdp, g.task.mdp.reward(g.task.true_weights));
  EStepState state = plain.initial_state(1);
  plain.expect(policy, state);  // away from the prior
  state.alpha->strength = 100.0;
  EStepState copy = state;
  const EStepResult fitted = cross.expect(policy, copy);

  const int P = g.task.mdp.num_pairs();
  const ObservationModel model = dirichlet_mean(*state.alpha);
  ExactEngine engine(g.task.mdp);
  std::vector<EStepStatistics> own;
  AlphaCounts all = AlphaCounts::zero(P, 2, 4);
  for (const ObservedTrajectory& t : cross.trajectories()) {
    own.push_back(EStepStatistics::zero(P, 2, 4));
    engine.accumulate(policy, model, t, own.back());
    all += own.back().alpha_dot;
  }
  EStepStatistics by_hand = EStepStatistics::zero(P, 2, 4);
  for (size_t i = 0; i < own.size(); ++i) {
    AlphaCounts others = all;
    others.subject -= own[i].alpha_dot.subject;
    others.confounders -= own[i].alpha_dot.confounders;
    const AlphaCounts posterior = dirichlet_posterior(g.prior, 100.0, others);
    engine.accumulate(policy, {dirichlet_mean(posterior.subject), dirichlet_mean(posterior.confounders), {}},
                      cross.trajectories()[i], by_hand);
  }
  EXPECT_LT((fitted.counts - by_hand.counts).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_NEAR(fitted.log_likelihood, by_hand.log_likelihood, 1e-9 * std::abs(by_hand.log_likelihood));
  // And it is not the plain pass: leaving a trajectory out moves its posterior.
  EStepState again = state;
  const EStepResult ordinary = plain.expect(policy, again);
  EXPECT_GT((fitted.counts - ordinary.counts).cwiseAbs().maxCoeff(), 1e-6);
  // An executor would compute plain passes: refused.
  struct Elsewhere final : BlockExecutor {
    std::vector<EStepStatistics> run(const ObservationEStep&, const SoftSolution&, const ObservationModel&,
                                     std::uint64_t, const RowMatrix*) override {
      return {};
    }
  };
  options.executor = std::make_shared<Elsewhere>();
  EXPECT_THROW(ObservationEStep(g.task.mdp, data, g.prior, options), InputError);
}

// Learned eta recovers a known miscalibration. The Gridworld's plausible eta gives the
// favoured source 0.6, but observations are drawn from the sources evenly and the
// favoured one is the true one with probability 0.8 (else any of the n sources): so
// Pr(true source = favoured | eta) = 0.8 + 0.2 / n. With the true O fixed and the true
// policy, the context that favours the subject must learn that, not 0.6; and with a huge
// prior strength learned eta stays the stated one.
TEST(ObservationEStep, LearnedEtaRecoversTheLabellersCalibration) {
  Rng rng(3);
  GridworldTask task = make_gridworld_task({}, 60, 10, rng);
  const Eigen::MatrixXd subject = gridworld_subject_observation_model(5, 1.0);
  const Eigen::MatrixXd elements = random_confounder_observation_model(3, rng);
  GridworldObservationOptions options;
  options.confounders = 3;
  options.per_step = 40;
  options.eta = EtaKind::kPlausible;
  const GridworldObservations observed =
      observe_gridworld(task.mdp, task.trajectories, subject, elements, options, rng);
  const SoftSolution policy = soft_value_iteration(task.mdp, task.mdp.reward(task.true_weights));
  for (double kappa : {10.0, 1e12}) {
    const ObservationEStep estep(task.mdp, observed.trajectories, known_o_prior(subject, elements, kappa));
    ASSERT_EQ(estep.num_contexts(), 4);  // one per favoured source
    EStepState state = estep.initial_state(1);
    for (int i = 0; i < 30; ++i) estep.expect(policy, state);
    const RowMatrix learned = *estep.learned_eta(*state.alpha);
    for (int c = 0; c < 4; ++c) {
      Eigen::Index favoured = 0;
      estep.context_eta().row(c).maxCoeff(&favoured);
      if (kappa > 1e6) {
        EXPECT_LT((learned.row(c) - estep.context_eta().row(c)).cwiseAbs().maxCoeff(), 1e-6);
      } else if (favoured == 0) {
        EXPECT_NEAR(learned(c, 0), 0.8 + 0.2 / 4, 0.03) << learned.row(c);
      }
    }
  }
}

// A labeller that states 0.8 for its pick but is right only 40% of the time (|E| = 3):
// with O known, learned eta converges to its true calibration per context (its pick),
// not to what it states.
TEST(ObservationEStep, LearnedEtaRecoversAMiscalibratedLabeller) {
  Rng rng(5);
  GridworldTask task = make_gridworld_task({}, 60, 10, rng);
  const Eigen::MatrixXd subject = gridworld_subject_observation_model(5, 1.0);
  const Eigen::MatrixXd elements = random_confounder_observation_model(3, rng);
  GridworldObservationOptions options;
  options.confounders = 3;
  GridworldObservations observed = observe_gridworld(task.mdp, task.trajectories, subject, elements, options, rng);
  const Labeller labeller{0.8, 0.4};
  assign_labeller_eta(observed, 4, labeller, rng);
  const SoftSolution policy = soft_value_iteration(task.mdp, task.mdp.reward(task.true_weights));
  const ObservationEStep estep(task.mdp, observed.trajectories, known_o_prior(subject, elements, 10.0));
  ASSERT_EQ(estep.num_contexts(), 4);  // the labeller's picks
  EStepState state = estep.initial_state(1);
  for (int i = 0; i < 40; ++i) estep.expect(policy, state);
  const RowMatrix learned = *estep.learned_eta(*state.alpha);
  for (int pick = 0; pick < 4; ++pick) {
    EXPECT_NEAR(estep.context_eta()(pick, pick), 0.8, 1e-12);
    const Eigen::VectorXd truth = labeller_calibration(labeller, 4, pick);
    EXPECT_LT((learned.row(pick).transpose() - truth).cwiseAbs().maxCoeff(), 0.03)
        << "pick " << pick << ": learned " << learned.row(pick) << ", true " << truth.transpose();
    EXPECT_GT(estep.context_observations()[pick], 2000.0);
  }
}

// With a very strong prior on eta (kappa = 1e13) learned eta stays the stated eta to 1e-9,
// and EM's answer is fixed eta's.
TEST(HiddenDataEm, VeryStrongEtaPriorIsFixedEta) {
  ObservedGridworld g = observed_gridworld(6, 3, 10, EtaKind::kPlausible);
  std::vector<ObservedTrajectory> data(g.observations.trajectories.begin(), g.observations.trajectories.begin() + 8);
  g.prior.automatic_strength = false;
  g.prior.eta_strength = 1e13;
  g.prior.learn_eta = true;
  const ObservationEStep learned_estep(g.task.mdp, data, g.prior);
  g.prior.learn_eta = false;
  const ObservationEStep fixed_estep(g.task.mdp, data, g.prior);
  LearnOptions learn;
  learn.theta_tolerance = 1e-8;
  learn.likelihood_tolerance = 1e-12;
  learn.max_em_iterations = 2000;
  const LearnResult learned = learn_reward(g.task.mdp, learned_estep, learn);
  const LearnResult fixed = learn_reward(g.task.mdp, fixed_estep, learn);
  const RowMatrix eta = *learned_estep.learned_eta(*learned.restarts[0].alpha);
  EXPECT_LT((eta - learned_estep.context_eta()).cwiseAbs().maxCoeff(), 1e-9);
  // theta then differs only by where each EM run stopped (its tolerances; 4e-5 under the
  // sanitizers' floating point), not by eta.
  EXPECT_LT((learned.theta - fixed.theta).lpNorm<Eigen::Infinity>(),
            1e-3 * std::max(1.0, fixed.theta.lpNorm<Eigen::Infinity>()))
      << learned.theta.transpose() << " vs " << fixed.theta.transpose();
}

// docs/MODEL.md "Unlisted confounders": under the paper's model (a label per observation,
// drawn independently) two unlisted elements with fixed O_1, O_2 that the labeller cannot
// tell apart (eta/2 each) have exactly the likelihood of one source with O = (O_1 + O_2)/2
// and eta: sum_z eta_z O_z(w) is the same for every observation.
TEST(ObservationEStep, UnlistedElementsAreOneSourceWithTheirMixture) {
  Rng rng(41);
  for (int trial = 0; trial < 60; ++trial) {
    testing::TinyProblem p = testing::tiny_problem(trial, rng);
    const int listed = p.model.num_confounders();
    const int symbols = p.model.num_symbols();
    const Eigen::MatrixXd unlisted = testing::random_distributions(2, symbols, rng);
    const double epsilon = 0.05 + 0.5 * rng.uniform();
    ObservationModel two = p.model, one = p.model;
    two.confounders.conservativeResize(listed + 2, symbols);
    two.confounders.bottomRows(2) = unlisted;
    one.confounders.conservativeResize(listed + 1, symbols);
    one.confounders.row(listed) = 0.5 * (unlisted.row(0) + unlisted.row(1));
    ObservedTrajectory with_two = p.trajectory, with_one = p.trajectory;
    const Eigen::Index n = p.trajectory.eta.rows();
    with_two.eta.conservativeResize(n, listed + 3);
    with_one.eta.conservativeResize(n, listed + 2);
    with_two.eta.leftCols(listed + 1) *= 1.0 - epsilon;
    with_one.eta.leftCols(listed + 1) *= 1.0 - epsilon;
    with_two.eta.rightCols(2).setConstant(epsilon / 2.0);
    with_one.eta.col(listed + 1).setConstant(epsilon);
    ExactEngine engine(p.mdp);
    const double a = engine.log_likelihood(p.policy, two, with_two);
    const double b = engine.log_likelihood(p.policy, one, with_one);
    ASSERT_TRUE(std::isfinite(a)) << "trial " << trial;
    EXPECT_NEAR(a, b, 1e-12 * std::max(1.0, std::abs(a))) << "trial " << trial;
  }
}

// add_unlisted_source: eta scaled by (1 - epsilon), epsilon to one more source with a flat
// prior; applying it twice adds it once.
TEST(ObservationEStep, AddUnlistedSourceAddsOneFlatSource) {
  Rng rng(8);
  testing::TinyProblem p = testing::tiny_problem(3, rng);
  while (p.trajectory.num_observations() == 0) p = testing::tiny_problem(3, rng);
  ObservationPrior prior = testing::prior_at(p.model);  // its mean is the model
  prior.unlisted_eta = 0.25;
  std::vector<ObservedTrajectory> data{p.trajectory};
  add_unlisted_source(prior, data);
  add_unlisted_source(prior, data);
  ASSERT_EQ(prior.num_confounders, p.model.num_confounders() + 1);
  ASSERT_TRUE(prior.unlisted_added);
  EXPECT_EQ(prior.confounder_alpha.row(prior.num_confounders - 1), Eigen::RowVectorXd::Ones(prior.num_symbols));
  ASSERT_EQ(data[0].eta.cols(), p.trajectory.eta.cols() + 1);
  EXPECT_LT((data[0].eta.leftCols(p.trajectory.eta.cols()) - 0.75 * p.trajectory.eta).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_TRUE((data[0].eta.rightCols(1).array() == 0.25).all());
  ObservationPrior bad = prior;
  bad.unlisted_added = false;
  bad.unlisted_eta = 1.0;
  try {
    add_unlisted_source(bad, data);
    ADD_FAILURE() << "epsilon = 1 accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "observation_model.unlisted_source.eta");
  }
}

// The posterior update's answer does not depend on c (the paper's step size, which the
// exact M-step does not use): EM with c = 1, 0.5 and 0.02 ends at the same bits.
TEST(HiddenDataEm, PosteriorUpdateGivesTheSameAnswerForAnyC) {
  ObservedGridworld g = observed_gridworld(4, 2, 10, EtaKind::kPlausible);
  std::vector<ObservedTrajectory> data(g.observations.trajectories.begin(), g.observations.trajectories.begin() + 8);
  std::optional<LearnResult> first;
  for (double c : {1.0, 0.5, 0.02}) {
    g.prior.c = c;
    const ObservationEStep estep(g.task.mdp, data, g.prior, ObservationEStepOptions{});
    LearnOptions learn;
    learn.max_em_iterations = 3000;
    const LearnResult r = learn_reward(g.task.mdp, estep, learn);
    ASSERT_TRUE(r.restarts[0].converged) << "c = " << c;
    if (!first) {
      first = r;
      continue;
    }
    EXPECT_EQ(r.theta, first->theta) << "c = " << c;
    EXPECT_EQ(r.restarts[0].alpha->strength, first->restarts[0].alpha->strength) << "c = " << c;
    EXPECT_EQ(r.restarts[0].alpha->subject_alpha, first->restarts[0].alpha->subject_alpha) << "c = " << c;
  }
}

}  // namespace
}  // namespace hbirl
