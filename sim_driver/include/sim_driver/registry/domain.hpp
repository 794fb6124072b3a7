#pragma once
// A domain: everything hbirl knows about one task, in one place (docs/your-task.md "Your own
// task"). The services, the dashboard, the CLI and the experiments look a domain up in
// the registry below and never test its name.
//
// The registry knows the built-in kinds; this header knows none of them. They live
// beside this folder: onion/ (paper §Experiments B, simulated by a camera), gridworld/
// (§Experiments A, any size, simulated by its own sensor) and file/ (any domain file,
// problem/domain_file.hpp, simulated by the sensor its "sensor" section describes).
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "learner/controlled_prior.hpp"
#include "learner/mdp.hpp"
#include "learner/observations.hpp"
#include "learner/trajectory.hpp"
#include "perception/camera_view.hpp"
#include "sim_driver/registry/domain_options.hpp"

namespace cv {
class Mat;
}

namespace hbirl {

// The names the dashboard, reports and results label things with.
struct DomainNames {
  std::vector<std::string> states, actions, features, symbols, sources;
  std::vector<std::string> contexts;  // of learned eta, when the domain's sensor gives them (its labeller's rules)
};

// How a simulator runs (sim_driver/registry/simulation_options.hpp): each domain's
// simulator reads the options that concern it.
struct SimulationOptions;

// A simulated run, planned up front so any frame can be produced again, identical: the
// controlled run's episodes first (true steps known, the subject alone), then the
// demonstrations. A camera's frames are images for perception and the labeller; a
// sensor's frames (one per step) are observations with their eta.
class Simulation {
 public:
  struct Episode {
    bool controlled = false;
    double start_time = 0.0;  // sim seconds
    Trajectory steps;
    bool ends_in_terminal = false;
    bool has_truth = true;  // its true steps are known (GROUND_TRUTH is published)
  };
  virtual ~Simulation() = default;

  std::vector<Episode> episodes;
  int frames_per_step = 1;
  double step_seconds = 1.0;
  Eigen::VectorXd true_weights;
  int num_symbols = 0;  // a sensor's
  int num_sources = 1;  // a sensor's: the subject and its confounding elements
  // A sensor's end sensor's alphabet (0: none); its reports and any terminal state known to
  // have been entered are the observed trajectories' end_symbols and end_state, published
  // with each episode's end marker.
  int num_end_symbols = 0;

  virtual bool camera() const = 0;
  // A camera's frame k of step t of episode `id`; returns its sim time.
  virtual double render(int id, int t, int k, cv::Mat& frame) const;
  // A sensor's observations of episode `id` (one frame per step).
  virtual const ObservedTrajectory& observed(int id) const;
};

class Domain {
 public:
  virtual ~Domain() = default;
  // The name EPISODE markers carry; the registry opens a built-in domain by it.
  virtual const std::string& name() const = 0;
  virtual const Mdp& mdp() const = 0;
  // The observation symbols, when the domain fixes them (0: whatever the sensor sends).
  virtual int num_symbols() const = 0;
  // Names of states, actions, features, symbols and `num_sources` sources (the subject,
  // then the confounding elements).
  virtual DomainNames names(int num_sources) const = 0;
  virtual std::optional<Eigen::VectorXd> true_weights() const { return std::nullopt; }
  // The observation model the domain states (a domain file's "observation_model": its
  // priors and how they are learned), if any; learning starts from it.
  virtual std::optional<ObservationPrior> stated_prior() const { return std::nullopt; }
  // What its camera shows (the labeller's reference sizes), when its simulator is a
  // camera (frames for perception and the labeller), not a sensor.
  virtual std::optional<perception::CameraView> camera() const { return std::nullopt; }
  bool has_camera() const { return camera().has_value(); }
  // The subject's Dirichlet prior (paper §Experiments): from a controlled run's observations and true steps.
  // Throws InputError when there is none and the domain states no prior of its own, or for
  // steps or symbols outside the domain.
  virtual Eigen::MatrixXd subject_prior(const std::vector<Trajectory>& truth,
                                        const std::vector<ObservedTrajectory>& observed, int num_symbols) const;
  // A simulated run; throws InputError("domain", ...) for a domain without a simulator.
  virtual std::unique_ptr<Simulation> simulate(const SimulationOptions& options) const = 0;

 protected:
  virtual ControlledPriorOptions controlled_prior_options() const { return {}; }
};

// A domain by spec: "onion"; "gridworld" (options.gridworld_size cells a side) or
// "gridworld:N"; otherwise the path of a domain file. Throws InputError naming the field
// ("domain", or the file and its field). File warnings go to *warnings.
std::unique_ptr<Domain> open_domain(const std::string& spec, const DomainOptions& options = {},
                                    std::vector<std::string>* warnings = nullptr);
// A built-in domain by the name its EPISODE markers carry -- never a file, since the name
// came off the bus; nullptr when there is none by that name.
std::unique_ptr<Domain> builtin_domain(const std::string& name);
// A domain described by a file's contents (what open_domain does with a path).
std::unique_ptr<Domain> file_domain(const std::string& path, std::vector<std::string>* warnings = nullptr);

}  // namespace hbirl
