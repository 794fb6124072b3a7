// What knowing what it knows costs (docs/BENCHMARKS.md "The posterior and the live
// estimates"): hbirl learn with and without the posterior's confidence on random tasks and
// on the onion demo's data, and the live optimiser's update after one more demonstration.
#include <benchmark/benchmark.h>

#include "app/learn.hpp"
#include "experiments/onion_data.hpp"
#include "services/dataset.hpp"
#include "services/learning.hpp"
#include "sim_driver/file/random_task.hpp"
#include "sim_driver/registry/domain.hpp"

namespace hbirl {
namespace {

// hbirl learn on random task `seed` (draw 0), from its observations, one thread, with
// `samples` posterior draws (0: none) -- the CLI's defaults otherwise.
void BM_LearnRandomTask(benchmark::State& state) {
  const RandomTask task = make_random_task(static_cast<std::uint64_t>(state.range(0)), 0);
  app::LearnSettings settings;
  settings.em.threads = 1;
  settings.posterior.samples = static_cast<int>(state.range(1));
  for (auto _ : state) {
    benchmark::DoNotOptimize(app::learn(task.mdp, task.observed.trajectories, task.prior, settings).em.theta);
  }
}
BENCHMARK(BM_LearnRandomTask)
    ->ArgsProduct({{1001, 1002, 1003, 1004, 1005, 1006, 1007, 1008, 1009}, {0, kConfidenceDraws}})
    ->ArgNames({"seed", "samples"})
    ->Unit(benchmark::kMillisecond);

// The onion demo's data set as services/launch.sh makes it (6 sorts, 20 controlled sorts,
// 15 frames a simulated second, seed 1), rendered, perceived and labelled in one process.
const services::Dataset& onion_demo() {
  static const services::Dataset data = [] {
    const std::shared_ptr<const Domain> onion = builtin_domain("onion");
    const Mdp& mdp = onion->mdp();
    onion::SceneConfig controlled = onion::SceneConfig::controlled();
    onion::DemonstrationOptions controlled_sorts;
    controlled_sorts.sorts = 20;
    controlled_sorts.rule_contexts = true;
    const onion::OnionDemonstration c = onion::demonstrate(mdp, controlled, controlled_sorts, 2);
    double end = 0.0;
    for (const auto& t : c.truth) end += static_cast<double>(t.size()) * onion::SceneConfig{}.step_seconds;
    onion::DemonstrationOptions sorts;
    sorts.sorts = 6;
    sorts.start_time = end;
    sorts.rule_contexts = true;
    const onion::OnionDemonstration d = onion::demonstrate(mdp, onion::SceneConfig{}, sorts, 1);
    services::Dataset out;
    out.domain = "onion";
    out.num_symbols = onion->num_symbols();
    out.num_sources = static_cast<int>(d.observed.front().eta.cols());  // the labeller's sources
    for (size_t i = 0; i < d.observed.size(); ++i) out.episodes.push_back(static_cast<int>(c.observed.size() + i));
    out.observed = d.observed;
    out.truth = d.truth;
    out.controlled_observed = c.observed;
    out.controlled_truth = c.truth;
    return out;
  }();
  return data;
}

// The onion demo's data learned as hbirl-optimiser learns it here (services::learn_from_dataset),
// with `samples` posterior draws.
void BM_LearnOnionDemo(benchmark::State& state) {
  const services::Dataset& data = onion_demo();
  app::LearnSettings settings;
  settings.em.threads = 1;
  settings.posterior.samples = static_cast<int>(state.range(0));
  for (auto _ : state) {
    benchmark::DoNotOptimize(services::learn_from_dataset(*builtin_domain("onion"), data, settings).theta);
  }
}
BENCHMARK(BM_LearnOnionDemo)->Arg(0)->Arg(kConfidenceDraws)->ArgName("samples")->Unit(benchmark::kMillisecond);

// The live optimiser's update after demonstration n of the onion demo (hbirl-optimiser
// --anytime under launch.sh: kLiveConfidenceDraws posterior draws, EM also from estimate
// n-1, the two EM starts on `threads` threads); with 0 draws what EM alone costs of it, with
// kConfidenceDraws what the calibration experiment's draws would.
void BM_LiveUpdateOnionDemo(benchmark::State& state) {
  const auto n = static_cast<size_t>(state.range(0));
  const std::shared_ptr<const Domain> onion = builtin_domain("onion");
  app::LearnSettings settings;
  settings.em.threads = static_cast<int>(state.range(1));
  settings.posterior.samples = static_cast<int>(state.range(2));
  if (n > 1) {
    settings.em.warm_start =
        services::learn_from_dataset(*onion, services::first_demonstrations(onion_demo(), n - 1), settings).theta;
  }
  const services::Dataset upto = services::first_demonstrations(onion_demo(), n);
  for (auto _ : state) benchmark::DoNotOptimize(services::learn_from_dataset(*onion, upto, settings).theta);
}
BENCHMARK(BM_LiveUpdateOnionDemo)
    ->ArgsProduct({{2, 4, 6}, {1, 2}, {0, kLiveConfidenceDraws, kConfidenceDraws}})
    ->ArgNames({"n", "threads", "samples"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace hbirl
