#pragma once
// What the sensors give the learner (paper §II): at timestep t, N_t >= 0 observations,
// each a symbol omega in Omega = {0 .. num_symbols-1} with a source distribution eta over
// 1 + |E| sources (index 0 the subject, 1..|E| the confounding elements). N_t = 0 is
// occlusion. Stored flat, one row per observation, so an E-step streams through memory.
#include <Eigen/Core>
#include <optional>
#include <cstdint>
#include <string>
#include <span>
#include <vector>

#include "learner/mdp.hpp"

namespace hbirl {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct ObservedTrajectory {
  std::vector<int> step_begin{0};  // observations of step t are rows [step_begin[t], step_begin[t+1])
  std::vector<int> symbols;        // one per observation
  RowMatrix eta;                   // one row per observation, 1 + |E| columns
  // Optional multiplicities: observation n stands for weights[n] identical ones (see
  // merge_identical_observations). Empty means every weight is 1.
  std::vector<double> weights;
  // Optional context of each observation (which rule of the labeller gave its eta), one
  // per row: observations of a context share a learned source distribution when eta is
  // learned (ObservationPrior::learn_eta). Empty means no contexts; the E-step then makes
  // each distinct eta its own context.
  std::vector<int> contexts;
  // The trajectory ended because its last action led into a terminal state (rather than
  // being cut off): the posterior then conditions on that.
  bool ends_in_terminal = false;
  // Which terminal state the last action entered, when it is known for certain
  // (ends_in_terminal only; a goal and a trap, say, then differ): the posterior conditions
  // on entering that one. -1: not known. An oracle's knowledge (the random-task
  // experiment's oracle_sensor_end); a real sensor's reports are end_symbols. Problem
  // files and the bus carry both; the flat Python form refuses them.
  int end_state = -1;
  // What an end sensor reported of the terminal state the last action entered
  // (ends_in_terminal only; docs/MODEL.md "Sensors that see the end"): symbols of the end
  // alphabet {0 .. K-1}, each drawn from O_end(s) of the state s entered. The subject's
  // own outcome (the onion lands in the bin, the picker reaches the dock), so no eta.
  std::vector<int> end_symbols;

  int length() const { return static_cast<int>(step_begin.size()) - 1; }
  int num_observations() const { return static_cast<int>(symbols.size()); }
  int observations_at(int t) const {
    return step_begin[static_cast<size_t>(t) + 1] - step_begin[static_cast<size_t>(t)];
  }
  double weight(int n) const { return weights.empty() ? 1.0 : weights[static_cast<size_t>(n)]; }
  int context(int n) const { return contexts.empty() ? -1 : contexts[static_cast<size_t>(n)]; }
};

// What a trajectory's end says of the state s its last action entered, log Pr(end | s)
// for every state: 0 for all when it may have been cut off; for a trajectory that ended
// in a terminal state, -inf off the terminal states (and off end_state when that is
// known), and on them the sum of log O_end(s, w) over its end_symbols. `end_model` is
// O_end (S x K, ObservationModel::end; any positive matrix of that shape gives the
// support). The last step's backward message is sum_s T(s | s_T, a_T) exp of this.
// Throws InputError naming the field for an end_state or end symbol the MDP or the end
// sensor does not have.
Eigen::VectorXd end_log_evidence(const Mdp& mdp, const ObservedTrajectory& trajectory,
                                 const Eigen::MatrixXd& end_model);

// exp(v - max v) entry by entry, exactly 0 where v is -inf (Eigen's vectorised exp is not
// there), with max v in *top: the end's evidence up to a constant. All 0 (and *top -inf)
// when every entry is -inf.
Eigen::VectorXd shifted_exp(const Eigen::VectorXd& v, double* top = nullptr);

// Whether every observation of `trajectories` (and at least one) came with its context: only
// then is learned eta one distribution per context of the sensor's -- its rules, which
// context names name -- rather than per distinct stated eta.
bool every_observation_has_context(std::span<const ObservedTrajectory> trajectories);

// A 64-bit digest (FNV-1a) of a data set: every length, symbol, eta, weight and end, bit for
// bit. Two processes with the same digest hold the same data (services/ compares them).
std::uint64_t dataset_digest(std::span<const ObservedTrajectory> trajectories);

// A source distribution eta as it comes in at the edge (a file, a message), checked and
// normalised in one place: its n entries must be finite and >= 0 and sum to 1 within
// `tolerance` (rounded values such as 1/3 as 0.333333 are fine). It is rescaled to sum
// to 1 only when it is off by more than rounding, so that a distribution written out
// exactly and read back keeps its bits. Returns what is wrong, empty when nothing is.
std::string normalise_eta(double* eta, int n, double tolerance = 1e-6);

// The same trajectory with identical (symbol, eta) observations of a step merged into
// one with a multiplicity: an exact rewrite of the emission product that makes the
// E-step's cost grow with the number of distinct observations, not all of them.
// `merged_of`, when given, receives for each observation row of `trajectory` the row of
// the result it was merged into.
ObservedTrajectory merge_identical_observations(const ObservedTrajectory& trajectory,
                                                std::vector<int>* merged_of = nullptr);

// The distinct (symbol, eta) observations of a data set ("kinds"), and the kind of every
// observation row. When eta takes few values (a labeller's rules, uniform eta) a data set
// of millions of observations has a few dozen kinds, and the E-step computes each kind's
// emission p(w | s,a) once per pass instead of once per observation.
struct ObservationKinds {
  std::vector<int> symbols;          // per kind
  RowMatrix eta;                     // per kind
  std::vector<int> contexts;         // per kind (-1: none)
  std::vector<std::vector<int>> of;  // per trajectory, per observation row: its kind
  int num_kinds() const { return static_cast<int>(symbols.size()); }
};

// The kinds of `trajectories`, or nothing when there are more than `max_kinds`.
std::optional<ObservationKinds> observation_kinds(const std::vector<ObservedTrajectory>& trajectories, int max_kinds);

// How the E-step refines the observation model (paper Algorithm 1; docs/MODEL.md, "The
// observation model").
enum class AlphaUpdate {
  // The Dirichlet posterior: alpha = s * alpha_subject_prior + alpha_dot for the subject,
  // alpha_prior + alpha_dot for the elements, at the fixed point; O = its mean. The prior
  // is kept; s, the weight of the subject prior's counts, is chosen from the data by the
  // held-out likelihood of each demonstration left out in turn unless fixed. The default.
  kPosterior,
  // The paper's alpha_i = c * alpha_dot + (1 - c) * alpha_{i-1}: fixed point alpha =
  // alpha_dot (maximum likelihood; the prior only sets the start). Kept for fidelity.
  kPaper,
};

// Dirichlet priors of the observation model (paper §II): alpha for the subject's
// O_{s,a} (one row per (s, a) pair) and for each confounding element's O_e. The same
// type carries the refined parameters from one EM iteration to the next (EStepState).
struct ObservationPrior {
  int num_symbols = 0;
  int num_confounders = 0;
  Eigen::MatrixXd subject_alpha;     // (S*A) x num_symbols
  Eigen::MatrixXd confounder_alpha;  // num_confounders x num_symbols
  bool learn = true;                 // refine alpha inside the E-step (paper Algorithm 1)
  AlphaUpdate update = AlphaUpdate::kPosterior;
  // The paper's step size (kPaper only): alpha_i = c * alpha_dot + (1 - c) * alpha_{i-1}.
  // kPosterior has none: its M-step is exact (docs/MODEL.md), because a damped step there
  // made EM's answer depend on c (it picks which fixed point the path reaches).
  double c = 0.1;
  // kPosterior: how much a controlled run's counts weigh against the demonstration (the
  // paper's "scale the hyper-parameters by a small constant"), as a power prior: the
  // subject's alpha is a base pseudo-count plus counts, and the counts are weighed by s,
  //   prior(s) = min(alpha, base) + s * max(alpha - base, 0),
  // so rows the controlled run never saw stay as uninformative as the base whatever s
  // is. base is the problem file's subject_alpha_default. With automatic_strength s is
  // chosen from the data (ObservationEStep::choose_strength) on prior_strength_grid()
  // and `strength` holds the current value.
  double subject_alpha_base = 1.0;
  // The base's shape, tied across a state's actions (docs/MODEL.md "A state's actions share
  // their view"): the base of row (s, a) times subject_base_shape(row), each row's mean 1,
  // so that a row with few or no counts is drawn towards what the controlled run saw at
  // the state's other actions, not towards uniform. Empty: the flat base (no tie).
  // Set by tie_subject_prior_across_actions, which ObservationEStep calls when tie_actions
  // is on (the posterior update only: a problem file's observation_model.tie_actions, off
  // by default); subject_tie is the share rho it chose.
  bool tie_actions = false;
  Eigen::MatrixXd subject_base_shape;
  double subject_tie = 0.0;
  bool automatic_strength = true;
  double strength = 1.0;
  // Learned eta (docs/MODEL.md, "Learned eta"): the source distribution of each context
  // (ObservedTrajectory::contexts; by default each distinct eta) gets a Dirichlet prior
  // centred on its stated eta with eta_strength pseudo-observations, and is refined inside
  // the E-step by MAP-EM's exact step, to the Dirichlet posterior of that prior and the
  // context's expected source counts (whatever `update` is: c never applies to eta). eta_alpha holds the refined
  // parameters, one row per context (set by the E-step). On by default with the posterior update; callers turn it off
  // with the paper's update (the paper's model takes eta as given).
  bool learn_eta = true;
  double eta_strength = 10.0;
  RowMatrix eta_alpha;
  // Unlisted confounders (docs/MODEL.md "Unlisted confounders"): 0 for none, else the
  // share epsilon in (0, 1) of every stated eta given to one more, catch-all source
  // (add_unlisted_source). `unlisted_added` says the catch-all is the last confounder.
  double unlisted_eta = 0.0;
  bool unlisted_added = false;
  // The end sensor's Dirichlet prior (docs/MODEL.md "Sensors that see the end"): one row
  // per state, K columns (the end alphabet; 0 columns: no end sensor). Only the terminal
  // states' rows are used. Refined inside the E-step as the elements' are: the posterior
  // update adds the expected counts to it (no strength), the paper's update steps by c.
  Eigen::MatrixXd end_alpha;
  // The pseudo-count of a terminal state nobody counted reports of (a problem file's
  // end_sensor.alpha_default): rows with no entry above it keep their mean under the
  // posterior update (weighed_end_prior).
  double end_alpha_base = 1.0;
  int num_end_symbols() const { return static_cast<int>(end_alpha.cols()); }
  static constexpr double kMinStrength = 1e-3;
  static constexpr double kMaxStrength = 1e3;
};

// An end sensor's alphabet at most (its reports travel as int16) and its reports of one
// ending at most: every reader (problem files, the bus) takes these bounds.
constexpr int kMaxEndSymbols = 1 << 15;
constexpr int kMaxEndReports = 1000;

// Largest explicit context id + 1 (a problem file's [symbol, eta, context]).
constexpr int kMaxContexts = 1 << 16;

// Adds the catch-all source for confounders nobody listed (docs/MODEL.md "Unlisted
// confounders"): one more confounding element with a flat Dirichlet(1) prior, and every
// observation's eta scaled by (1 - prior.unlisted_eta) with prior.unlisted_eta going to it.
// Nothing when prior.unlisted_eta is 0 or the source was added already (see
// adds_unlisted_source).
void add_unlisted_source(ObservationPrior& prior, std::vector<ObservedTrajectory>& trajectories);
// Whether add_unlisted_source would change anything: a caller that holds the data need
// copy them only then.
inline bool adds_unlisted_source(const ObservationPrior& prior) {
  return prior.unlisted_eta != 0.0 && !prior.unlisted_added;
}

// Sets the update and its companion default: eta is learned with the posterior update,
// taken as given with the paper's.
void use_alpha_update(ObservationPrior& prior, AlphaUpdate update);

const char* alpha_update_name(AlphaUpdate update);
// "posterior" or "paper"; false for anything else.
bool parse_alpha_update(const std::string& name, AlphaUpdate& update);

}  // namespace hbirl
