#pragma once
// The domain file (docs/your-task.md "Your own task"): a task as the service set runs it -- a
// problem file without a demonstration (the same "mdp" and "observation_model" keys),
// plus names for its symbols and sources, the expert's true weights and a "sensor"
// section that says how to simulate watching the expert. A problem file is also a
// domain file (its demonstration is not read here). Validated at the edge like problem
// files: a bad file raises InputError naming the field ("sensor.occlusion: ...").
#include <optional>
#include <string>
#include <vector>

#include "learner/mdp.hpp"
#include "learner/observation_model.hpp"

namespace hbirl {

// How the simulator watches the expert (the paper's Gridworld scheme, §Experiments A).
struct SensorSpec {
  Eigen::MatrixXd subject_o;         // (S*A) x symbols: the subject's true O (unlisted rows uniform)
  Eigen::MatrixXd confounder_o;      // E x symbols: each element's true O (unlisted rows uniform)
  int observations_per_step = 40;    // drawn equally from the subject and every element
  std::string eta = "plausible";     // "plausible", "uniform" or "true"
  double occlusion = 0.0;            // chance that a step has no observations
  int trajectories = 20;             // demonstrations
  int length = 10;                   // at most this many steps each (fewer when a terminal state is entered)
  int controlled_trajectories = 20;  // the controlled run: the subject alone, true steps known
  double step_seconds = 1.0;         // sim time per step (the messages' utime)
  // With an end sensor (observation_model.end_sensor): its true O_end, one row per state
  // (terminal rows as listed, else uniform), and the reports of each ending.
  Eigen::MatrixXd end_o;
  int end_reports = 1;
};

// Why `name` cannot name a domain on the bus (empty: it can): 1 to 64 letters, digits, '_',
// '-' and '.' (EPISODE markers carry it; a problem or domain file's "name").
std::string domain_name_problem(const std::string& name);
// A domain name for a file: its stem, kept to those characters (a file without "name").
std::string stem_name(const std::string& path);

struct DomainSpec {
  std::string name;  // "name", else the file's stem; what EPISODE markers carry
  Mdp mdp;
  std::vector<std::string> state_names, action_names, feature_names;  // empty when not given
  std::vector<std::string> symbol_names, source_names;                // empty when not given
  std::vector<std::string> context_names;  // the sensor's contexts (its labeller's rules); empty when not given
  std::optional<ObservationPrior> observation_model;
  std::optional<Eigen::VectorXd> true_weights;
  std::optional<SensorSpec> sensor;

  int num_symbols() const { return observation_model ? observation_model->num_symbols : 0; }
  int num_sources() const { return observation_model ? 1 + observation_model->num_confounders : 1; }
};

// Parse and validate; `default_name` is used when the document has no "name". Unknown
// keys add a line to *warnings (when not null).
DomainSpec parse_domain(const std::string& text, const std::string& default_name,
                        std::vector<std::string>* warnings = nullptr);
// Read a file (its stem is the default name); unreadable files are InputError("", ...).
DomainSpec read_domain_file(const std::string& path, std::vector<std::string>* warnings = nullptr);

}  // namespace hbirl
