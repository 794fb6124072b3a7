"""The Python binding's cost (docs/BENCHMARKS.md "Python"): the same two measurements as
learner_bench's BM_MaxCausalEntSolve/1/0 and BM_Gradient/45/30, called from Python.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_bench.py

Prints the median of `--repeats` timed calls (after a warm-up) of:
  fit:      hbirl.MaxCausalEntIRL(threads=1).fit on the 5x5 Gridworld, 20 trajectories x 10 steps
  gradient: hbirl.causal_log_likelihood on the 45x45 Gridworld (|S| = 2025), 20 x 30 steps
"""
import argparse
import statistics
import time

import hbirl


def median_seconds(call, repeats):
    call()  # warm-up: first-touch allocations, caches
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=50)
    args = parser.parse_args()
    small = hbirl.gridworld(size=5, trajectories=20, length=10, seed=1)
    small_truth = small.truth_trajectories()
    large = hbirl.gridworld(size=45, trajectories=20, length=30, seed=1)
    large_truth = large.truth_trajectories()
    theta = [0.1, -0.2, 0.3, 0.05]
    fit = median_seconds(lambda: hbirl.MaxCausalEntIRL(threads=1).fit(small.mdp, small_truth), args.repeats)
    gradient = median_seconds(lambda: hbirl.causal_log_likelihood(large.mdp, large_truth, theta), args.repeats)
    print(f"fit 5x5, 20 trajectories:       {fit * 1e3:8.3f} ms (median of {args.repeats})")
    print(f"gradient |S| = 2025, 20 x 30:   {gradient * 1e3:8.3f} ms (median of {args.repeats})")


if __name__ == "__main__":
    main()
