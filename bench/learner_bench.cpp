// Speed of the learner core (docs/BENCHMARKS.md has the figures and the command).
#include <benchmark/benchmark.h>

#include <cmath>

#include "learner/hidden_data_em.hpp"
#include "learner/maxcausalent.hpp"
#include "learner/metrics.hpp"
#include "learner/value_iteration.hpp"
#include "sim_driver/gridworld/gridworld.hpp"

namespace hbirl {
namespace {

GridworldTask task(int size, int trajectories, int length) {
  Rng rng(1);
  GridworldOptions options;
  options.size = size;
  return make_gridworld_task(options, trajectories, length, rng);
}

// Weights away from the truth, as an optimiser would meet them.
Eigen::VectorXd probe_weights() { return Eigen::Vector4d(0.3, -0.2, 0.5, 0.1); }

void BM_SoftValueIteration(benchmark::State& state) {
  const GridworldTask t = task(static_cast<int>(state.range(0)), 1, 1);
  SoftViOptions options;
  options.method = state.range(1) == 0 ? SoftViMethod::kNewton : SoftViMethod::kFixedPoint;
  const Eigen::VectorXd reward = t.mdp.reward(probe_weights());
  SoftBellmanSolver solver(t.mdp, options);
  int backups = 0;
  for (auto _ : state) {
    solver.forget_warm_start();
    benchmark::DoNotOptimize(solver.solve(reward).value.data());
    backups = solver.solution().iterations;
  }
  state.counters["backups"] = backups;
  state.counters["states"] = t.mdp.num_states;
  state.SetLabel(options.method == SoftViMethod::kNewton ? "newton" : "fixed-point");
}
BENCHMARK(BM_SoftValueIteration)->ArgsProduct({{5, 45}, {0, 1}})->Unit(benchmark::kMicrosecond);

// One objective + gradient evaluation from a cold start: soft value iteration (the
// backward pass) and the adjoint solve (the forward pass), for 20 trajectories.
void BM_Gradient(benchmark::State& state) {
  const int size = static_cast<int>(state.range(0));
  const int length = static_cast<int>(state.range(1));
  const GridworldTask t = task(size, 20, length);
  CausalLikelihood objective(t.mdp, visit_counts(t.mdp, t.trajectories));
  const Eigen::VectorXd theta = probe_weights();
  Eigen::VectorXd gradient(4);
  for (auto _ : state) {
    objective.cold_start();
    benchmark::DoNotOptimize(objective.evaluate(theta, &gradient));
  }
  state.counters["states"] = t.mdp.num_states;
}
BENCHMARK(BM_Gradient)
    ->Args({5, 10})
    ->Args({5, 30})
    ->Args({10, 30})
    ->Args({20, 30})
    ->Args({45, 30})
    ->Args({100, 30})
    ->Args({200, 30})
    ->Unit(benchmark::kMicrosecond);

// One evaluation as an optimiser pays for it: warm, its soft Bellman solve and its adjoint
// solve started from the evaluation before, at weights that differ from those by a relative
// step of 10^-k (k = range(1)); evaluations alternate between the two points.
void BM_GradientWarm(benchmark::State& state) {
  const int size = static_cast<int>(state.range(0));
  const GridworldTask t = task(size, 20, 30);
  CausalLikelihood objective(t.mdp, visit_counts(t.mdp, t.trajectories));
  const Eigen::VectorXd theta = probe_weights();
  const Eigen::VectorXd step = std::pow(10.0, -static_cast<double>(state.range(1))) * theta.norm() *
                               Eigen::Vector4d(1.0, 1.0, -1.0, 1.0).normalized();
  Eigen::VectorXd gradient(4);
  objective.evaluate(theta, &gradient);
  bool away = false;
  for (auto _ : state) {
    away = !away;
    benchmark::DoNotOptimize(objective.evaluate(away ? Eigen::VectorXd(theta + step) : theta, &gradient));
  }
  state.counters["states"] = t.mdp.num_states;
}
BENCHMARK(BM_GradientWarm)->ArgsProduct({{45, 200}, {1, 2, 3}})->Unit(benchmark::kMicrosecond);

// A full MaxCausalEnt solve on the 5x5 gridworld with 20 trajectories of 10 steps: the
// whole of `hbirl learn --from truth` but for reading the file (one thread).
void BM_MaxCausalEntSolve(benchmark::State& state) {
  const GridworldTask t = task(5, 20, 10);
  const TruthEStep estep(t.mdp, t.trajectories);
  LearnOptions options;
  options.restarts = static_cast<int>(state.range(0));
  options.optimizer.kind = state.range(1) == 0 ? OptimizerKind::kLbfgs : OptimizerKind::kExponentiatedGradient;
  options.threads = 1;
  int iterations = 0;
  for (auto _ : state) {
    const LearnResult result = learn_reward(t.mdp, estep, options);
    iterations = result.restarts[0].optimizer_iterations;
    benchmark::DoNotOptimize(result.theta.data());
  }
  state.counters["restarts"] = options.restarts;
  state.counters["iterations"] = iterations;
  state.SetLabel(to_string(options.optimizer.kind));
}
BENCHMARK(BM_MaxCausalEntSolve)->Args({1, 0})->Args({4, 0})->Args({1, 1})->Unit(benchmark::kMillisecond);

// How close the sparse operations run to this machine's memory bandwidth (issue 17, "Large
// MDPs"; issue 35): BM_StreamTriad is the bandwidth of a = b + s c (bytes counted as read b,
// c and write a) over 3 x 128 MB (memory) and over 3 x 2 MB (larger than the 1 MB L2, held
// in L3, as a 40,000-state gradient's matrices and vectors are), BM_TransitionProduct one
// product q = T v with the N x N Gridworld's transitions (bytes: the values, column
// indices and row starts read, q written; v is small enough to stay in cache at N = 200:
// 320 kB), the operation the soft Bellman backups and BiCGSTAB's products are made of.
void BM_StreamTriad(benchmark::State& state) {
  const Eigen::Index n = state.range(0);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, 0.0, 1.0);
  const Eigen::VectorXd c = Eigen::VectorXd::LinSpaced(n, 1.0, 2.0);
  Eigen::VectorXd a(n);
  for (auto _ : state) {
    a.noalias() = b + 0.5 * c;
    benchmark::DoNotOptimize(a.data());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * 3 * n * static_cast<int64_t>(sizeof(double)));
}
BENCHMARK(BM_StreamTriad)->Arg(16 * 1024 * 1024)->Arg(256 * 1024)->Unit(benchmark::kMicrosecond);

// One solve with PolicyMatrix (BiCGSTAB, diagonal preconditioner, to working precision
// from zero) for the N x N Gridworld's soft policy at the probe weights: the solves a
// gradient is made of. range(1) = 1: the transposed (adjoint) system. Bytes per iteration
// as docs/BENCHMARKS.md counts them: two products (PolicyOperator::bytes_per_product: its
// storage, the input and the output) and the vector passes of Eigen's BiCGSTAB iteration
// (30 reads and writes of S doubles: its dots, norms, updates and the preconditioner's
// two applications).
void BM_PolicySolve(benchmark::State& state) {
  const GridworldTask t = task(static_cast<int>(state.range(0)), 1, 1);
  const bool transposed = state.range(1) == 1;
  SoftBellmanSolver soft(t.mdp, SoftViOptions{});
  const Eigen::VectorXd policy = soft.solve(t.mdp.reward(probe_weights())).policy;
  PolicyMatrix matrix(t.mdp);
  matrix.set_policy(policy);
  const int S = t.mdp.num_states;
  Eigen::VectorXd b = Eigen::VectorXd::Zero(S);
  for (int s = 0; s < S; ++s) b[s] = t.mdp.is_terminal(s) ? 0.0 : 1.0;
  Eigen::VectorXd x(S);
  for (auto _ : state) {
    x.setZero();
    const bool solved = transposed ? matrix.solve_transposed(b, x) : matrix.solve(b, x);
    if (!solved) state.SkipWithError("PolicyMatrix did not solve");
    benchmark::DoNotOptimize(x.data());
  }
  const int64_t per_iteration =
      2 * matrix.bytes_per_product(transposed) + 30 * S * static_cast<int64_t>(sizeof(double));
  state.counters["iterations"] = matrix.last_iterations();
  state.counters["MB_per_iteration"] = static_cast<double>(per_iteration) / 1e6;
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * matrix.last_iterations() * per_iteration);
  state.SetLabel(transposed ? "adjoint" : "policy evaluation");
}
BENCHMARK(BM_PolicySolve)->ArgsProduct({{200}, {0, 1}})->Unit(benchmark::kMillisecond);

void BM_TransitionProduct(benchmark::State& state) {
  const GridworldTask t = task(static_cast<int>(state.range(0)), 1, 1);
  const SparseRowMatrix& m = t.mdp.transitions;
  const Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(t.mdp.num_states, -1.0, 1.0);
  Eigen::VectorXd q(m.rows());
  for (auto _ : state) {
    q.noalias() = m * v;
    benchmark::DoNotOptimize(q.data());
  }
  const int64_t bytes = m.nonZeros() * static_cast<int64_t>(sizeof(double) + sizeof(int)) +
                        m.rows() * static_cast<int64_t>(sizeof(int) + sizeof(double));
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * bytes);
  state.counters["nonzeros"] = static_cast<double>(m.nonZeros());
}
BENCHMARK(BM_TransitionProduct)->Arg(200)->Unit(benchmark::kMicrosecond);

// The metrics of a learned reward on a large MDP (issue 17 "Large MDPs"): the ILE (value
// iteration for both rewards' optimal policies, then exact policy evaluation) and the
// policy agreement, as `hbirl learn` prints them (policy_metrics: one optimal policy per
// reward for both).
// Second argument 0: the two metrics each on its own, as before (four optimal policies).
void BM_Metrics(benchmark::State& state) {
  const GridworldTask t = task(static_cast<int>(state.range(0)), 1, 1);
  const Eigen::VectorXd learned = probe_weights();
  for (auto _ : state) {
    if (state.range(1) == 1) {
      benchmark::DoNotOptimize(policy_metrics(t.mdp, t.true_weights, learned).ile.ile);
    } else {
      benchmark::DoNotOptimize(inverse_learning_error(t.mdp, t.true_weights, learned).ile);
      benchmark::DoNotOptimize(policy_agreement(t.mdp, t.true_weights, learned));
    }
  }
  state.counters["states"] = t.mdp.num_states;
}
BENCHMARK(BM_Metrics)->ArgsProduct({{45, 100, 200}, {0, 1}})->ArgNames({"", "together"})->Unit(benchmark::kMillisecond);

// One optimal policy (value_iteration: value iteration, then policy iteration to an exact
// optimum) for the true reward: its sweeps and policy-iteration steps as counters. (A
// looser value iteration is no faster: at 200x200, stopping at 1e-3 instead of 1e-10 cut
// the sweeps 392 -> 78 but needed 96 policy steps instead of 6: 4.1 s instead of 0.9 s.)
void BM_ValueIteration(benchmark::State& state) {
  const GridworldTask t = task(static_cast<int>(state.range(0)), 1, 1);
  const Eigen::VectorXd reward = t.mdp.reward(t.true_weights);
  OptimalPolicy p;
  for (auto _ : state) p = value_iteration(t.mdp, reward);
  state.counters["sweeps"] = p.iterations;
  state.counters["policy_steps"] = p.policy_iterations;
}
BENCHMARK(BM_ValueIteration)->Arg(45)->Arg(100)->Arg(200)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace hbirl
