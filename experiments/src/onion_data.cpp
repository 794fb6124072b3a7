#include "experiments/onion_data.hpp"

#include "learner/rng.hpp"
#include "sim_driver/onion.hpp"

namespace hbirl::onion {

perception::LabellerOptions labeller_options(const SceneConfig& config, bool uniform_eta) {
  perception::LabellerOptions o;
  o.width = config.width;
  o.height = config.height();
  const GripperSize g = gripper_size(config);
  o.gripper_area = static_cast<double>(g.width) * g.height;
  o.onion_area = onion_area(config);
  o.uniform_eta = uniform_eta;
  return o;
}

std::vector<Episode> plan_sorts(const Mdp& mdp, const SceneConfig& config, const DemonstrationOptions& options,
                                std::uint64_t seed) {
  const Eigen::VectorXd weights = expert_weights();
  Rng rng(seed, 11);
  std::vector<Episode> sorts;
  double time = options.start_time;
  const bool first_blemished = rng.uniform() < 0.5;
  for (int i = 0; i < options.sorts; ++i) {
    const bool blemished = options.alternate_quality ? first_blemished != (i % 2 == 1) : rng.uniform() < options.blemished;
    const Trajectory steps = expert_sort(mdp, weights, rng.uniform_int(3), blemished);
    sorts.push_back(make_episode(steps, blemished, time, rng.next_u64()));
    time += static_cast<double>(steps.size()) * config.step_seconds;
  }
  return sorts;
}

OnionDemonstration demonstrate(const Mdp& mdp, const SceneConfig& config, const DemonstrationOptions& options,
                               std::uint64_t seed) {
  const OnionScene scene(config, seed);
  perception::BlobDetector detector;
  const perception::LabellerOptions labels = labeller_options(config, options.uniform_eta);
  OnionDemonstration out;
  cv::Mat frame;
  std::vector<double> eta;
  for (const Episode& episode : plan_sorts(mdp, config, options, seed)) {
    const Trajectory& steps = episode.steps;
    ObservedTrajectory observed;
    observed.ends_in_terminal = true;  // every sort ends with a release into a terminal state
    eta.clear();
    for (int t = 0; t < static_cast<int>(steps.size()); ++t) {
      for (int k = 0; k < config.frames_per_step(); ++k) {
        scene.render(episode, t, k, frame);
        ++out.frames;
        for (const perception::Observation& o : perception::label(detector.detect(frame), labels)) {
          observed.symbols.push_back(o.symbol);
          eta.insert(eta.end(), o.eta.begin(), o.eta.end());
        }
      }
      observed.step_begin.push_back(static_cast<int>(observed.symbols.size()));
    }
    observed.eta = Eigen::Map<const RowMatrix>(eta.data(), static_cast<Eigen::Index>(observed.symbols.size()),
                                               perception::kNumSources);
    out.truth.push_back(steps);
    out.blemished.push_back(episode.blemished);
    out.observed.push_back(std::move(observed));
  }
  return out;
}

Eigen::MatrixXd controlled_prior(const Mdp& mdp, const OnionDemonstration& controlled, double pseudo_count) {
  Eigen::MatrixXd counts = Eigen::MatrixXd::Zero(mdp.num_pairs(), perception::kNumSymbols);
  Eigen::VectorXd visits = Eigen::VectorXd::Zero(mdp.num_pairs());
  for (size_t i = 0; i < controlled.truth.size(); ++i) {
    const ObservedTrajectory& o = controlled.observed[i];
    for (int t = 0; t < o.length(); ++t) {
      const StateAction& x = controlled.truth[i][static_cast<size_t>(t)];
      const int r = mdp.pair(x.state, x.action);
      visits[r] += 1.0;
      for (int n = o.step_begin[static_cast<size_t>(t)]; n < o.step_begin[static_cast<size_t>(t) + 1]; ++n) {
        counts(r, o.symbols[static_cast<size_t>(n)]) += o.weight(n);
      }
    }
  }
  for (int r = 0; r < mdp.num_pairs(); ++r) {
    if (visits[r] > 0.0) counts.row(r) /= visits[r];
  }
  return counts.array() + pseudo_count;
}

}  // namespace hbirl::onion
