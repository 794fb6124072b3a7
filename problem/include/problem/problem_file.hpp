#pragma once
// The problem file (docs/files.md "Problem files"): the user's MDP and demonstration as one JSON document.
// Everything is validated here, at the edge; a bad file raises InputError naming the
// field and position, e.g. "demonstration[3].steps[2].observations[0]: eta has 2
// entries, expected 3". The full format is documented in docs/files.md ("Problem files").
#include <nlohmann/json.hpp>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "learner/input_error.hpp"
#include "learner/mdp.hpp"
#include "learner/observations.hpp"
#include "learner/trajectory.hpp"

namespace hbirl {

struct DemonstratedTrajectory {
  std::optional<ObservedTrajectory> steps;  // what the sensors saw
  std::optional<Trajectory> truth;          // the true (s, a) pairs, for baselines and metrics
  // It ended because its last action entered a terminal state (default when the MDP has
  // terminal states); false for a trajectory that was cut off.
  bool ends_in_terminal = false;
  // Part of a controlled run (the subject alone, its true steps known): it gives the
  // subject's prior (learner/controlled_prior.hpp) instead of demonstrating; it needs
  // both steps and truth.
  bool controlled = false;
};

struct Problem {
  // "name": the domain's name EPISODE markers carry when `hbirl publish` sends it (a domain
  // file's "name"); empty: none given (publish then uses the file's stem).
  std::string name;
  Mdp mdp;
  std::vector<std::string> state_names;  // empty when the file gives none
  std::vector<std::string> action_names;
  std::vector<std::string> feature_names;
  std::optional<ObservationPrior> observation_model;
  // "context_names": the sensor's contexts by name (context c the c-th; empty: none given):
  // learned eta is reported by them.
  std::vector<std::string> context_names;
  std::vector<DemonstratedTrajectory> demonstration;
  std::optional<Eigen::VectorXd> true_weights;

  // The truth of the demonstrations (the controlled run's left out); throws InputError
  // naming the first trajectory without one.
  std::vector<Trajectory> truth_trajectories() const;
};

// Parse and validate. `source` names the document in messages only. Unknown keys add a
// line to *warnings (when not null) and are otherwise ignored.
Problem parse_problem(const std::string& text, std::vector<std::string>* warnings = nullptr);
// A file that cannot be read as a problem or domain file at all: missing, unreadable, not
// a regular file (a FIFO, a device, a directory, a socket) or over 256 MB. An InputError
// with an empty field, so that a caller can name the option that gave the path.
class FileError : public InputError {
 public:
  explicit FileError(std::string message) : InputError("", std::move(message)) {}
};

// Read a file; one that cannot be read is a FileError (refused before it is read).
Problem read_problem_file(const std::string& path, std::vector<std::string>* warnings = nullptr);

// The problem as a JSON document in the same format (round-trips through parse_problem).
nlohmann::ordered_json problem_to_json(const Problem& problem);

// format_json(problem_to_json(problem)) with `before`'s fields first and `after`'s last,
// written to `out` a trajectory at a time (keys of `before` and `after` must be neither the
// problem's nor each other's): what a data set of millions of observations is
// written with (hbirl export), in memory a trajectory's JSON, not the whole document's.
void write_problem(std::ostream& out, const Problem& problem, const nlohmann::ordered_json& before = {},
                   const nlohmann::ordered_json& after = {});

}  // namespace hbirl
