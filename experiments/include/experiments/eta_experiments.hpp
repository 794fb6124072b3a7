#pragma once
// Beyond the paper (its "future work"; docs/results.md "Beyond the paper"): how learning fares
// when the labeller's eta is miscalibrated, and when the environment was not fully listed.
//
// eta sensitivity (docs/results/eta_sensitivity): the Gridworld (gridworld_scenario.hpp)
// at each |E|, watched by a labeller that gives its pick `mass` of eta and picks the true
// source with probability `accuracy` (sim_driver Labeller; its pick is the context).
// Methods: "fixed" (eta as stated), "learned" (eta learned per context), and per (run,
// |E|) the "perfect" labeller (all of eta on the true source, fixed) as the reference.
//
// unlisted confounders (docs/results/unlisted): the Gridworld with |E| true elements of
// which the learner is told `told` (0: eta over the subject alone, the paper's
// "controlled" assumption broken; 1: the first element). Its labeller knows only the told
// sources: an observation of a told source gets its true source as pick with probability
// 0.8, else a told source at random; one of an untold element a told source at random; the
// pick gets 0.6 of eta (all of it when only the subject is told), the rest evenly. Methods:
// "as_told" (hbirl's defaults on the told sources), "catch_all" (plus the unlisted source,
// eta fixed), "catch_all_learned_eta" (plus the unlisted source, eta learned), and the
// "oracle" told every element (told = |E|).
//
// Every method of a run sees the same observations; EM as in the Gridworld experiment
// (posterior update, SQUAREM). Results do not depend on the thread count.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "experiments/gridworld_scenario.hpp"

namespace hbirl {

struct EtaSensitivityOptions {
  GridworldScenarioOptions scenario;
  std::vector<int> confounders = {3, 7};
  std::vector<double> masses = {0.4, 0.6, 0.8, 0.95};
  std::vector<double> accuracies = {0.2, 0.4, 0.6, 0.8, 1.0};
  int runs = 30;
  double eta_prior_strength = 10.0;  // kappa of learned eta (ObservationPrior::eta_strength)
  int threads = 0;
  std::function<void(int done, int total)> progress;
};

struct EtaRun {
  int run = 0;
  int confounders = 0;
  double mass = 0.0;
  double accuracy = 0.0;
  std::string method;  // "fixed", "learned" or "perfect"
  double ile = 0.0;
  double ile_relative = 0.0;
  bool goal_recovered = false;
  double subject_eta = -1.0;     // learned eta of the context "pick = subject", its subject share (-1: n/a)
  double label_accuracy = -1.0;  // subject-or-not labels right (gridworld_scenario.hpp)
  int em_evaluations = 0;        // EM evaluations (the cost)
  double seconds = 0.0;
  std::string error;
};

std::vector<EtaRun> run_eta_sensitivity(const EtaSensitivityOptions& options);
std::string eta_runs_csv(const std::vector<EtaRun>& runs);

struct UnlistedOptions {
  GridworldScenarioOptions scenario;
  std::vector<int> confounders = {0, 1, 3, 5, 7};
  std::vector<int> told = {0, 1};
  double unlisted_eta = 0.25;  // epsilon of the catch-all (observation_model.unlisted_source.eta)
  int runs = 30;
  int threads = 0;
  std::function<void(int done, int total)> progress;
};

struct UnlistedRun {
  int run = 0;
  int confounders = 0;
  int told = 0;
  std::string method;  // "as_told", "catch_all", "catch_all_learned_eta", "oracle"
  double ile = 0.0;
  double ile_relative = 0.0;
  bool goal_recovered = false;
  double label_accuracy = -1.0;
  int em_evaluations = 0;
  double seconds = 0.0;
  std::string error;
};

std::vector<UnlistedRun> run_unlisted(const UnlistedOptions& options);
std::string unlisted_runs_csv(const std::vector<UnlistedRun>& runs);

// Each experiment's summary (markdown: means with 95% CIs, paired comparisons; `footer`
// says how it was run) and figure (<stem>.gp/.png/.svg; returns what went wrong, empty
// on success) -- experiments/src/eta_reports.cpp.
std::string eta_sensitivity_summary(const std::vector<EtaRun>& runs, const std::string& footer);
std::string draw_eta_sensitivity_figure(const std::vector<EtaRun>& runs, const std::string& path_stem);
std::string unlisted_summary(const std::vector<UnlistedRun>& runs, const std::string& footer);
std::string draw_unlisted_figure(const std::vector<UnlistedRun>& runs, const std::string& path_stem);

}  // namespace hbirl
