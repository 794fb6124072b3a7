#include "sim_driver/gridworld/observations.hpp"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace hbirl
