// The support of the observation model (observation_support.hpp).
#include "learner/observation_support.hpp"

#include "learner/input_error.hpp"

namespace hbirl {

namespace {

// Can a confounding element with weight in `eta` produce symbol w? Then the observation is
// possible at every state-action.
bool some_element_produces(const ObservationPrior& prior, const double* eta, int w) {
  for (int e = 0; e < prior.num_confounders; ++e) {
    if (eta[1 + e] > 0.0 && prior.confounder_alpha(e, w) > 0.0) return true;
  }
  return false;
}

// Can the subject, at pair r, produce symbol w with eta's weight?
bool subject_produces(const ObservationPrior& prior, const double* eta, int r, int w) {
  return eta[0] > 0.0 && prior.subject_alpha(r, w) > 0.0;
}

std::string symbol_sources(const ObservationPrior& prior, const ObservedTrajectory& t, int n) {
  std::string s = "symbol " + std::to_string(t.symbols[static_cast<size_t>(n)]) + " with eta [";
  for (int i = 0; i <= prior.num_confounders; ++i) s += (i ? ", " : "") + std::to_string(t.eta(n, i));
  return s + "]";
}

std::optional<ImpossibleObservation> check(const Mdp& mdp, const ObservedTrajectory& t, const ObservationPrior& prior,
                                           int index) {
  const int S = mdp.num_states, A = mdp.num_actions;
  std::vector<char> reach(static_cast<size_t>(S), 0), next(static_cast<size_t>(S), 0);
  for (int s = 0; s < S; ++s) reach[static_cast<size_t>(s)] = mdp.start[s] > 0.0;
  std::vector<char> alive(static_cast<size_t>(mdp.num_pairs()), 0);
  // What the end allows: the terminal states that can give it (end_state, and the end
  // symbols under the end sensor's prior: log alpha is -inf where alpha is 0).
  Eigen::VectorXd end;
  try {
    end = end_log_evidence(mdp, t, prior.end_alpha);
  } catch (const InputError& e) {
    return ImpossibleObservation{index, t.length() - 1, -1, e.field() + " " + e.message()};
  }
  if (t.end_state >= 0 && !t.ends_in_terminal) {
    return ImpossibleObservation{
        index, t.length() - 1, -1,
        "end_state " + std::to_string(t.end_state) + " is set, but the trajectory does not end in a terminal state"};
  }
  for (int step = 0; step < t.length(); ++step) {
    bool any = false;
    for (int s = 0; s < S; ++s) {
      for (int a = 0; a < A; ++a) {
        const bool ok = reach[static_cast<size_t>(s)] && !mdp.is_terminal(s) && mdp.available(s, a);
        alive[static_cast<size_t>(mdp.pair(s, a))] = ok;
        any = any || ok;
      }
    }
    if (!any)
      return ImpossibleObservation{index, step, -1, "every state the trajectory can be in at this step is terminal"};
    for (int n = t.step_begin[static_cast<size_t>(step)]; n < t.step_begin[static_cast<size_t>(step) + 1]; ++n) {
      const int w = t.symbols[static_cast<size_t>(n)];
      const double* eta = t.eta.row(n).data();
      if (some_element_produces(prior, eta, w)) continue;
      bool alone = false, together = false;
      for (int r = 0; r < mdp.num_pairs(); ++r) {
        if (!subject_produces(prior, eta, r, w)) {
          alive[static_cast<size_t>(r)] = 0;
          continue;
        }
        const int s = r / A;
        alone = alone || (reach[static_cast<size_t>(s)] && !mdp.is_terminal(s) && mdp.available(s, r % A));
        together = together || alive[static_cast<size_t>(r)];
      }
      if (!alone) {
        return ImpossibleObservation{
            index, step, n - t.step_begin[static_cast<size_t>(step)],
            symbol_sources(prior, t, n) +
                ": no source it gives weight to can produce it at any state-action reachable here (prior alpha 0)"};
      }
      if (!together) {
        return ImpossibleObservation{index, step, -1,
                                     "no single state-action can produce all of this step's observations"};
      }
    }
    const bool last = step + 1 == t.length();
    std::fill(next.begin(), next.end(), 0);
    bool ends = false;
    for (int r = 0; r < mdp.num_pairs(); ++r) {
      if (!alive[static_cast<size_t>(r)]) continue;
      for (SparseRowMatrix::InnerIterator it(mdp.transitions, r); it; ++it) {
        if (it.value() <= 0.0) continue;
        next[static_cast<size_t>(it.col())] = 1;
        ends = ends || (mdp.is_terminal(static_cast<int>(it.col())) && end[it.col()] > kNegInf);
      }
    }
    if (last && t.ends_in_terminal && !ends) {
      return ImpossibleObservation{
          index, step, -1,
          t.end_state >= 0 ? "the trajectory ends in terminal state " + std::to_string(t.end_state) +
                                 ", but no state-action it can be in leads to it"
          : !t.end_symbols.empty()
              ? "the trajectory ends in a terminal state whose end symbols the end sensor can give (prior "
                "end_alpha above 0), but no state-action it can be in leads to one"
              : "the trajectory ends in a terminal state, but no state-action it can be in leads to one"};
    }
    reach.swap(next);
  }
  return std::nullopt;
}

}  // namespace

std::optional<ImpossibleObservation> first_impossible_observation(const Mdp& mdp,
                                                                  const std::vector<ObservedTrajectory>& trajectories,
                                                                  const ObservationPrior& prior) {
  for (size_t i = 0; i < trajectories.size(); ++i) {
    if (auto found = check(mdp, trajectories[i], prior, static_cast<int>(i))) return found;
  }
  return std::nullopt;
}

}  // namespace hbirl
