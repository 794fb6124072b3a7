#include "app/learn.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <set>

#include "learner/input_error.hpp"
#include "learner/observation_support.hpp"
#include "sim_driver/file/random_task.hpp"

namespace hbirl::app {
namespace {

bool same_bits(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

RandomTask small_task(std::uint64_t seed) {
  RandomTaskOverrides overrides;
  overrides.demonstrations = 5;
  return make_random_task(seed, 0, overrides);
}

// Independent of app::learn: the learner's parts put together by hand, as the command line
// did before the application layer (prior overrides, catch-all, E-step, HiddenDataEM).
LearnResult by_hand(const RandomTask& task, std::optional<AlphaUpdate> update, int restarts) {
  ObservationPrior prior = task.prior;
  std::vector<ObservedTrajectory> observed = task.observed.trajectories;
  add_unlisted_source(prior, observed);
  if (update) use_alpha_update(prior, *update);
  ObservationEStepOptions estep_options;
  estep_options.threads = restarts == 1 ? 2 : 1;
  const ObservationEStep estep(task.mdp, observed, prior, estep_options);
  LearnOptions options;
  options.restarts = restarts;
  options.threads = 2;
  options.seed = 5;
  return learn_reward(task.mdp, estep, options);
}

// learn() is the learner's parts and nothing else: the same theta, bit for bit, as putting
// them together by hand, with the settings' overrides applied, on random tasks.
TEST(Learn, IsTheLearnersPartsBitForBit) {
  for (std::uint64_t seed : {3u, 8u}) {
    const RandomTask task = small_task(seed);
    for (const auto& [update, restarts] :
         {std::pair<std::optional<AlphaUpdate>, int>{std::nullopt, 1}, {AlphaUpdate::kPaper, 2}}) {
      LearnSettings settings;
      settings.alpha_update = update;
      settings.em.restarts = restarts;
      settings.em.threads = 2;
      settings.em.seed = 5;
      const Learned learned = learn(task.mdp, task.observed.trajectories, task.prior, settings);
      const LearnResult expected = by_hand(task, update, restarts);
      EXPECT_TRUE(same_bits(learned.em.theta, expected.theta)) << "task " << seed << ", restarts " << restarts;
      EXPECT_EQ(learned.em.log_likelihood, expected.log_likelihood);
      EXPECT_EQ(learned.given.update, update.value_or(task.prior.update));
      ASSERT_NE(learned.observed, nullptr);
      EXPECT_EQ(learned.model.subject.rows(), task.mdp.num_pairs());
    }
  }
}

// Every iterate reaches the hook, with the E-step it came from; the count is EM's.
TEST(Learn, ReportsEveryIterate) {
  const RandomTask task = small_task(4);
  int calls = 0;
  LearnHooks hooks;
  hooks.on_iteration = [&calls](const Iterate& i) {
    ++calls;
    EXPECT_EQ(i.iteration, calls);
    EXPECT_NE(i.observed, nullptr);
  };
  LearnSettings settings;
  settings.em.threads = 1;
  const Learned learned = learn(task.mdp, task.observed.trajectories, task.prior, settings, hooks);
  EXPECT_EQ(calls, learned.best().em_iterations);
}

// The posterior is drawn only when asked, around EM's theta, and needs the exact engine;
// its summary has a probability for a confidence and an interval that holds its mean.
TEST(Learn, DrawsThePosteriorWhenAsked) {
  const RandomTask task = small_task(6);
  LearnSettings settings;
  settings.em.threads = 1;
  EXPECT_FALSE(learn(task.mdp, task.observed.trajectories, task.prior, settings).posterior);
  settings.posterior.samples = 40;
  const Learned learned = learn(task.mdp, task.observed.trajectories, task.prior, settings);
  ASSERT_TRUE(learned.posterior && learned.confidence);
  EXPECT_EQ(learned.posterior->samples.rows(), 40);
  const nlohmann::ordered_json j = posterior_summary(learned);
  EXPECT_GE(j["confidence"].get<double>(), 0.0);
  EXPECT_LE(j["confidence"].get<double>(), 1.0);
  EXPECT_GE(j["confidence"].get<double>(), j["probability_optimal"].get<double>());
  for (size_t k = 0; k < j["mean"].size(); ++k) {
    EXPECT_LE(j["interval_90"][k][0].get<double>(), j["interval_90"][k][1].get<double>());
  }
  // O learned: the confidence is the even mixture of the posterior with O as learned and
  // the one with O held at the prior -- the latter what learning with O fixed draws, asked
  // of this learned policy.
  ASSERT_TRUE(learned.given.learn && learned.confidence_learned_o && learned.confidence_prior_o);
  LearnSettings held = settings;
  held.learn_observation_model = false;
  const Learned at_prior = learn(task.mdp, task.observed.trajectories, task.prior, held);
  EXPECT_FALSE(at_prior.confidence_prior_o);  // nothing to average when O is not learned
  const PolicyConfidence expected = policy_confidence(task.mdp, *at_prior.posterior, learned.em.theta);
  EXPECT_EQ(learned.confidence_prior_o->near_optimal, expected.near_optimal);
  EXPECT_DOUBLE_EQ(learned.confidence->near_optimal,
                   0.5 * (learned.confidence_learned_o->near_optimal + expected.near_optimal));
  EXPECT_EQ(j["confidence_by_sensor_model"]["prior"].get<double>(), expected.near_optimal);
  settings.engine = "mcmc";
  settings.mcmc.samples = 20;
  settings.mcmc.burn_in = 5;
  settings.em.max_em_iterations = 2;
  EXPECT_THROW(learn(task.mdp, task.observed.trajectories, task.prior, settings), InputError);
}

// Learning while it watches: estimate n is learn() on the first n demonstrations started
// also from estimate n - 1 (bit for bit: any point of the sequence can be reproduced alone),
// and never worse by EM's selection score than a start from scratch on the same n -- from
// observations and from true trajectories (where the score is the log-likelihood).
TEST(LearnAnytime, EachEstimateIsLearnOnThePrefixFromThePreviousAndNoWorseThanFresh) {
  // One task of 3 demonstrations: each estimate is learned three times from observations
  // (two tasks of 5 took most of a minute of CI).
  for (std::uint64_t seed : {4u}) {
    RandomTaskOverrides three;
    three.demonstrations = 3;
    const RandomTask task = make_random_task(seed, 0, three);
    LearnSettings settings;
    settings.em.threads = 2;
    std::vector<Eigen::VectorXd> estimates;
    int warm_wins = 0;
    const auto check = [&](int n, const Learned& got, const std::function<Learned(const LearnSettings&)>& again) {
      ASSERT_EQ(n, static_cast<int>(estimates.size()) + 1);
      LearnSettings from_previous = settings;
      if (n > 1) from_previous.em.warm_start = estimates.back();
      EXPECT_TRUE(same_bits(again(from_previous).em.theta, got.em.theta)) << "task " << seed << ", n " << n;
      const Learned fresh = again(settings);
      EXPECT_GE(got.best().score, fresh.best().score) << "task " << seed << ", n " << n;
      if (got.em.theta != fresh.em.theta) ++warm_wins;
      estimates.push_back(got.em.theta);
    };
    const std::vector<ObservedTrajectory>& observed = task.observed.trajectories;
    learn_anytime(task.mdp, observed, task.prior, settings, {}, [&](int n, const Learned& got) {
      const std::vector<ObservedTrajectory> first(observed.begin(), observed.begin() + n);
      check(n, got, [&](const LearnSettings& s) { return learn(task.mdp, first, task.prior, s); });
    });
    EXPECT_EQ(estimates.size(), observed.size());
    estimates.clear();
    learn_from_truth_anytime(task.mdp, task.demonstrations, settings, {}, [&](int n, const Learned& got) {
      const std::vector<Trajectory> first(task.demonstrations.begin(), task.demonstrations.begin() + n);
      check(n, got, [&](const LearnSettings& s) { return learn_from_truth(task.mdp, first, s); });
      // Concave: both starts reach the one optimum, to the M-step's tolerance.
      const double fresh = learn_from_truth(task.mdp, first, settings).em.log_likelihood;
      EXPECT_GE(got.em.log_likelihood, fresh - 1e-9 * std::abs(fresh));
    });
    EXPECT_EQ(estimates.size(), task.demonstrations.size());
    RecordProperty("warm_start_changed_estimates_task_" + std::to_string(seed), warm_wins);
  }
}

// A warm start of the wrong length is named.
TEST(LearnAnytime, AWarmStartOfTheWrongLengthIsNamed) {
  const RandomTask task = small_task(4);
  LearnSettings settings;
  settings.em.warm_start = Eigen::VectorXd::Zero(task.mdp.num_features() + 1);
  try {
    (void)learn_from_truth(task.mdp, task.demonstrations, settings);
    FAIL() << "learned from a warm start of the wrong length";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "warm_start");
  }
}

// An observation no source can make is named as the front end names its data.
TEST(Learn, AnImpossibleObservationIsNamedByTheFrontEnd) {
  const RandomTask task = small_task(5);
  ObservationPrior prior = task.prior;
  prior.subject_alpha.setZero();     // the subject makes nothing,
  prior.confounder_alpha.setZero();  // nor does any confounding element
  LearnHooks hooks;
  hooks.trajectory_name = [](int i) { return "demonstration[" + std::to_string(10 + i) + "]"; };
  try {
    (void)learn(task.mdp, task.observed.trajectories, prior, LearnSettings{}, hooks);
    FAIL() << "learned from impossible observations";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field().rfind("demonstration[10].steps[", 0), 0u) << e.what();
  }
}

// The schema: every setting named once, settable to its own default, and refused out of
// its range with its name.
TEST(LearnSettingsSchema, EverySettingOnceAndChecked) {
  std::set<std::string> names, flags;
  const LearnSettings defaults;
  for (const Setting& s : learn_settings_schema()) {
    EXPECT_TRUE(names.insert(s.name).second) << s.name;
    EXPECT_TRUE(flags.insert(s.flag).second) << s.flag;
    LearnSettings settings;
    set(settings, s, s.get(defaults));  // its own default is in range
    EXPECT_EQ(to_json(settings), to_json(defaults)) << s.name;
    if (s.type == Setting::Type::kInteger || s.type == Setting::Type::kNumber) {
      const nlohmann::json below = s.type == Setting::Type::kInteger
                                       ? nlohmann::json(static_cast<std::int64_t>(s.min) - 1)
                                       : nlohmann::json(static_cast<double>(s.min) - 1.0);
      try {
        set(settings, s, below);
        ADD_FAILURE() << s.name << " took " << below;
      } catch (const InputError& e) {
        EXPECT_EQ(e.field(), s.name);
      }
    }
    if (!s.optional) {
      EXPECT_THROW(set(settings, s, nullptr), InputError) << s.name;
    }
  }
  EXPECT_THROW(learn_setting("max_em_iteration"), InputError);
}

// The defaults are the learner's own (each number is written once, in the learner).
TEST(LearnSettingsSchema, DefaultsAreTheLearners) {
  const nlohmann::ordered_json d = to_json(LearnSettings{});
  EXPECT_EQ(d["max_em_iterations"], LearnOptions{}.max_em_iterations);
  EXPECT_EQ(d["tolerance"], OptimizerOptions{}.gradient_tolerance);
  EXPECT_EQ(d["alpha_tolerance"], ObservationEStepOptions{}.alpha_tolerance);
  EXPECT_EQ(d["mcmc_samples"], McmcOptions{}.samples);
  EXPECT_EQ(d["mcmc_chains"], 4);
  EXPECT_TRUE(d["eta"].is_null());
}

TEST(LearnSettingsSchema, TextAndJsonRoundTrip) {
  LearnSettings settings;
  set_all(settings, {{"max_em_iterations", 7},
                     {"eta", "stated"},
                     {"alpha_update", "paper"},
                     {"c", 0.25},
                     {"seed", 18446744073709551615ull}});
  EXPECT_EQ(settings.em.max_em_iterations, 7);
  EXPECT_EQ(settings.learn_eta, false);
  EXPECT_EQ(settings.alpha_update, AlphaUpdate::kPaper);
  EXPECT_EQ(settings.c, 0.25);
  EXPECT_EQ(settings.em.seed, 18446744073709551615ull);
  LearnSettings again;
  set_all(again, to_json(settings));
  EXPECT_EQ(to_json(again), to_json(settings));
  const Setting& restarts = learn_setting("restarts");
  EXPECT_EQ(value_of_text(restarts, "12"), 12);
  EXPECT_THROW(value_of_text(restarts, "12.5"), InputError);
  EXPECT_THROW(check(restarts, value_of_text(restarts, "0")), InputError);
  EXPECT_THROW(check(learn_setting("tolerance"), value_of_text(learn_setting("tolerance"), "nan")), InputError);
  EXPECT_THROW(set_all(settings, {{"engine", "gibbs"}}), InputError);
}

}  // namespace
}  // namespace hbirl::app
