#include "experiments/onion_data.hpp"

#include "learner/rng.hpp"
#include "sim_driver/onion/onion.hpp"

namespace hbirl::onion {

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
          if (options.rule_contexts) observed.contexts.push_back(o.rule);
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

}  // namespace hbirl::onion
