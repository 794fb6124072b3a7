#pragma once
// What every executable's command line shares, defined once: the learning settings made
// into options from their schema (learn_settings.hpp), and --domain/--size, --key and --url
// (domain_args.hpp opens the domain). CLI11.
#include <CLI/CLI.hpp>
#include <string>

#include "app/learn_settings.hpp"
#include "sim_driver/registry/domain_options.hpp"

namespace hbirl::app {

// Which settings a command offers: every one (hbirl learn), those the optimiser service can
// use (Setting::optimiser), those that override the observation prior (hbirl export writes
// the prior learned from), or the posterior engine's (hbirl posterior).
enum class Front { kCommandLine, kOptimiser, kPrior, kEngine };

// One option per setting (its flag, help, default and range from the schema), each writing
// `settings` when given. `settings` must outlive the parse.
void add_learn_settings(CLI::App* cmd, LearnSettings& settings, Front front);

// --domain onion|gridworld|FILE and --size N: a domain from the registry (sim_driver/registry/domain.hpp).
struct DomainArgs {
  std::string spec;
  DomainOptions options;
};
void add_domain_options(CLI::App* cmd, DomainArgs& args, const std::string& what);

// --key FILE: the run's key file (services/keyed_bus.hpp; docs/RELIABILITY.md). `what` says
// what this program does with it.
void add_key_option(CLI::App* cmd, std::string& key_file, const std::string& what);
// What a reader of a recording does with the key (hbirl learn --log, export, report).
inline const std::string kRecordingKeyHelp =
    "check every recorded message against it and drop, counting them, those it did not sign for its run.\n"
    "A key file for many runs (hbirl keygen FILE) reads the recording's run, and refuses a recording of several";
// --url URL: the LCM URL to use.
void add_url_option(CLI::App* cmd, std::string& url, const std::string& what);

}  // namespace hbirl::app
