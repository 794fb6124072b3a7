// Speed of the E-step engines (docs/BENCHMARKS.md has the figures and the command).
#include <benchmark/benchmark.h>
#include <malloc.h>
#include <sys/resource.h>
#include <unistd.h>

#include <fstream>

#include "learner/estep_mcmc.hpp"
#include "learner/estep_observations.hpp"
#include "sim_driver/gridworld/observations.hpp"

namespace hbirl {
namespace {

// The paper's Gridworld with 3 confounding elements and plausible eta.
struct Setup {
  GridworldTask task;
  GridworldObservations observations;
  ObservationPrior prior;
  SoftSolution policy;
};

Setup setup(int trajectories, int length, int per_step) {
  Rng rng(11);
  Setup s{make_gridworld_task({}, trajectories, length, rng), {}, {}, {}};
  const Eigen::MatrixXd subject = gridworld_subject_observation_model(5, 1.0);
  const Eigen::MatrixXd elements = random_confounder_observation_model(3, rng);
  GridworldObservationOptions options;
  options.per_step = per_step;
  s.observations = observe_gridworld(s.task.mdp, s.task.trajectories, subject, elements, options, rng);
  s.prior.num_symbols = 4;
  s.prior.num_confounders = 3;
  s.prior.subject_alpha = subject;
  s.prior.confounder_alpha = elements;
  s.policy = soft_value_iteration(s.task.mdp, s.task.mdp.reward(s.task.true_weights));
  return s;
}

// Largest total-variation distance, over the steps, between two sets of marginals.
double max_tv(const RowMatrix& a, const RowMatrix& b) { return 0.5 * (a - b).cwiseAbs().rowwise().sum().maxCoeff(); }

// One trajectory of 10 steps, range(0) observations per step: the exact posterior.
void BM_ExactPosterior(benchmark::State& state) {
  const Setup s = setup(1, 10, static_cast<int>(state.range(0)));
  const ObservationModel model = dirichlet_mean(s.prior);
  ExactEngine engine(s.task.mdp);
  for (auto _ : state)
    benchmark::DoNotOptimize(engine.posterior(s.policy, model, s.observations.trajectories[0]).log_likelihood);
}
BENCHMARK(BM_ExactPosterior)->Arg(4)->Arg(40)->Unit(benchmark::kMicrosecond);

// The same posterior by MCMC with range(0) sweeps, range(1) observations per step, and
// (range(2) = 1) the block move added to the single-site updates; counter tv = max over
// steps of TV(MCMC, exact), worst over the timed repetitions.
void BM_McmcPosterior(benchmark::State& state) {
  const Setup s = setup(1, 10, static_cast<int>(state.range(1)));
  const ObservationModel model = dirichlet_mean(s.prior);
  ExactEngine exact(s.task.mdp);
  const TrajectoryPosterior truth = exact.posterior(s.policy, model, s.observations.trajectories[0]);
  McmcOptions options;
  options.samples = static_cast<int>(state.range(0));
  options.burn_in = options.samples / 10;
  options.block = state.range(2) == 1 ? McmcOptions::Block::kAlways : McmcOptions::Block::kAuto;
  McmcEngine engine(s.task.mdp, options);
  double tv = 0.0;
  std::uint64_t seed = 1;
  for (auto _ : state) {
    Rng rng(seed++);
    const TrajectoryPosterior post = engine.posterior(s.policy, model, s.observations.trajectories[0], rng);
    state.PauseTiming();
    tv = std::max(tv, max_tv(post.marginals, truth.marginals));
    state.ResumeTiming();
  }
  state.counters["tv"] = tv;  // worst over the timed repetitions
}
BENCHMARK(BM_McmcPosterior)
    ->ArgsProduct({{10000, 100000, 400000}, {4, 40}, {0, 1}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

// One E-step pass (every trajectory, exact engine) as the data grow along one axis.
void estep_pass(benchmark::State& state, int trajectories, int length, int per_step) {
  const Setup s = setup(trajectories, length, per_step);
  const ObservationEStep estep(s.task.mdp, s.observations.trajectories, s.prior);
  const ObservationModel model = dirichlet_mean(s.prior);
  for (auto _ : state) benchmark::DoNotOptimize(estep.statistics(s.policy, model, 1).log_likelihood);
  state.counters["observations"] = static_cast<double>(trajectories) * length * per_step;
  state.counters["obs_per_s"] = benchmark::Counter(static_cast<double>(trajectories) * length * per_step,
                                                   benchmark::Counter::kIsIterationInvariantRate);
}

void BM_EStepObservationsPerStep(benchmark::State& state) {
  estep_pass(state, 1, 10, static_cast<int>(state.range(0)));
}
BENCHMARK(BM_EStepObservationsPerStep)->Arg(1)->Arg(10)->Arg(100)->Arg(1000)->Unit(benchmark::kMicrosecond);

void BM_EStepLength(benchmark::State& state) { estep_pass(state, 1, static_cast<int>(state.range(0)), 40); }
BENCHMARK(BM_EStepLength)->Arg(10)->Arg(100)->Arg(1000)->Unit(benchmark::kMicrosecond);

void BM_EStepTrajectories(benchmark::State& state) { estep_pass(state, static_cast<int>(state.range(0)), 10, 40); }
BENCHMARK(BM_EStepTrajectories)->Arg(1)->Arg(10)->Arg(100)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond);

// This process's resident memory now, in bytes (what malloc keeps free given back first).
double resident_bytes() {
  malloc_trim(0);
  std::ifstream statm("/proc/self/statm");
  long pages = 0, resident = 0;
  statm >> pages >> resident;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE));
}

// range(0) trajectories x 10 steps x 40 observations: one exact pass, and the memory the
// data take as generated (data_B_per_obs: the observations with their eta), as the E-step
// holds them (estep_B_per_obs: merged identical observations, their kinds), and at the
// peak. Run it alone (--benchmark_filter), so that no other benchmark's memory counts.
void BM_EStepManyTrajectories(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const double before = resident_bytes();
  const Setup s = setup(n, 10, 40);
  const double generated = resident_bytes();
  const ObservationEStep estep(s.task.mdp, s.observations.trajectories, s.prior);
  const double held = resident_bytes();
  const ObservationModel model = dirichlet_mean(s.prior);
  for (auto _ : state) benchmark::DoNotOptimize(estep.statistics(s.policy, model, 1).log_likelihood);
  double observations = 0.0, rows = 0.0;
  for (const auto& t : s.observations.trajectories) observations += t.num_observations();
  for (const auto& t : estep.trajectories()) rows += t.num_observations();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  state.counters["observations"] = observations;
  state.counters["merged_rows"] = rows;
  state.counters["data_B_per_obs"] = (generated - before) / observations;
  state.counters["estep_B_per_obs"] = (held - generated) / observations;
  state.counters["peak_MB"] = static_cast<double>(usage.ru_maxrss) / 1024.0;
  state.counters["obs_per_s"] = benchmark::Counter(observations, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_EStepManyTrajectories)->Arg(10000)->Arg(100000)->Iterations(1)->Unit(benchmark::kSecond);

// The observation model's refinement on the paper's Gridworld data (20 trajectories x 10
// steps x 40 observations, plausible eta), range(0) = 0: one E-step refinement with the
// stated eta (one pass), 1: the same with learned eta (one pass with each context's eta),
// 2: choosing the subject prior's strength by held-out likelihood (one pass for the
// counts, then a forward pass per trajectory and grid point). EM pays 0 or 1 every
// iteration and 2 once per convergence.
void BM_ObservationModelRefinement(benchmark::State& state) {
  Setup s = setup(20, 10, 40);
  s.prior.subject_alpha = 1.0 + 40.0 * s.prior.subject_alpha.array();  // a prior with counts
  s.prior.confounder_alpha = Eigen::MatrixXd::Ones(3, 4);
  s.prior.learn_eta = state.range(0) != 0;
  ObservationEStepOptions options;
  options.max_alpha_iterations = 1;
  const ObservationEStep estep(s.task.mdp, s.observations.trajectories, s.prior, options);
  const EStepState start = estep.initial_state(1);
  for (auto _ : state) {
    EStepState work = start;
    if (state.range(0) == 2) {
      benchmark::DoNotOptimize(estep.choose_strength(s.policy, work)->best_strength);
    } else {
      benchmark::DoNotOptimize(estep.expect(s.policy, work).objective);
    }
  }
}
BENCHMARK(BM_ObservationModelRefinement)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace hbirl
