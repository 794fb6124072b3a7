#pragma once
// How hbirl learns: every setting of HiddenDataEM, its M-step, its E-step and the
// observation model, declared once. The command line (`hbirl learn`), the Python estimators
// and the optimiser service make their options from learn_settings_schema() -- the name,
// the default (the learner's own option structs hold each number once), the range and the
// help -- so a new setting is one entry here and its use in the learner.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "learner/estep_mcmc.hpp"
#include "learner/estep_observations.hpp"
#include "learner/hidden_data_em.hpp"
#include "learner/observation_model.hpp"
#include "learner/reward_posterior.hpp"

namespace hbirl::app {

struct LearnSettings {
  // HiddenDataEM and its MaxCausalEnt M-step (learner/hidden_data_em.hpp's defaults).
  // `em.accelerate` follows the engine: it is not a setting.
  LearnOptions em;
  // The E-step: its engine and when the observation model has converged.
  std::string engine = "exact";  // or "mcmc"
  McmcOptions mcmc = four_chains();
  double alpha_tolerance = ObservationEStepOptions{}.alpha_tolerance;
  int max_alpha_iterations = ObservationEStepOptions{}.max_alpha_iterations;
  // What overrides the prior's own choices (unset: as the problem file or the domain says).
  std::optional<bool> learn_observation_model;
  std::optional<AlphaUpdate> alpha_update;
  std::optional<double> c;        // the paper's step size (alpha_update paper)
  std::optional<bool> learn_eta;  // eta "learned" per context or "stated"
  // The posterior over theta drawn after EM (learner/reward_posterior.hpp): none unless
  // posterior.samples > 0.
  RewardPosteriorOptions posterior;

  // R-hat compares chains: four unless told (Vehtari et al. 2021 run 4 by default).
  static McmcOptions four_chains() {
    McmcOptions o;
    o.chains = 4;
    return o;
  }
};

// The prior as these settings have it: learn_observation_model, alpha_update, c and eta
// override what the prior says.
void apply_to_prior(const LearnSettings& settings, ObservationPrior& prior);

// One setting as every front end offers it.
struct Setting {
  enum class Type { kInteger, kNumber, kChoice, kSwitch };
  // The posterior engine; HiddenDataEM and its M-step; what overrides the prior.
  enum class Group { kEngine, kEm, kPrior };
  std::string name;  // the Python keyword; the key in a settings object
  std::string flag;  // on the command line
  std::string help;
  Type type = Type::kNumber;
  Group group = Group::kEm;
  // kInteger and kNumber: the inclusive range; `above_min`: min itself is not allowed.
  long double min = 0, max = 0;
  bool above_min = false;
  std::vector<std::string> choices;  // kChoice
  // Unset (null) is allowed and means "as the prior says"; `unset_help` says what that is.
  // The kPrior group's settings are these.
  bool optional = false;
  std::string unset_help;
  bool hidden_data = false;  // only when learning from observations (not from true trajectories)
  bool optimiser = true;     // hbirl-optimiser takes it
  std::function<nlohmann::json(const LearnSettings&)> get;
  std::function<void(LearnSettings&, const nlohmann::json&)> put;  // a value check() accepted
};

const std::vector<Setting>& learn_settings_schema();
const Setting& learn_setting(const std::string& name);  // InputError when there is no such setting

// Throws InputError naming the setting when `value` is not of its type or range.
void check(const Setting& setting, const nlohmann::json& value);
// check, then set.
void set(LearnSettings& settings, const Setting& setting, const nlohmann::json& value);
// Every key of `object` set by its name (InputError for an unknown name).
void set_all(LearnSettings& settings, const nlohmann::json& object);
// The value a command-line word gives (InputError when it is not of the setting's type).
nlohmann::json value_of_text(const Setting& setting, const std::string& text);
// Every setting's value, by name (unset: null).
nlohmann::ordered_json to_json(const LearnSettings& settings);
// The range or choices, as help shows them ("in [1, 100000]", "lbfgs or eg").
std::string describe_range(const Setting& setting);

}  // namespace hbirl::app
