#pragma once
// Where each onion baseline breaks (docs/results.md "Beyond the paper"): the onion experiment
// (onion_experiment.hpp) at one number of sorts, across scenes -- the foreground person's
// share of the time in front of the expert (0: absent), with and without the mirror, and
// with the labeller's eta as stated or overconfident (raised to a power and renormalised).
// Our onion figure differs from the paper's for ML Observations and Uniform eta; this map
// says in which scene each baseline fails.
#include <functional>
#include <string>
#include <vector>

#include "experiments/onion_experiment.hpp"

namespace hbirl::onion {

struct OnionRegime {
  double foreground_share = 0.0;  // 0: no foreground person
  bool mirror = true;
  double eta_power = 1.0;  // 1: eta as the labeller states it
};

struct OnionRegimesOptions {
  OnionExperimentOptions base;  // runs, sorts (base.trajectories), methods, EM settings
  std::vector<double> shares = {0.0, 0.25, 0.5, 0.75, 0.9};
  std::vector<bool> mirrors = {true, false};
  std::vector<double> eta_powers = {1.0, 3.0};
  std::function<void(int done, int total)> progress;
};

struct OnionRegimeRun {
  OnionRegime regime;
  OnionRun run;
};

std::vector<OnionRegime> onion_regimes(const OnionRegimesOptions& options);
std::vector<OnionRegimeRun> run_onion_regimes(const OnionRegimesOptions& options);
std::string onion_regimes_csv(const std::vector<OnionRegimeRun>& runs);
// Mean ILE ± 95% CI per method and share, one table per (mirror, eta) scene.
std::string onion_regimes_summary(const std::vector<OnionRegimeRun>& runs, const std::string& footer);
// One panel per (mirror, eta) scene: ILE vs the foreground share, a line per method.
std::string draw_onion_regimes_figure(const std::vector<OnionRegimeRun>& runs, const std::string& path_stem);

}  // namespace hbirl::onion
