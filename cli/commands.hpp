#pragma once
// The subcommands of `hbirl`. Each registers its options on the app and returns the
// function to run once parsing succeeded; the function returns the exit status.
#include <CLI/CLI.hpp>
#include <functional>

namespace hbirl {
class Domain;
}  // namespace hbirl

namespace hbirl::cli {

using Command = std::function<int()>;

Command add_learn(CLI::App& app);
Command add_posterior(CLI::App& app);
Command add_validate(CLI::App& app);
Command add_generate(CLI::App& app);
Command add_summary(CLI::App& app);
Command add_experiment(CLI::App& app);
Command add_render(CLI::App& app);
Command add_report(CLI::App& app);
Command add_publish(CLI::App& app);
Command add_export(CLI::App& app);
Command add_keygen(CLI::App& app);
// In `hbirl`, the commands of hbirl-full (full_commands.hpp) run it with main's arguments,
// which remember_arguments() keeps (forward.cpp).
struct FullCommand;
Command add_forwarded(CLI::App& app, const FullCommand& command);
void remember_arguments(int argc, char** argv);

// Output that could not be written (a full disk, a closed pipe): exit status 1, one line.
struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Print a JSON result to stdout, or to `path` when it is not empty. Throws OutputError
// (stdout) or InputError("--out", ...) when it cannot be written.
void emit(const std::string& text, const std::string& path);
// The same, for a text written piece by piece (a problem file of millions of observations:
// write_problem), never held whole.
void emit_streamed(const std::function<void(std::ostream&)>& write, const std::string& path);
// Print warnings (one line each) to stderr.
void warn_all(const std::string& source, const std::vector<std::string>& warnings);

}  // namespace hbirl::cli

#include "learner/estep_mcmc.hpp"
#include "learner/estep_observations.hpp"
#include "learner/input_error.hpp"
#include "learner/mcmc_diagnostics.hpp"
#include "problem/json_format.hpp"
#include "problem/problem_file.hpp"
#include "sim_driver/registry/domain_options.hpp"

namespace hbirl::cli {
// Read a problem file; warnings go to stderr, errors are rethrown as InputError whose
// field starts with the file name ("examples/x.json: mdp.start: ..."), or -- for a path
// that is not a file it can read (a FIFO, a directory) -- with the option
// ("--problem PATH: is a FIFO ...").
Problem load_problem(const std::string& path);
// An InputError about the content of the file at `path`, with the file name prefixed.
InputError in_file(const std::string& path, const InputError& e);

// The MCMC engine's convergence diagnostics as printed ("mcmc_diagnostics": worst_rhat,
// worst_bulk_ess, quantities, chains; the worst are null when nothing was checked, and
// worst_rhat also when it is infinite, JSON having no infinity), and one warning line on
// stderr when they miss the thresholds (mcmc_diagnostics.hpp).
nlohmann::ordered_json mcmc_diagnostics_json(const McmcDiagnostics& diagnostics);
void warn_if_not_converged(const McmcDiagnostics& diagnostics);
// --alpha-update posterior|paper: how the observation model is refined (observation_model.hpp).
CLI::Option* add_alpha_update_option(CLI::App* cmd, AlphaUpdate& update);

}  // namespace hbirl::cli
