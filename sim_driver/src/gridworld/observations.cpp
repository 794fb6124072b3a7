#include "sim_driver/gridworld/observations.hpp"

#include <cmath>
#include <cstdlib>
#include <limits>

#include "learner/controlled_prior.hpp"

namespace hbirl {

Eigen::MatrixXd gridworld_subject_observation_model(int size, double decay) {
  const int S = size * size;
  Eigen::MatrixXd o(S * 4, 4);
  for (int s = 0; s < S; ++s) {
    Eigen::Vector4d distance;
    for (int k = 0; k < 4; ++k) {
      const int corner = gridworld_corner_state(size, k);
      distance[k] = std::abs(s / size - corner / size) + std::abs(s % size - corner % size);
    }
    // std::exp per weight, as before (a vectorised exp may round differently).
    const auto weights = [&](double nearest) {
      Eigen::Vector4d w;
      for (int k = 0; k < 4; ++k) w[k] = std::exp(-decay * (distance[k] - nearest));
      return w;
    };
    Eigen::Vector4d row = weights(0.0);
    // Far from every corner (decay x distance above ~708: at decay 1, grids over ~700 cells
    // a side) even the nearest corner's weight is subnormal, rounded to a few bits, or 0:
    // measure the distances from the nearest corner instead, the same row once normalised.
    // Only there, so that every other row keeps its bits (and every committed result its
    // numbers).
    if (row.maxCoeff() < std::numeric_limits<double>::min()) row = weights(distance.minCoeff());
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
  const int sources = 1 + static_cast<int>(confounder_o.rows());
  GridworldObservations out;
  for (const Trajectory& trajectory : trajectories) {
    ObservedTrajectory observed;
    std::vector<int> truth;
    observed.symbols.reserve(trajectory.size() * static_cast<size_t>(options.per_step));
    for (const StateAction& step : trajectory) {
      const bool occluded = options.occlusion > 0.0 && rng.uniform() < options.occlusion;
      for (int i = 0; i < (occluded ? 0 : options.per_step); ++i) {
        const int z = rng.uniform_int(sources);
        observed.symbols.push_back(z == 0
                                       ? rng.categorical(subject_o.row(mdp.pair(step.state, step.action)).transpose())
                                       : rng.categorical(confounder_o.row(z - 1).transpose()));
        truth.push_back(z);
      }
      observed.step_begin.push_back(static_cast<int>(observed.symbols.size()));
    }
    out.trajectories.push_back(std::move(observed));
    out.true_sources.push_back(std::move(truth));
  }
  Rng eta_rng = rng.split(0xE7A);
  assign_eta(out, sources, options.eta, eta_rng);
  return out;
}

namespace {
// assign_eta's plausible rule: the true source is favoured with this probability (else a
// source drawn evenly is), and the favoured source gets this much of eta.
constexpr double kPlausibleAccuracy = 0.8;
constexpr double kPlausibleMass = 0.6;
}  // namespace

void assign_eta(GridworldObservations& observations, int sources, EtaKind kind, Rng& rng) {
  const int E = sources - 1;
  for (size_t i = 0; i < observations.trajectories.size(); ++i) {
    ObservedTrajectory& observed = observations.trajectories[i];
    const std::vector<int>& truth = observations.true_sources[i];
    const int n = observed.num_observations();
    observed.eta.resize(n, kind == EtaKind::kSubject ? 1 : sources);
    for (int row = 0; row < n; ++row) {
      switch (kind) {
        case EtaKind::kSubject:
          observed.eta(row, 0) = 1.0;
          break;
        case EtaKind::kTrue:
          observed.eta.row(row).setZero();
          observed.eta(row, truth[static_cast<size_t>(row)]) = 1.0;
          break;
        case EtaKind::kUniform:
          observed.eta.row(row).setConstant(1.0 / sources);
          break;
        case EtaKind::kPlausible: {
          if (E == 0) {
            observed.eta(row, 0) = 1.0;
            break;
          }
          const int favoured =
              rng.uniform() < kPlausibleAccuracy ? truth[static_cast<size_t>(row)] : rng.uniform_int(sources);
          observed.eta.row(row).setConstant((1.0 - kPlausibleMass) / E);
          observed.eta(row, favoured) = kPlausibleMass;
          break;
        }
      }
    }
  }
}

Eigen::RowVectorXd calibrated_eta(const Eigen::RowVectorXd& stated, const Eigen::RowVectorXd& mixture, EtaKind kind) {
  switch (kind) {
    case EtaKind::kTrue:
    case EtaKind::kSubject:
      return stated;
    case EtaKind::kUniform:
      return mixture;
    case EtaKind::kPlausible: {
      const Eigen::Index sources = stated.size();
      if (sources == 1) return stated;
      Eigen::Index favoured = 0;
      stated.maxCoeff(&favoured);
      // Pr(favoured | z) = accuracy [favoured = z] + (1 - accuracy) / sources.
      Eigen::RowVectorXd p = mixture * ((1.0 - kPlausibleAccuracy) / static_cast<double>(sources));
      p[favoured] += mixture[favoured] * kPlausibleAccuracy;
      return p / p.sum();
    }
  }
  return stated;
}

namespace {

// `mass` on `pick`, the rest evenly over the other sources.
Eigen::VectorXd eta_with_pick(double mass, int sources, int pick) {
  if (sources == 1) return Eigen::VectorXd::Ones(1);
  Eigen::VectorXd eta = Eigen::VectorXd::Constant(sources, (1.0 - mass) / (sources - 1));
  eta[pick] = mass;
  return eta;
}

}  // namespace

Eigen::VectorXd labeller_calibration(const Labeller& labeller, int sources, int pick) {
  return eta_with_pick(labeller.accuracy, sources, pick);
}

void assign_labeller_eta(GridworldObservations& observations, int sources, const Labeller& labeller, Rng& rng) {
  for (size_t i = 0; i < observations.trajectories.size(); ++i) {
    ObservedTrajectory& observed = observations.trajectories[i];
    const std::vector<int>& truth = observations.true_sources[i];
    const int n = observed.num_observations();
    observed.eta.resize(n, sources);
    observed.contexts.assign(static_cast<size_t>(n), 0);
    for (int row = 0; row < n; ++row) {
      const int source = truth[static_cast<size_t>(row)];
      int pick = source;
      if (sources > 1 && !(rng.uniform() < labeller.accuracy)) {
        pick = rng.uniform_int(sources - 1);  // one of the others, evenly
        if (pick >= source) ++pick;
      }
      observed.eta.row(row) = eta_with_pick(labeller.mass, sources, pick).transpose();
      observed.contexts[static_cast<size_t>(row)] = pick;
    }
  }
}

Eigen::MatrixXd controlled_run_alpha(const Mdp& mdp, const std::vector<Trajectory>& trajectories,
                                     const Eigen::MatrixXd& subject_o, int per_step, double pseudo_count, Rng& rng) {
  // The subject alone: every observation drawn from its O at the true (s, a).
  std::vector<ObservedTrajectory> observed(trajectories.size());
  for (size_t i = 0; i < trajectories.size(); ++i) {
    for (const StateAction& step : trajectories[i]) {
      const int r = mdp.pair(step.state, step.action);
      for (int k = 0; k < per_step; ++k) observed[i].symbols.push_back(rng.categorical(subject_o.row(r).transpose()));
      observed[i].step_begin.push_back(static_cast<int>(observed[i].symbols.size()));
    }
  }
  ControlledPriorOptions options;
  options.pseudo_count = pseudo_count;
  return controlled_run_prior(mdp, trajectories, observed, static_cast<int>(subject_o.cols()), options);
}

}  // namespace hbirl
