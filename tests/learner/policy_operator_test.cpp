#include "learner/policy_operator.hpp"

#include <gtest/gtest.h>

#include <Eigen/IterativeLinearSolvers>
#include <cstring>
#include <vector>

#include "learner/policy_matrix.hpp"
#include "learner/rng.hpp"
#include "learner/random_mdp.hpp"
#include "sim_driver/gridworld/gridworld.hpp"

namespace hbirl {
namespace {

// (I - gamma P_pi) for a random policy: every (s, a) pair's probability drawn, so every
// entry of the pattern holds a different value.
SparseRowMatrix random_policy_matrix(const Mdp& mdp, Rng& rng) {
  PolicyMatrix m(mdp);
  Eigen::VectorXd policy(mdp.num_pairs());
  for (int s = 0; s < mdp.num_states; ++s) {
    double sum = 0.0;
    for (int a = 0; a < mdp.num_actions; ++a) sum += (policy[mdp.pair(s, a)] = 0.05 + rng.uniform());
    for (int a = 0; a < mdp.num_actions; ++a) policy[mdp.pair(s, a)] /= sum;
  }
  m.set_policy(policy);
  return m.matrix();
}

Eigen::VectorXd random_vector(int n, Rng& rng) {
  Eigen::VectorXd x(n);
  for (int i = 0; i < n; ++i) x[i] = rng.uniform(-1.0, 1.0);
  return x;
}

Mdp gridworld(int size) {
  Rng rng(7);
  GridworldOptions options;
  options.size = size;
  return make_gridworld_task(options, 1, 1, rng).mdp;
}

Eigen::VectorXd product(PolicyOperator& op, const SparseRowMatrix& m, const Eigen::VectorXd& x) {
  op.update_values(m);
  Eigen::VectorXd y(x.size());
  op.multiply(x.data(), y.data());
  return y;
}

bool same_bits(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
}

TEST(PolicyOperator, AGridIsStoredByDiagonalAndARandomMdpByRow) {
  Rng rng(1);
  const SparseRowMatrix grid = random_policy_matrix(gridworld(12), rng);
  EXPECT_TRUE(PolicyOperator(grid, false).by_diagonal());
  EXPECT_TRUE(PolicyOperator(grid, true).by_diagonal());
  EXPECT_FALSE(PolicyOperator(grid, false, PolicyOperator::Storage::kRows).by_diagonal());
  testing::RandomMdpOptions o;
  o.states = 60;
  o.successors = 4;
  const SparseRowMatrix random = random_policy_matrix(testing::random_mdp(o, rng), rng);
  EXPECT_FALSE(PolicyOperator(random, false).by_diagonal());
}

// The diagonal products sum each row as the row products do, so they agree bit for bit
// (both compiled as the library is; the row products are Eigen's loop, next test).
// Grids of 25 to 1,681 states (more than one block of rows, and a last block cut short),
// both the matrix and its transpose, terminal rows, and entries of the diagonals outside
// the pattern (a grid's edges).
TEST(PolicyOperator, ProductsByDiagonalAreTheRowProductsBitForBit) {
  Rng rng(2);
  for (int size : {5, 13, 23, 41}) {
    const Mdp mdp = gridworld(size);
    for (int trial = 0; trial < 3; ++trial) {
      const SparseRowMatrix m = random_policy_matrix(mdp, rng);
      for (bool transposed : {false, true}) {
        PolicyOperator diagonals(m, transposed);
        PolicyOperator rows(m, transposed, PolicyOperator::Storage::kRows);
        ASSERT_TRUE(diagonals.by_diagonal());
        const Eigen::VectorXd x = random_vector(mdp.num_states, rng);
        const Eigen::VectorXd expected = product(rows, m, x);
        EXPECT_TRUE(same_bits(product(diagonals, m, x), expected)) << "size " << size << " transposed " << transposed;
        // The row products are the matrix's: independent of how they are computed.
        const Eigen::VectorXd eigen = transposed ? Eigen::VectorXd(m.transpose() * x) : Eigen::VectorXd(m * x);
        EXPECT_LE((expected - eigen).lpNorm<Eigen::Infinity>(), 1e-14) << "size " << size;
      }
    }
  }
}

// On matrices with many diagonals (stored by row) the operator is the matrix, both ways,
// and follows its values when they change.
TEST(PolicyOperator, RowProductsAreTheMatrixsAndFollowItsValues) {
  Rng rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    const Mdp mdp = testing::random_mdp(testing::varied_options(trial), rng);
    SparseRowMatrix m = random_policy_matrix(mdp, rng);
    for (bool transposed : {false, true}) {
      PolicyOperator op(m, transposed);
      for (int change = 0; change < 2; ++change) {
        const Eigen::VectorXd x = random_vector(mdp.num_states, rng);
        const Eigen::VectorXd eigen = transposed ? Eigen::VectorXd(m.transpose() * x) : Eigen::VectorXd(m * x);
        EXPECT_LE((product(op, m, x) - eigen).lpNorm<Eigen::Infinity>(), 1e-14) << "trial " << trial;
        for (int j = 0; j < m.nonZeros(); ++j) m.valuePtr()[j] *= 0.5 + rng.uniform();
      }
    }
  }
}

// Through Eigen's expressions (BiCGSTAB's r = b - A x, v = A y; and +=, -=) the operator
// is the product it computes.
TEST(PolicyOperator, EigensExpressionsUseItsProduct) {
  Rng rng(4);
  const SparseRowMatrix m = random_policy_matrix(gridworld(9), rng);
  PolicyOperator op(m, false);
  op.update_values(m);
  const Eigen::VectorXd x = random_vector(static_cast<int>(m.rows()), rng);
  const Eigen::VectorXd b = random_vector(static_cast<int>(m.rows()), rng);
  Eigen::VectorXd y(m.rows());
  op.multiply(x.data(), y.data());
  Eigen::VectorXd v;
  v.noalias() = op * x;
  EXPECT_TRUE(same_bits(v, y));
  const Eigen::VectorXd r = b - op * x;
  EXPECT_TRUE(same_bits(r, Eigen::VectorXd(b - y)));
  Eigen::VectorXd sum = b;
  sum += op * x;
  EXPECT_TRUE(same_bits(sum, Eigen::VectorXd(b + y)));
  Eigen::VectorXd difference = b;
  difference -= op * x;
  EXPECT_TRUE(same_bits(difference, Eigen::VectorXd(b - y)));
  Eigen::VectorXd scaled = b;
  scaled += 2.0 * (op * x);
  EXPECT_TRUE(same_bits(scaled, Eigen::VectorXd(b + 2.0 * y)));
}

// Eigen's solver on Eigen's matrix: what PolicyMatrix computed before it had an operator.
// This file is compiled with the library's optimisation (tests/CMakeLists.txt), so that
// the compiler fuses a * b + c into one rounding here exactly where it does there.
Eigen::VectorXd eigens_solve(const SparseRowMatrix& m, const Eigen::VectorXd& b, const Eigen::VectorXd& guess,
                             double tolerance, int* iterations) {
  Eigen::BiCGSTAB<SparseRowMatrix, Eigen::DiagonalPreconditioner<double>> solver;
  solver.setTolerance(tolerance);
  solver.compute(m);
  Eigen::VectorXd x = solver.solveWithGuess(b, guess);
  *iterations = static_cast<int>(solver.iterations());
  return x;
}

// The products and the solves are Eigen's bit for bit: grids (by diagonal) and random
// MDPs (by row), both ways, from zero and from a guess, at a Newton step's loose
// tolerance and at working precision.
TEST(PolicyOperator, SolvesAreEigensBitForBit) {
  Rng rng(6);
  std::vector<Mdp> mdps{gridworld(5), gridworld(23), gridworld(41)};
  for (int trial = 0; trial < 12; ++trial) mdps.push_back(testing::random_mdp(testing::varied_options(trial), rng));
  for (const Mdp& mdp : mdps) {
    PolicyMatrix matrix(mdp);
    Eigen::VectorXd policy(mdp.num_pairs());
    for (int r = 0; r < mdp.num_pairs(); ++r) policy[r] = 0.05 + rng.uniform();
    for (int s = 0; s < mdp.num_states; ++s) {
      policy.segment(static_cast<Eigen::Index>(s) * mdp.num_actions, mdp.num_actions) /=
          policy.segment(static_cast<Eigen::Index>(s) * mdp.num_actions, mdp.num_actions).sum();
    }
    matrix.set_policy(policy);
    const SparseRowMatrix m = matrix.matrix();
    const SparseRowMatrix mt = m.transpose();
    const Eigen::VectorXd b = random_vector(mdp.num_states, rng);
    for (bool warm : {false, true}) {
      const Eigen::VectorXd guess = warm ? random_vector(mdp.num_states, rng) : Eigen::VectorXd::Zero(mdp.num_states);
      for (double tolerance : {1e-3, PolicyMatrix::kWorkingTolerance}) {
        int iterations = 0;
        const Eigen::VectorXd expected = eigens_solve(m, b, guess, tolerance, &iterations);
        Eigen::VectorXd x = guess;
        matrix.solve(b, x, tolerance);
        EXPECT_TRUE(same_bits(x, expected)) << mdp.num_states << " states, tolerance " << tolerance;
        EXPECT_EQ(matrix.last_iterations(), iterations);
      }
      int iterations = 0;
      const Eigen::VectorXd expected = eigens_solve(mt, b, guess, PolicyMatrix::kWorkingTolerance, &iterations);
      Eigen::VectorXd x = guess;
      matrix.solve_transposed(b, x);
      EXPECT_TRUE(same_bits(x, expected)) << mdp.num_states << " states, transposed";
      EXPECT_EQ(matrix.last_iterations(), iterations);
    }
  }
}

// Eigen adds a row's sum to a zeroed result, so a sum of -0 (here the product of two tiny
// numbers, rounded to zero) comes out +0; so does the operator's, both ways.
TEST(PolicyOperator, ASumOfMinusZeroIsPlusZeroAsInEigen) {
  SparseRowMatrix m(2, 2);
  const std::vector<Eigen::Triplet<double>> entries{{0, 0, 1.0}, {0, 1, 1e-200}, {1, 0, -1e-200}, {1, 1, 1.0}};
  m.setFromTriplets(entries.begin(), entries.end());
  m.makeCompressed();
  Eigen::VectorXd x(2);
  x << 0.0, -1e-200;
  Eigen::VectorXd y(2);
  y << 1e-200, 0.0;
  for (auto storage : {PolicyOperator::Storage::kChosen, PolicyOperator::Storage::kRows}) {
    PolicyOperator op(m, false, storage);
    op.update_values(m);
    const Eigen::VectorXd product = op * x;
    EXPECT_TRUE(same_bits(product, Eigen::VectorXd(m * x)));
    EXPECT_FALSE(std::signbit(product[0]));
    PolicyOperator transposed(m, true, storage);
    transposed.update_values(m);
    const Eigen::VectorXd product_t = transposed * y;
    EXPECT_TRUE(same_bits(product_t, Eigen::VectorXd(m.transpose() * y)));
    EXPECT_FALSE(std::signbit(product_t[0]));
  }
}

// PolicyMatrix's solves through the operator solve the system, on a grid (by diagonal)
// and on random MDPs (by row), both ways.
TEST(PolicyOperator, PolicyMatrixSolvesThroughIt) {
  Rng rng(5);
  std::vector<Mdp> mdps{gridworld(30)};
  for (int trial = 0; trial < 6; ++trial) {
    testing::RandomMdpOptions o = testing::varied_options(trial);
    if (o.discount == 0.0) o.discount = 0.9;
    mdps.push_back(testing::random_mdp(o, rng));
  }
  for (const Mdp& mdp : mdps) {
    PolicyMatrix matrix(mdp);
    Eigen::VectorXd policy = Eigen::VectorXd::Constant(mdp.num_pairs(), 1.0 / mdp.num_actions);
    matrix.set_policy(policy);
    const Eigen::VectorXd b = random_vector(mdp.num_states, rng);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(mdp.num_states);
    ASSERT_TRUE(matrix.solve(b, x));
    EXPECT_LE((matrix.matrix() * x - b).lpNorm<Eigen::Infinity>(), 1e-10);
    Eigen::VectorXd xt = Eigen::VectorXd::Zero(mdp.num_states);
    ASSERT_TRUE(matrix.solve_transposed(b, xt));
    EXPECT_LE((matrix.matrix().transpose() * xt - b).lpNorm<Eigen::Infinity>(), 1e-10);
  }
}

}  // namespace
}  // namespace hbirl
