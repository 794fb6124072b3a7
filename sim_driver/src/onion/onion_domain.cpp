// The onion sorter (paper §Experiments B) as a domain: its MDP and names, and a run
// simulated by the scene's camera.
#include <opencv2/core.hpp>

#include "registry/builtin_domains.hpp"
#include "sim_driver/registry/simulation_options.hpp"
#include "learner/input_error.hpp"
#include "perception/labeller.hpp"
#include "sim_driver/onion/onion.hpp"

namespace hbirl {

namespace {

// Sorts planned as hbirl experiment onion plans them: the controlled run in the
// controlled scene (seed + 1), then the demonstrations in the chosen scene (seed).
class OnionSimulation final : public Simulation {
 public:
  OnionSimulation(const Mdp& mdp, const SimulationOptions& o) {
    onion::SceneConfig controlled_scene = onion::SceneConfig::controlled();
    controlled_scene.width = o.scene.width;
    controlled_scene.fps = o.scene.fps;
    controlled_scene.step_seconds = o.scene.step_seconds;
    onion::DemonstrationOptions controlled_sorts;
    controlled_sorts.sorts = o.controlled_sorts;
    sorts_ = onion::plan_sorts(mdp, controlled_scene, controlled_sorts, o.seed + 1);
    controlled_ = static_cast<int>(sorts_.size());
    double end = 0.0;
    for (const auto& e : sorts_) end += static_cast<double>(e.steps.size()) * controlled_scene.step_seconds;
    onion::DemonstrationOptions demo_sorts;
    demo_sorts.sorts = o.sorts;
    demo_sorts.start_time = end;
    for (auto& e : onion::plan_sorts(mdp, o.scene, demo_sorts, o.seed)) sorts_.push_back(std::move(e));
    controlled_camera_ = std::make_unique<onion::OnionScene>(controlled_scene, o.seed + 1);
    camera_ = std::make_unique<onion::OnionScene>(o.scene, o.seed);
    frames_per_step = o.scene.frames_per_step();
    step_seconds = o.scene.step_seconds;
    true_weights = onion::expert_weights();
    num_symbols = perception::kNumSymbols;
    for (int id = 0; id < static_cast<int>(sorts_.size()); ++id) {
      const onion::Episode& e = sorts_[static_cast<size_t>(id)];
      episodes.push_back({id < controlled_, e.start_time, e.steps, true});  // a sort ends with the release
    }
  }

  bool camera() const override { return true; }

  double render(int id, int t, int k, cv::Mat& frame) const override {
    const onion::Episode& e = sorts_[static_cast<size_t>(id)];
    const onion::OnionScene& scene = id < controlled_ ? *controlled_camera_ : *camera_;
    scene.render(e, t, k, frame);
    return scene.time_of(e, t, k);
  }

 private:
  std::vector<onion::Episode> sorts_;
  int controlled_ = 0;
  std::unique_ptr<onion::OnionScene> controlled_camera_, camera_;
};

class OnionDomain final : public Domain {
 public:
  const std::string& name() const override { return name_; }
  const Mdp& mdp() const override { return mdp_; }
  int num_symbols() const override { return perception::kNumSymbols; }
  std::optional<Eigen::VectorXd> true_weights() const override { return onion::expert_weights(); }
  std::optional<perception::CameraView> camera() const override { return onion::camera_view(); }

  // Symbols: "R2C3" is the gripper seen in the field of view's region row 2, column 3
  // (of 4 x 5); then "bright onion", "dark onion" (perception/labeller.hpp).
  DomainNames names(int num_sources) const override {
    DomainNames n;
    n.states = onion::state_names();
    n.actions = onion::action_names();
    n.features = onion::feature_names();
    for (int r = 0; r < perception::kRegionRows; ++r) {
      for (int c = 0; c < perception::kRegionColumns; ++c)
        n.symbols.push_back("R" + std::to_string(r + 1) + "C" + std::to_string(c + 1));
    }
    n.symbols.push_back("bright onion");
    n.symbols.push_back("dark onion");
    n.sources = {"subject (expert)", "blue-shirt person", "other onions", "foreground person"};
    n.sources.resize(static_cast<size_t>(std::max(num_sources, 1)));
    for (int e = 4; e < num_sources; ++e) n.sources[static_cast<size_t>(e)] = "element " + std::to_string(e);
    // The labeller's rules (perception/labeller.hpp): the gripper rule per size ratio, then the onion rules.
    for (int k = 0; k < perception::kGripperRatioRules; ++k)
      n.contexts.push_back("gripper, size ratio " + std::to_string(5 * (k + 1)) + "%");
    n.contexts.push_back("onion near the gripper");
    n.contexts.push_back("large onion");
    n.contexts.push_back("small onion");
    return n;
  }

  std::unique_ptr<Simulation> simulate(const SimulationOptions& options) const override {
    return std::make_unique<OnionSimulation>(mdp_, options);
  }

 protected:
  ControlledPriorOptions controlled_prior_options() const override { return onion::controlled_prior_options(); }

 private:
  std::string name_ = "onion";
  Mdp mdp_ = onion::make_onion_mdp();
};

}  // namespace

std::unique_ptr<Domain> make_onion_domain() { return std::make_unique<OnionDomain>(); }

}  // namespace hbirl
