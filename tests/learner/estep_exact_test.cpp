#include "learner/estep_exact.hpp"

#include <gtest/gtest.h>

#include <limits>

#include <array>
#include <cmath>

#include "brute_force_posterior.hpp"
#include "tiny_observed_problem.hpp"

namespace hbirl {
namespace {

// The exact posterior against brute-force enumeration's; false when the truth has
// probability 0 (then the engine must say so too).
bool expect_matches_enumeration(const testing::BruteForce& truth, const TrajectoryPosterior& post,
                                const ObservedTrajectory& trajectory, int trial) {
  if (truth.likelihood == 0.0) {
    EXPECT_EQ(post.log_likelihood, -std::numeric_limits<double>::infinity()) << "trial " << trial;
    return false;
  }
  EXPECT_NEAR(post.log_likelihood, std::log(truth.likelihood), 1e-9) << "trial " << trial;
  EXPECT_LT((post.marginals - truth.marginals).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
  if (trajectory.num_observations() > 0) {
    EXPECT_LT((post.sources - truth.sources).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
  }
  if (trajectory.ends_in_terminal) {
    EXPECT_LT((post.end_states - truth.end_states).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
  }
  return true;
}

// The terminal state a trajectory entered, when seen (ObservedTrajectory::end_state):
// the posterior conditions on entering that one, as brute-force enumeration says, and the
// likelihoods of the two ends add up to that of an unseen end.
TEST(ExactEngine, SeenEndStateEqualsBruteForceEnumeration) {
  Rng rng(4242);
  int compared = 0, impossible = 0;
  for (int trial = 0; trial < 40; ++trial) {
    testing::TinyProblem p = testing::two_exits(trial, rng);
    ExactEngine engine(p.mdp);
    const double unseen = engine.posterior(p.policy, p.model, p.trajectory).log_likelihood;
    double sum = 0.0;
    for (int end = 2; end <= 3; ++end) {
      p.trajectory.end_state = end;
      const testing::BruteForce truth = testing::brute_force(p.mdp, p.policy, p.model, p.trajectory);
      const TrajectoryPosterior post = engine.posterior(p.policy, p.model, p.trajectory);
      if (!expect_matches_enumeration(truth, post, p.trajectory, trial)) {
        ++impossible;
        continue;
      }
      ++compared;
      sum += truth.likelihood;
    }
    if (sum > 0.0) {
      EXPECT_NEAR(std::log(sum), unseen, 1e-9) << "trial " << trial;
    }
  }
  EXPECT_GE(compared, 40);  // (an end no last pair can reach is rare here: `impossible` counts them)
  EXPECT_LT(impossible, 40);
}

// An end sensor's reports (end_symbols under O_end) against brute-force enumeration: the
// likelihood, the marginals, the sources, the posterior of the state entered and the end
// sensor's expected counts, by the per-observation and the by-kind accumulation. One
// report's likelihoods, summed over the symbols it could have been, are the unreported end's.
TEST(ExactEngine, EndSymbolsEqualBruteForceEnumeration) {
  Rng rng(777);
  int compared = 0, impossible = 0;
  for (int trial = 0; trial < 40; ++trial) {
    testing::TinyProblem p = testing::two_exits(trial, rng);
    const int K = 2 + trial % 2;
    p.model.end = testing::random_distributions(p.mdp.num_states, K, rng);
    if (trial % 5 == 0) {  // a symbol one terminal state never gives
      p.model.end(2 + trial % 2, 0) = 0.0;
      p.model.end.row(2 + trial % 2) /= p.model.end.row(2 + trial % 2).sum();
    }
    ExactEngine engine(p.mdp);
    const double unreported = engine.posterior(p.policy, p.model, p.trajectory).log_likelihood;
    double one_report = 0.0;
    for (int w = 0; w < K; ++w) {
      p.trajectory.end_symbols = {w};
      one_report += std::exp(engine.posterior(p.policy, p.model, p.trajectory).log_likelihood);
    }
    EXPECT_NEAR(std::log(one_report), unreported, 1e-9) << "trial " << trial;
    p.trajectory.end_symbols.clear();
    for (int i = 1 + trial % 3; i > 0; --i) p.trajectory.end_symbols.push_back(rng.uniform_int(K));
    const testing::BruteForce truth = testing::brute_force(p.mdp, p.policy, p.model, p.trajectory);
    const TrajectoryPosterior post = engine.posterior(p.policy, p.model, p.trajectory);
    if (!expect_matches_enumeration(truth, post, p.trajectory, trial)) {
      ++impossible;
      continue;
    }
    ++compared;
    EStepStatistics stats = EStepStatistics::zero(p.mdp.num_pairs(), p.model.num_confounders(), p.model.num_symbols());
    engine.accumulate(p.policy, p.model, p.trajectory, stats);
    EXPECT_NEAR(stats.log_likelihood, truth.stats.log_likelihood, 1e-9);
    EXPECT_LT((stats.counts - truth.stats.counts).cwiseAbs().maxCoeff(), 1e-9);
    ASSERT_EQ(stats.alpha_dot.end.rows(), p.mdp.num_states);
    EXPECT_LT((stats.alpha_dot.end - truth.stats.alpha_dot.end).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
    EXPECT_NEAR(stats.alpha_dot.end.sum(), static_cast<double>(p.trajectory.end_symbols.size()), 1e-9);
    // By kinds: the same sums.
    const std::vector<ObservedTrajectory> one{p.trajectory};
    const ObservationKinds kinds = *observation_kinds(one, 100);
    EStepStatistics by_kind =
        EStepStatistics::zero(p.mdp.num_pairs(), p.model.num_confounders(), p.model.num_symbols());
    accumulate_by_kind(engine, p.policy, p.model, one, 0, 1, kinds, kind_emissions(p.model, kinds), -1, by_kind);
    EXPECT_NEAR(by_kind.log_likelihood, truth.stats.log_likelihood, 1e-9);
    EXPECT_LT((by_kind.alpha_dot.end - truth.stats.alpha_dot.end).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((by_kind.alpha_dot.subject - truth.stats.alpha_dot.subject).cwiseAbs().maxCoeff(), 1e-9);
  }
  EXPECT_GE(compared, 30);
  RecordProperty("impossible", impossible);
}

TEST(ExactEngine, EqualsBruteForceEnumeration) {
  Rng rng(2024);
  int ends_tested = 0;
  int scaled = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const testing::TinyProblem p = testing::tiny_problem(trial, rng);
    const testing::BruteForce truth = testing::brute_force(p.mdp, p.policy, p.model, p.trajectory);
    if (p.trajectory.ends_in_terminal && truth.likelihood == 0.0) continue;  // no way out: skip
    ASSERT_GT(truth.likelihood, 0.0) << "trial " << trial;
    ends_tested += p.trajectory.ends_in_terminal;
    ExactEngine engine(p.mdp);
    const TrajectoryPosterior post = engine.posterior(p.policy, p.model, p.trajectory);
    scaled += engine.last_passes_scaled();
    EXPECT_NEAR(post.log_likelihood, std::log(truth.likelihood), 1e-9) << "trial " << trial;
    EXPECT_LT((post.marginals - truth.marginals).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
    if (p.trajectory.num_observations() > 0) {
      EXPECT_LT((post.sources - truth.sources).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
    }
    EStepStatistics stats = EStepStatistics::zero(p.mdp.num_pairs(), p.model.num_confounders(), p.model.num_symbols());
    engine.accumulate(p.policy, p.model, p.trajectory, stats);
    EXPECT_NEAR(stats.log_likelihood, truth.stats.log_likelihood, 1e-9);
    EXPECT_LT((stats.counts - truth.stats.counts).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((stats.alpha_dot.subject - truth.stats.alpha_dot.subject).cwiseAbs().maxCoeff(), 1e-9);
    if (p.model.num_confounders() > 0) {
      EXPECT_LT((stats.alpha_dot.confounders - truth.stats.alpha_dot.confounders).cwiseAbs().maxCoeff(), 1e-9);
    }
  }
  EXPECT_GE(ends_tested, 3);  // trajectories known to end in a terminal state were covered
  EXPECT_GE(scaled, 40);      // mostly by the scaled passes (RowsFarBelowTheMaximumStayExact covers the others)
}

// Thousands of observations per step and long trajectories: a direct product of the
// emissions would underflow; the log-space engine stays finite and normalised.
TEST(ExactEngine, ThousandsOfObservationsAndLongTrajectoriesDoNotUnderflow) {
  Rng rng(5);
  testing::TinyProblem p = testing::tiny_problem(0, rng);  // deterministic transitions
  const int length = 2000;
  const int per_step = 1000;
  ObservedTrajectory& tr = p.trajectory;
  tr = ObservedTrajectory{};
  const int Z = 1 + p.model.num_confounders();
  tr.eta = RowMatrix::Constant(static_cast<Eigen::Index>(length / 100) * per_step, Z, 1.0 / Z);
  for (int t = 0; t < length; ++t) {
    const int n = t % 100 == 0 ? per_step : 0;  // mostly occluded, some steps with 1000
    for (int i = 0; i < n; ++i) tr.symbols.push_back(rng.uniform_int(p.model.num_symbols()));
    tr.step_begin.push_back(static_cast<int>(tr.symbols.size()));
  }
  ExactEngine engine(p.mdp);
  const TrajectoryPosterior post = engine.posterior(p.policy, p.model, tr);
  EXPECT_TRUE(std::isfinite(post.log_likelihood));
  EXPECT_LT(post.log_likelihood, -1000.0);  // far below what a double product can hold
  for (int t = 0; t < length; t += 97) EXPECT_NEAR(post.marginals.row(t).sum(), 1.0, 1e-9) << t;
  for (int n = 0; n < tr.num_observations(); n += 333) EXPECT_NEAR(post.sources.row(n).sum(), 1.0, 1e-9);
}

// log sum_j exp(x_j), -inf for none: the reference below sums every row in log space.
double reference_lse(const std::vector<double>& x) {
  double m = -INFINITY;
  for (double v : x) m = std::max(m, v);
  if (m == -INFINITY) return m;
  double sum = 0.0;
  for (double v : x) sum += std::exp(v - m);
  return m + std::log(sum);
}

// A plain log-space forward-backward straight from the definitions, every sum its own
// log-sum-exp: the log emissions, log alpha, log beta (with a terminal exit at the end
// when the trajectory is known to have ended, into end_state when that was seen) and the
// log-likelihood.
struct Reference {
  std::vector<std::vector<double>> log_emission, la, lb;
  double log_likelihood = -INFINITY;
};

Reference reference_posterior(const Mdp& mdp, const SoftSolution& policy, const ObservationModel& model,
                              const ObservedTrajectory& tr) {
  const int T = tr.length();
  const int P = mdp.num_pairs();
  const int A = mdp.num_actions;
  const int E = model.num_confounders();
  Reference ref;
  auto& e = ref.log_emission;
  e.assign(static_cast<size_t>(T), std::vector<double>(static_cast<size_t>(P), 0.0));
  for (int t = 0; t < T; ++t) {
    for (int r = 0; r < P; ++r) {
      for (int n = tr.step_begin[static_cast<size_t>(t)]; n < tr.step_begin[static_cast<size_t>(t) + 1]; ++n) {
        const int w = tr.symbols[static_cast<size_t>(n)];
        double p = tr.eta(n, 0) * model.subject(r, w);
        for (int z = 0; z < E; ++z) p += tr.eta(n, z + 1) * model.confounders(z, w);
        e[static_cast<size_t>(t)][static_cast<size_t>(r)] += tr.weight(n) * std::log(p);
      }
    }
  }
  auto log_t = [&](int r, int s2) { return std::log(mdp.transitions.coeff(r, s2)); };
  auto& la = ref.la;
  auto& lb = ref.lb;
  la.assign(static_cast<size_t>(T), std::vector<double>(static_cast<size_t>(P)));
  lb.assign(static_cast<size_t>(T), std::vector<double>(static_cast<size_t>(P), 0.0));
  for (int t = 0; t < T; ++t) {
    for (int r = 0; r < P; ++r) {
      const int s = r / A;
      double d = std::log(mdp.start[s]);
      if (t > 0) {
        std::vector<double> in;
        for (int q = 0; q < P; ++q) in.push_back(la[static_cast<size_t>(t) - 1][static_cast<size_t>(q)] + log_t(q, s));
        d = reference_lse(in);
      }
      la[static_cast<size_t>(t)][static_cast<size_t>(r)] =
          mdp.is_terminal(s) ? -INFINITY : d + policy.log_policy[r] + e[static_cast<size_t>(t)][static_cast<size_t>(r)];
    }
  }
  if (tr.ends_in_terminal) {
    for (int r = 0; r < P; ++r) {
      std::vector<double> out;
      for (int s2 = 0; s2 < mdp.num_states; ++s2) {
        if (!mdp.is_terminal(s2) || (tr.end_state >= 0 && s2 != tr.end_state)) continue;
        double seen = log_t(r, s2);  // and what the end sensor reported of it
        for (int w : tr.end_symbols) seen += std::log(model.end(s2, w));
        out.push_back(seen);
      }
      lb[static_cast<size_t>(T) - 1][static_cast<size_t>(r)] = reference_lse(out);
    }
  }
  for (int t = T - 2; t >= 0; --t) {
    for (int r = 0; r < P; ++r) {
      std::vector<double> out;
      for (int q = 0; q < P; ++q) {
        if (mdp.is_terminal(q / A)) continue;
        out.push_back(log_t(r, q / A) + policy.log_policy[q] + e[static_cast<size_t>(t) + 1][static_cast<size_t>(q)] +
                      lb[static_cast<size_t>(t) + 1][static_cast<size_t>(q)]);
      }
      lb[static_cast<size_t>(t)][static_cast<size_t>(r)] = reference_lse(out);
    }
  }
  std::vector<double> last;
  for (int r = 0; r < P; ++r)
    last.push_back(la[static_cast<size_t>(T) - 1][static_cast<size_t>(r)] +
                   lb[static_cast<size_t>(T) - 1][static_cast<size_t>(r)]);
  ref.log_likelihood = reference_lse(last);
  return ref;
}

void expect_marginals(const Reference& ref, const TrajectoryPosterior& post, int trial) {
  for (size_t t = 0; t < ref.la.size(); ++t) {
    for (size_t r = 0; r < ref.la[t].size(); ++r) {
      const double gamma = std::exp(ref.la[t][r] + ref.lb[t][r] - ref.log_likelihood);
      EXPECT_NEAR(post.marginals(static_cast<Eigen::Index>(t), static_cast<Eigen::Index>(r)), gamma, 1e-9)
          << "trial " << trial << " step " << t << " pair " << r;
    }
  }
}

// Heavy observations (weights in the hundreds, as merged repeats give) make the steps'
// log emissions differ by thousands between pairs, so states fall e^-1000 below others
// and become likely again later: the engine must then leave its scaled linear-space
// passes for the log-space ones, whose vectorised sums recompute the rows that
// underflow. Lighter ones (the second half of the trials) spread tens to hundreds of
// nats, where the scaled passes must be exact by themselves. Against a plain log-space
// forward-backward, every row summed by its own log-sum-exp, on random MDPs (terminal
// states, impossible actions, deterministic transitions).
TEST(ExactEngine, RowsFarBelowTheMaximumStayExact) {
  Rng rng(77);
  int extreme = 0;
  int scaled = 0;
  for (int trial = 0; trial < 80; ++trial) {
    const bool heavy = trial < 40;
    testing::RandomMdpOptions o = testing::varied_options(trial);
    o.states = 4 + trial % 7;
    o.actions = 2 + trial % 3;
    o.successors = std::min(3, o.states);
    const Mdp mdp = testing::random_mdp(o, rng);
    const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(testing::random_vector(o.features, rng, 2.0)));
    ObservationModel model;
    const int symbols = 3;
    model.subject = testing::random_distributions(mdp.num_pairs(), symbols, rng);
    model.confounders = testing::random_distributions(trial % 3, symbols, rng);
    for (Eigen::Index i = 0; i < model.subject.size(); ++i) {
      if (rng.uniform() < 0.3) model.subject.data()[i] *= 1e-3;  // near-impossible symbols
    }
    const int E = model.num_confounders();
    ObservedTrajectory tr;
    const int T = 6;
    for (int t = 0; t < T; ++t) {
      for (int i = rng.uniform_int(3); i > 0; --i) {
        tr.symbols.push_back(rng.uniform_int(symbols));
        tr.weights.push_back(heavy ? 50.0 + rng.uniform_int(900) : 1.0 + rng.uniform_int(60));
      }
      tr.step_begin.push_back(static_cast<int>(tr.symbols.size()));
    }
    tr.eta.resize(tr.num_observations(), 1 + E);
    for (int n = 0; n < tr.num_observations(); ++n) {
      for (int z = 0; z <= E; ++z) tr.eta(n, z) = z == 0 ? 0.7 : 0.3 / E;
    }
    // The reference, straight from the definitions.
    const Reference ref = reference_posterior(mdp, policy, model, tr);
    const double ll = ref.log_likelihood;
    double spread = 0.0;
    for (int t = 0; t < T; ++t) {
      const auto [lo, hi] = std::minmax_element(ref.log_emission[static_cast<size_t>(t)].begin(),
                                                ref.log_emission[static_cast<size_t>(t)].end());
      spread = std::max(spread, *hi - *lo);
    }
    ASSERT_TRUE(std::isfinite(ll)) << "trial " << trial;
    extreme += heavy && spread > 1000.0;
    ExactEngine engine(mdp);
    const TrajectoryPosterior post = engine.posterior(policy, model, tr);
    scaled += engine.last_passes_scaled();
    EXPECT_NEAR(post.log_likelihood, ll, 1e-12 * std::abs(ll)) << "trial " << trial;
    expect_marginals(ref, post, trial);
  }
  EXPECT_GE(extreme, 20);  // most heavy trials had log emissions more than 1000 apart within a step
  EXPECT_GE(scaled, 20);   // the scaled passes were exact by themselves in many
}

// Two states that keep to themselves (one action, deterministic self-loops), started
// half and half. Step 0's observations favour A by 800 nats, so in linear space B's
// forward probability underflows to 0; step 1's favour B by 1,600 nats, so B is in fact
// the likely one. By hand: log Pr = log(0.5 e^{x_A} + 0.5 e^{x_B}) with x the summed log
// emissions of each state's path, and B's marginal is 1 / (1 + e^{x_A - x_B}). The
// engine must notice the mass it lost and go to log space.
TEST(ExactEngine, MassLostInLinearSpaceIsNoticed) {
  const Mdp mdp =
      make_mdp(2, 1, 1, {{0, 0, 0, 1.0}, {1, 0, 1, 1.0}}, {{0, 0, 0, 1.0}}, Eigen::Vector2d(0.5, 0.5), {}, 0.9);
  const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(Eigen::VectorXd::Zero(1)));
  ObservationModel model;
  model.subject.resize(2, 2);
  model.subject << 0.9, 0.1,  // A mostly shows symbol 0
      1e-4, 1.0 - 1e-4;       // B almost never
  model.confounders.resize(0, 2);
  ObservedTrajectory tr;
  const double log_ratio = std::log(0.9 / 1e-4);            // nats per symbol-0 observation for A
  const double w0 = 800.0 / log_ratio;                      // step 0: symbol 0, A ahead by 800 nats
  const double w1 = 1600.0 / std::log((1.0 - 1e-4) / 0.1);  // step 1: symbol 1, B ahead by 1,600
  tr.symbols = {0, 1};
  tr.weights = {w0, w1};
  tr.eta = RowMatrix::Ones(2, 1);
  tr.step_begin = {0, 1, 2};
  const double xa = w0 * std::log(0.9) + w1 * std::log(0.1);
  const double xb = w0 * std::log(1e-4) + w1 * std::log(1.0 - 1e-4);
  ASSERT_NEAR(xb - xa, 800.0, 1e-6);
  const double ll = std::log(0.5) + xb + std::log1p(std::exp(xa - xb));
  ExactEngine engine(mdp);
  // The forward pass alone (held-out likelihoods) must notice it too.
  EXPECT_NEAR(engine.log_likelihood(policy, model, tr), ll, 1e-9 * std::abs(xb));
  EXPECT_FALSE(engine.last_passes_scaled());
  const TrajectoryPosterior post = engine.posterior(policy, model, tr);
  EXPECT_FALSE(engine.last_passes_scaled());
  EXPECT_NEAR(post.log_likelihood, ll, 1e-9 * std::abs(xb));
  for (int t = 0; t < 2; ++t) {
    EXPECT_NEAR(post.marginals(t, 1), 1.0, 1e-12) << t;  // B, the whole way
    EXPECT_NEAR(post.marginals(t, 0), 0.0, 1e-12) << t;
  }
}

// Probabilities at the edge of the doubles, at random: start probabilities down to
// 1e-320, policies from rewards up to 400x (log pi in the -1000s, pi flushed to 0 or
// clamped), emission probabilities down to 1e-12 and exactly 0, observations weighing up
// to thousands of nats, trajectories of 1-6 steps that may end in a terminal state, on random MDPs (terminal states,
// impossible actions, deterministic transitions). Whatever the engine does -- the scaled passes or the log-space ones
// -- it must agree with the plain log-space reference, impossible trajectories included.
TEST(ExactEngine, ExtremeProbabilitiesStayExact) {
  Rng rng(4242);
  int scaled = 0, fallback = 0, impossible = 0, seen_end_fallback = 0, end_sensed = 0, end_sensed_fallback = 0;
  for (int trial = 0; trial < 400; ++trial) {
    testing::RandomMdpOptions o = testing::varied_options(trial);
    o.states = 3 + trial % 6;
    o.actions = 2 + trial % 3;
    o.successors = std::min(3, o.states);
    o.terminal = trial % 2 == 0 ? (trial % 8 == 0 ? 2 : 1) : 0;
    Mdp mdp = testing::random_mdp(o, rng);
    for (int s = 0; s < mdp.num_states; ++s) {
      if (mdp.start[s] > 0.0 && rng.uniform() < 0.5) mdp.start[s] *= std::pow(10.0, -rng.uniform(0.0, 320.0));
    }
    mdp.start /= mdp.start.sum();
    const double reward_scale = std::array<double, 3>{1.0, 50.0, 400.0}[static_cast<size_t>(trial % 3)];
    const SoftSolution policy =
        soft_value_iteration(mdp, mdp.reward(testing::random_vector(o.features, rng, reward_scale)));
    ObservationModel model;
    const int symbols = 3;
    model.subject = testing::random_distributions(mdp.num_pairs(), symbols, rng);
    for (Eigen::Index i = 0; i < model.subject.size(); ++i) {
      const double u = rng.uniform();
      if (u < 0.3) model.subject.data()[i] *= std::pow(10.0, -rng.uniform(0.0, 12.0));
      if (u > 0.95) model.subject.data()[i] = 0.0;  // a symbol this pair never shows
    }
    model.confounders = testing::random_distributions(trial % 2, symbols, rng);
    const int E = model.num_confounders();
    ObservedTrajectory tr;
    const int T = 1 + rng.uniform_int(6);
    const double heavy = std::array<double, 3>{1.0, 100.0, 600.0}[static_cast<size_t>((trial / 3) % 3)];
    for (int t = 0; t < T; ++t) {
      for (int i = rng.uniform_int(3); i > 0; --i) {
        tr.symbols.push_back(rng.uniform_int(symbols));
        tr.weights.push_back(1.0 + heavy * rng.uniform());
      }
      tr.step_begin.push_back(static_cast<int>(tr.symbols.size()));
    }
    tr.eta.resize(tr.num_observations(), 1 + E);
    for (int n = 0; n < tr.num_observations(); ++n) {
      for (int z = 0; z <= E; ++z) tr.eta(n, z) = z == 0 ? (E > 0 ? 0.9 : 1.0) : 0.1 / E;
    }
    tr.ends_in_terminal = o.terminal > 0 && trial % 4 == 0;
    if (o.terminal == 2 && trial % 16 == 0) tr.end_state = o.states - 1 - rng.uniform_int(2);  // which one was seen
    if (tr.ends_in_terminal && trial % 3 == 0 && tr.end_state < 0) {
      // An end sensor whose reports are hundreds of nats apart between the terminal states
      // (its own stream: the other trials' draws stay as they were).
      Rng end_rng(static_cast<std::uint64_t>(trial));
      model.end = testing::random_distributions(mdp.num_states, symbols, end_rng);
      for (Eigen::Index i = 0; i < model.end.size(); ++i) {
        if (end_rng.uniform() < 0.4) model.end.data()[i] *= std::pow(10.0, -end_rng.uniform(0.0, 300.0));
      }
      for (int i = 1 + end_rng.uniform_int(4); i > 0; --i) tr.end_symbols.push_back(end_rng.uniform_int(symbols));
    }
    const Reference ref = reference_posterior(mdp, policy, model, tr);
    ExactEngine engine(mdp);
    const TrajectoryPosterior post = engine.posterior(policy, model, tr);
    (engine.last_passes_scaled() ? scaled : fallback) += 1;
    seen_end_fallback += tr.end_state >= 0 && !engine.last_passes_scaled() && ref.log_likelihood > -INFINITY;
    end_sensed += !tr.end_symbols.empty() && ref.log_likelihood > -INFINITY;
    end_sensed_fallback += !tr.end_symbols.empty() && !engine.last_passes_scaled() && ref.log_likelihood > -INFINITY;
    if (ref.log_likelihood == -INFINITY) {
      ++impossible;
      EXPECT_EQ(post.log_likelihood, -INFINITY) << "trial " << trial;
      continue;
    }
    ASSERT_TRUE(std::isfinite(ref.log_likelihood)) << "trial " << trial;
    EXPECT_NEAR(post.log_likelihood, ref.log_likelihood, 1e-12 * std::max(1.0, std::abs(ref.log_likelihood)))
        << "trial " << trial;
    EXPECT_NEAR(engine.log_likelihood(policy, model, tr), ref.log_likelihood,
                1e-12 * std::max(1.0, std::abs(ref.log_likelihood)))
        << "trial " << trial;
    expect_marginals(ref, post, trial);
    if (!tr.end_symbols.empty()) {
      // The state entered, from the definitions: log q(s) = logsumexp_r (log alpha_T(r) +
      // log T(s | r)) + sum_k log O_end(s, w_k) - log-likelihood.
      const auto last = static_cast<size_t>(tr.length()) - 1;
      for (int s = 0; s < mdp.num_states; ++s) {
        std::vector<double> in;
        for (int r = 0; r < mdp.num_pairs(); ++r)
          in.push_back(ref.la[last][static_cast<size_t>(r)] + std::log(mdp.transitions.coeff(r, s)));
        double log_q = reference_lse(in);
        for (int w : tr.end_symbols) log_q += std::log(model.end(s, w));
        const double q = mdp.is_terminal(s) && log_q > -INFINITY ? std::exp(log_q - ref.log_likelihood) : 0.0;
        EXPECT_NEAR(post.end_states[s], q, 1e-9) << "trial " << trial << " state " << s;
      }
    }
  }
  // Both kinds of passes were exercised, the log-space ones with a seen end too.
  EXPECT_GE(scaled, 50);
  EXPECT_GE(fallback, 10);
  EXPECT_GE(seen_end_fallback, 1);
  EXPECT_GE(end_sensed, 10);  // possible trajectories with an end sensor's reports
  EXPECT_GE(end_sensed_fallback, 1);
  RecordProperty("scaled", scaled);
  RecordProperty("fallback", fallback);
  RecordProperty("impossible", impossible);
}

// One-step trajectories whose forward products underflow in linear space (found by a
// review): a start probability times a policy probability below the smallest double, a
// policy probability that is 0 while its log is finite, a terminal exit of probability
// 1e-330. Each against log Pr = logsumexp_r [log d(s) + log pi(r) + log e(r) + log b(r)]
// (b: the terminal exit's probability, or 1) and its softmax for the marginals.
struct OneStepCase {
  Mdp mdp;
  SoftSolution policy;
  ObservationModel model;
  ObservedTrajectory trajectory;
};

void expect_one_step_exact(const OneStepCase& c, const char* name) {
  const int P = c.mdp.num_pairs();
  const int A = c.mdp.num_actions;
  std::vector<double> terms(static_cast<size_t>(P), -INFINITY);
  for (int r = 0; r < P; ++r) {
    const int s = r / A;
    if (c.mdp.is_terminal(s) || c.policy.log_policy[r] == -INFINITY) continue;
    double log_e = 0.0;
    for (int n = 0; n < c.trajectory.num_observations(); ++n) {
      log_e += c.trajectory.weight(n) * std::log(c.model.subject(r, c.trajectory.symbols[static_cast<size_t>(n)]));
    }
    double exit = 1.0;
    if (c.trajectory.ends_in_terminal) {
      exit = 0.0;
      for (int s2 = 0; s2 < c.mdp.num_states; ++s2) {
        if (c.mdp.is_terminal(s2)) exit += c.mdp.transitions.coeff(r, s2);
      }
    }
    terms[static_cast<size_t>(r)] = std::log(c.mdp.start[s]) + c.policy.log_policy[r] + log_e + std::log(exit);
  }
  const double ll = reference_lse(terms);
  ASSERT_TRUE(std::isfinite(ll)) << name;
  ExactEngine engine(c.mdp);
  EXPECT_NEAR(engine.log_likelihood(c.policy, c.model, c.trajectory), ll, 1e-9 * std::abs(ll)) << name;
  const TrajectoryPosterior post = engine.posterior(c.policy, c.model, c.trajectory);
  EXPECT_NEAR(post.log_likelihood, ll, 1e-9 * std::abs(ll)) << name;
  for (int r = 0; r < P; ++r) {
    EXPECT_NEAR(post.marginals(0, r), std::exp(terms[static_cast<size_t>(r)] - ll), 1e-9) << name << " pair " << r;
  }
}

ObservedTrajectory one_observation(int symbol, double weight, bool ends_in_terminal = false) {
  ObservedTrajectory tr;
  if (weight > 0.0) {
    tr.symbols = {symbol};
    tr.weights = {weight};
    tr.eta = RowMatrix::Ones(1, 1);
  } else {
    tr.eta.resize(0, 1);
  }
  tr.step_begin = {0, tr.num_observations()};
  tr.ends_in_terminal = ends_in_terminal;
  return tr;
}

TEST(ExactEngine, UnderflowingForwardProductsStayExact) {
  {
    // Start 1e-295 on B, pi(b1 | B) ~ 1e-30: the product 1e-325 rounds to 0, yet the
    // observation favours (B, b1) by 1000 nats, so it is nearly all of the posterior.
    OneStepCase c;
    c.mdp = make_mdp(2, 2, 1, {{0, 0, 0, 1.0}, {0, 1, 0, 1.0}, {1, 0, 1, 1.0}, {1, 1, 1, 1.0}}, {{1, 1, 0, 1.0}},
                     Eigen::Vector2d(1.0, 1e-295), {}, 0.9);
    c.policy = soft_value_iteration(c.mdp, c.mdp.reward(Eigen::VectorXd::Constant(1, -69.0)));
    ASSERT_LT(c.mdp.start[1] * c.policy.policy[3], 1e-320);
    c.model.subject.resize(4, 2);
    c.model.subject << 1e-4, 1.0 - 1e-4, 1e-4, 1.0 - 1e-4, 1e-4, 1.0 - 1e-4, 1.0, 0.0;
    c.model.confounders.resize(0, 2);
    c.trajectory = one_observation(0, 1000.0 / std::log(1e4));
    expect_one_step_exact(c, "underflowing prior");
    // The same where nothing else can emit the observation at all.
    c.model.subject.topRows(3) << 0.0, 1.0, 0.0, 1.0, 0.0, 1.0;
    expect_one_step_exact(c, "underflowing prior, the only possible pair");
  }
  {
    // A policy probability that is 0 in linear space while its log is finite (-800).
    OneStepCase c;
    c.mdp = make_mdp(1, 3, 1, {{0, 0, 0, 1.0}, {0, 1, 0, 1.0}, {0, 2, 0, 1.0}}, {{0, 2, 0, 1.0}},
                     Eigen::VectorXd::Ones(1), {}, 0.9);
    c.policy = soft_value_iteration(c.mdp, c.mdp.reward(Eigen::VectorXd::Constant(1, -800.0)));
    c.policy.policy[2] = 0.0;  // as an exp that flushes to 0 leaves it
    ASSERT_GT(c.policy.log_policy[2], -INFINITY);
    c.model.subject.resize(3, 2);
    c.model.subject << 1e-4, 1.0 - 1e-4, 1e-4, 1.0 - 1e-4, 1.0, 0.0;
    c.model.confounders.resize(0, 2);
    c.trajectory = one_observation(0, 1000.0 / std::log(1e4));
    expect_one_step_exact(c, "policy probability flushed to 0");
  }
  {
    // A trajectory known to end in a terminal state, whose only way out has probability
    // 1e-290 * 1e-40: the normaliser underflows, the trajectory is possible.
    OneStepCase c;
    c.mdp = make_mdp(3, 1, 1, {{0, 0, 0, 1.0}, {1, 0, 1, 1.0}, {1, 0, 2, 1e-40}}, {{0, 0, 0, 1.0}},
                     Eigen::Vector3d(1.0, 1e-290, 0.0), {2}, 0.9);
    c.policy = soft_value_iteration(c.mdp, c.mdp.reward(Eigen::VectorXd::Zero(1)));
    c.model.subject = Eigen::MatrixXd::Constant(3, 2, 0.5);
    c.model.confounders.resize(0, 2);
    c.trajectory = one_observation(0, 0.0, true);
    expect_one_step_exact(c, "terminal exit of 1e-330");
  }
}

// A trajectory known to have ended, whose exit has probability 1e-249 (found by a second
// review): the backward messages start at 1e-249, and times a policy probability of 5e-131
// they would fall below the smallest double before the scale divides them -- the
// marginals of step 0 came out 0. The backward messages start divided by the normaliser.
TEST(ExactEngine, SmallExitProbabilityKeepsTheMarginals) {
  const Mdp mdp =
      make_mdp(2, 2, 1, {{0, 0, 0, 1 - 1e-249}, {0, 0, 1, 1e-249}, {0, 1, 0, 1 - 1e-249}, {0, 1, 1, 1e-249}},
               {{0, 1, 0, -300.0}}, Eigen::Vector2d(1.0, 0.0), {1}, 0.9);
  const SoftSolution policy = soft_value_iteration(mdp, mdp.reward(Eigen::VectorXd::Ones(1)));
  ObservationModel model;
  model.subject.resize(4, 2);
  model.subject << std::exp(-300.0), 1.0 - std::exp(-300.0), 1.0, 0.0, 0.5, 0.5, 0.5, 0.5;
  model.confounders.resize(0, 2);
  ObservedTrajectory tr;
  tr.step_begin = {0, 0, 1};  // step 0 occluded
  tr.symbols = {0};
  tr.eta = RowMatrix::Ones(1, 1);
  tr.ends_in_terminal = true;
  const Reference ref = reference_posterior(mdp, policy, model, tr);
  ASSERT_TRUE(std::isfinite(ref.log_likelihood));
  ExactEngine engine(mdp);
  const TrajectoryPosterior post = engine.posterior(policy, model, tr);
  EXPECT_NEAR(post.log_likelihood, ref.log_likelihood, 1e-12 * std::abs(ref.log_likelihood));
  EXPECT_NEAR(post.marginals.row(0).sum(), 1.0, 1e-12);
  expect_marginals(ref, post, 0);
}

TEST(ExactEngine, ImpossibleObservationsGiveMinusInfinity) {
  Rng rng(1);
  testing::TinyProblem p = testing::tiny_problem(1, rng);
  p.model.subject.col(0).setZero();
  p.model.subject.col(1).setOnes();  // symbol 0 can only come from... nobody
  p.model.confounders.col(0).setZero();
  p.trajectory = ObservedTrajectory{};
  p.trajectory.symbols = {0};
  p.trajectory.eta = RowMatrix::Constant(1, 1 + p.model.num_confounders(), 1.0 / (1 + p.model.num_confounders()));
  p.trajectory.step_begin = {0, 1};
  ExactEngine engine(p.mdp);
  EXPECT_EQ(engine.posterior(p.policy, p.model, p.trajectory).log_likelihood, -INFINITY);
  EStepStatistics stats = EStepStatistics::zero(p.mdp.num_pairs(), p.model.num_confounders(), p.model.num_symbols());
  engine.accumulate(p.policy, p.model, p.trajectory, stats);
  EXPECT_EQ(stats.impossible, 1);
  EXPECT_EQ(stats.counts.sum(), 0.0);
}

}  // namespace
}  // namespace hbirl
