#pragma once
// The paper's Gridworld (paper §Experiments A) as a problem file's contents: what
// `hbirl generate gridworld` writes and `hbirl.gridworld()` returns in Python, from one
// seed, so both give the same problem bit for bit.
#include <cstdint>

#include "problem/problem_file.hpp"
#include "sim_driver/gridworld/observations.hpp"

namespace hbirl {

struct GridworldProblemOptions {
  int size = 5;
  int trajectories = 20;
  int length = 10;
  int goal = -1;  // corner 0-3; -1: drawn from the seed
  double goal_weight = 1.0;
  double intended = 0.9;
  double discount = 0.95;
  std::uint64_t seed = 1;
  // Watched through the paper's sensor: observations labelled by a labeller of stated mass
  // and true accuracy (its pick is each observation's context), and a controlled run for
  // the subject prior. -1: the true steps only.
  int confounders = -1;
  int per_step = 40;
  Labeller labeller;
  int controlled = 20;
};

// Throws InputError naming the option when one is out of range.
Problem gridworld_problem(const GridworldProblemOptions& options);

}  // namespace hbirl
