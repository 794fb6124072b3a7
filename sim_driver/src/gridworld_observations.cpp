#include "sim_driver/gridworld_observations.hpp"

#include <cmath>
#include <cstdlib>

namespace hbirl {

Eigen::MatrixXd gridworld_subject_observation_model(int size, double decay) {
  const int S = size * size;
  Eigen::MatrixXd o(S * 4, 4);
  for (int s = 0; s < S; ++s) {
    Eigen::Vector4d row;
    for (int k = 0; k < 4; ++k) {
      const int corner = gridworld_corner_state(size, k);
      const int distance = std::abs(s / size - corner / size) + std::abs(s % size - corner % size);
      row[k] = std::exp(-decay * distance);
    }
    row /= row.sum();
    for (int a = 0; a < 4; ++a) o.row(s * 4 + a) = row.transpose();
  }
  return o;
}

Eigen::MatrixXd random_confounder_observation_model(int confounders, Rng& rng) {
  Eigen::MatrixXd o(confounders, 4);
  for (int e = 0; e < confounders; ++e) {
    // Dirichlet(1, 1, 1, 1): normalised exponentials.
    for (int k = 0; k < 4; ++k) o(e, k) = -std::log(1.0 - rng.uniform());
    o.row(e) /= o.row(e).sum();
  }
  return o;
}

GridworldObservations observe_gridworld(const Mdp& mdp, const std::vector<Trajectory>& trajectories,
                                        const Eigen::MatrixXd& subject_o, const Eigen::MatrixXd& confounder_o,
                                        const GridworldObservationOptions& options, Rng& rng) {
  const int E = static_cast<int>(confounder_o.rows());
  const int sources = 1 + E;
  const int columns = options.eta == EtaKind::kSubject ? 1 : sources;
  GridworldObservations out;
  for (const Trajectory& trajectory : trajectories) {
    ObservedTrajectory observed;
    std::vector<int> truth;
    const int total = static_cast<int>(trajectory.size()) * options.per_step;
    observed.eta.resize(total, columns);
    observed.symbols.reserve(static_cast<size_t>(total));
    int row = 0;
    for (const StateAction& step : trajectory) {
      for (int i = 0; i < options.per_step; ++i, ++row) {
        const int z = rng.uniform_int(sources);
        const auto distribution = z == 0 ? Eigen::VectorXd(subject_o.row(mdp.pair(step.state, step.action)).transpose())
                                         : Eigen::VectorXd(confounder_o.row(z - 1).transpose());
        observed.symbols.push_back(rng.categorical(distribution));
        truth.push_back(z);
        switch (options.eta) {
          case EtaKind::kSubject:
            observed.eta(row, 0) = 1.0;
            break;
          case EtaKind::kUniform:
            observed.eta.row(row).setConstant(1.0 / sources);
            break;
          case EtaKind::kPlausible: {
            if (E == 0) {
              observed.eta(row, 0) = 1.0;
              break;
            }
            const int favoured = rng.uniform() < 0.8 ? z : rng.uniform_int(sources);
            observed.eta.row(row).setConstant(0.4 / E);
            observed.eta(row, favoured) = 0.6;
            break;
          }
        }
      }
      observed.step_begin.push_back(row);
    }
    out.trajectories.push_back(std::move(observed));
    out.true_sources.push_back(std::move(truth));
  }
  return out;
}

Eigen::MatrixXd controlled_run_alpha(const Mdp& mdp, const std::vector<Trajectory>& trajectories,
                                     const Eigen::MatrixXd& subject_o, int per_step, double pseudo_count, Rng& rng) {
  Eigen::MatrixXd alpha = Eigen::MatrixXd::Constant(mdp.num_pairs(), subject_o.cols(), pseudo_count);
  for (const Trajectory& trajectory : trajectories) {
    for (const StateAction& step : trajectory) {
      const int r = mdp.pair(step.state, step.action);
      for (int i = 0; i < per_step; ++i) alpha(r, rng.categorical(subject_o.row(r).transpose())) += 1.0;
    }
  }
  return alpha;
}

}  // namespace hbirl
