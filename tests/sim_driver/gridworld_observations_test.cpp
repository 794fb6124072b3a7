#include "sim_driver/gridworld/observations.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <utility>

namespace hbirl {
namespace {

TEST(GridworldObservations, SubjectModelFavoursTheNearestCorner) {
  const Eigen::MatrixXd o = gridworld_subject_observation_model(5, 1.0);
  ASSERT_EQ(o.rows(), 100);
  for (int r = 0; r < o.rows(); ++r) EXPECT_NEAR(o.row(r).sum(), 1.0, 1e-12);
  for (int k = 0; k < 4; ++k) {
    Eigen::Index best = 0;
    o.row(gridworld_corner_state(5, k) * 4).maxCoeff(&best);
    EXPECT_EQ(best, k);
  }
  // exp(-distance): at the top-left corner, symbol 1 (top-right, distance 4) vs symbol 3
  // (bottom-right, distance 8) differ by e^4.
  EXPECT_NEAR(o(0, 1) / o(0, 3), std::exp(4.0), 1e-9);
}

// Far from every corner each exp(-decay * distance) underflows to a subnormal, rounded to a
// few bits, or to 0 (on a 1000x1000 grid at decay 1; here a 149x149 grid at decay 5, whose
// centre is 148 cells from every corner: exp(-740) is 80 times the smallest subnormal, and a
// 10x10 grid at decay 100, exp(-800) = 0). Every row is the model's distribution,
// exp(-decay * (d_k - d_nearest)) normalised; and a row whose nearest weight is a normal
// number has exactly the bits of exp(-decay * d_k) normalised, as before (what keeps every
// committed result's numbers).
TEST(GridworldObservations, SubjectModelFarFromEveryCornerIsStillTheModel) {
  for (const auto& [size, decay] : {std::pair{10, 1.0}, std::pair{149, 5.0}, std::pair{10, 100.0}}) {
    const Eigen::MatrixXd o = gridworld_subject_observation_model(size, decay);
    int shifted = 0;
    for (int s = 0; s < size * size; ++s) {
      Eigen::Vector4d d;
      for (int k = 0; k < 4; ++k) {
        const int c = gridworld_corner_state(size, k);
        d[k] = std::abs(s / size - c / size) + std::abs(s % size - c % size);
      }
      Eigen::Vector4d plain;
      for (int k = 0; k < 4; ++k) plain[k] = std::exp(-decay * d[k]);
      for (int a = 0; a < 4; ++a) {
        const Eigen::RowVectorXd row = o.row(s * 4 + a);
        if (plain.maxCoeff() >= std::numeric_limits<double>::min()) {
          ASSERT_EQ(row, (plain / plain.sum()).transpose()) << "decay " << decay << ", state " << s;
          continue;
        }
        ++shifted;
        Eigen::Vector4d exact;
        for (int k = 0; k < 4; ++k) exact[k] = std::exp(-decay * (d[k] - d.minCoeff()));
        exact /= exact.sum();
        for (int k = 0; k < 4; ++k) ASSERT_NEAR(row[k], exact[k], 1e-15) << "decay " << decay << ", state " << s;
      }
    }
    // Shifted where the centre is far enough, never at decay 1 on a 10x10 grid.
    if (decay == 1.0) {
      EXPECT_EQ(shifted, 0);
    } else {
      EXPECT_GT(shifted, 0) << "decay " << decay;
    }
  }
}

TEST(GridworldObservations, EtaKinds) {
  Rng rng(3);
  const GridworldTask task = make_gridworld_task({}, 30, 10, rng);
  const Eigen::MatrixXd subject = gridworld_subject_observation_model(5, 1.0);
  const Eigen::MatrixXd elements = random_confounder_observation_model(4, rng);
  GridworldObservationOptions options;
  options.confounders = 4;
  options.per_step = 20;
  options.eta = EtaKind::kPlausible;
  GridworldObservations obs = observe_gridworld(task.mdp, task.trajectories, subject, elements, options, rng);
  ASSERT_EQ(obs.trajectories.size(), 30u);
  long long favoured_true = 0;
  long long total = 0;
  for (size_t i = 0; i < obs.trajectories.size(); ++i) {
    const ObservedTrajectory& t = obs.trajectories[i];
    EXPECT_EQ(t.length(), 10);
    EXPECT_EQ(t.num_observations(), 200);
    for (int n = 0; n < t.num_observations(); ++n) {
      EXPECT_NEAR(t.eta.row(n).sum(), 1.0, 1e-12);
      Eigen::Index favoured = 0;
      EXPECT_DOUBLE_EQ(t.eta.row(n).maxCoeff(&favoured), 0.6);
      favoured_true += favoured == obs.true_sources[i][static_cast<size_t>(n)];
      ++total;
    }
  }
  // The true source is favoured with probability 0.8 + 0.2 / 5 = 0.84; 6000 draws put
  // 4 standard errors at +-0.019.
  EXPECT_NEAR(static_cast<double>(favoured_true) / static_cast<double>(total), 0.84, 0.019);
  assign_eta(obs, 5, EtaKind::kUniform, rng);
  EXPECT_DOUBLE_EQ(obs.trajectories[0].eta(7, 3), 0.2);
  assign_eta(obs, 5, EtaKind::kSubject, rng);
  EXPECT_EQ(obs.trajectories[0].eta.cols(), 1);
  EXPECT_DOUBLE_EQ(obs.trajectories[0].eta(7, 0), 1.0);
}

// calibrated_eta is what a plausible eta says of the true source: against the frequencies of
// assign_eta's own draws, sources drawn from an uneven mixture (each favoured source's
// column of true sources, 20000 observations, binomial bounds at 5 standard errors).
TEST(GridworldObservations, CalibratedEtaIsTheTrueSourcesFrequencyGivenTheStatedEta) {
  Rng rng(11);
  const int sources = 3;
  Eigen::RowVectorXd mixture(sources);
  mixture << 0.5, 0.3, 0.2;
  GridworldObservations obs;
  ObservedTrajectory t;
  std::vector<int> truth;
  for (int n = 0; n < 20000; ++n) {
    t.symbols.push_back(0);
    truth.push_back(rng.categorical(mixture.transpose()));
  }
  t.step_begin = {0, static_cast<int>(t.symbols.size())};
  obs.trajectories.push_back(t);
  obs.true_sources.push_back(truth);
  assign_eta(obs, sources, EtaKind::kPlausible, rng);
  Eigen::MatrixXd counts = Eigen::MatrixXd::Zero(sources, sources);  // favoured x true
  for (int n = 0; n < static_cast<int>(truth.size()); ++n) {
    Eigen::Index favoured = 0;
    obs.trajectories[0].eta.row(n).maxCoeff(&favoured);
    counts(favoured, truth[static_cast<size_t>(n)]) += 1.0;
  }
  for (int j = 0; j < sources; ++j) {
    Eigen::RowVectorXd stated = Eigen::RowVectorXd::Constant(sources, 0.2);
    stated[j] = 0.6;
    const Eigen::RowVectorXd p = calibrated_eta(stated, mixture, EtaKind::kPlausible);
    const double total = counts.row(j).sum();
    for (int z = 0; z < sources; ++z) {
      EXPECT_NEAR(counts(j, z) / total, p[z], 5 * std::sqrt(p[z] * (1 - p[z]) / total)) << j << " " << z;
    }
  }
  EXPECT_EQ(calibrated_eta(Eigen::RowVectorXd::Constant(sources, 1.0 / 3), mixture, EtaKind::kUniform), mixture);
}

}  // namespace
}  // namespace hbirl
