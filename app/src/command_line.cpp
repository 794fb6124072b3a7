#include "app/command_line.hpp"

#include "learner/input_error.hpp"

namespace hbirl::app {

namespace {

const char* type_name(const Setting& s) {
  switch (s.type) {
    case Setting::Type::kInteger:
      return "INT";
    case Setting::Type::kNumber:
      return "FLOAT";
    case Setting::Type::kChoice:
      return "TEXT";
    case Setting::Type::kSwitch:
      return "BOOL";
  }
  return "";
}

// The help text: the setting's, its range, and what unset means.
std::string help_of(const Setting& s, Front front) {
  std::string help = s.help + " (" + describe_range(s) + ")";
  if (front == Front::kCommandLine && s.hidden_data) help += "; not with --from truth";
  return help;
}

std::string default_of(const Setting& s) {
  static const LearnSettings defaults;
  const nlohmann::json value = s.get(defaults);
  if (value.is_null()) return s.unset_help;
  return value.is_string() ? value.get<std::string>() : value.dump();
}

bool offered(const Setting& s, Front front) {
  switch (front) {
    case Front::kCommandLine:
      return true;
    case Front::kOptimiser:
      return s.optimiser;
    case Front::kPrior:
      return s.group == Setting::Group::kPrior;
    case Front::kEngine:
      return s.group == Setting::Group::kEngine;
  }
  return false;
}

}  // namespace

void add_learn_settings(CLI::App* cmd, LearnSettings& settings, Front front) {
  for (const Setting& s : learn_settings_schema()) {
    if (!offered(s, front)) continue;
    // The word is checked while parsing (CLI11 reports it as for any other option), then set.
    const CLI::Validator valid(
        [&s](std::string& text) {
          try {
            check(s, value_of_text(s, text));
          } catch (const InputError& e) {
            return std::string(e.message());
          }
          return std::string();
        },
        "", s.name);
    cmd->add_option(
           s.flag,
           [&settings, &s](const CLI::results_t& words) {
             set(settings, s, value_of_text(s, words.back()));
             return true;
           },
           help_of(s, front))
        ->type_size(1)
        ->expected(1)
        ->type_name(type_name(s))
        ->default_str(default_of(s))
        ->check(valid);
  }
}

void add_domain_options(CLI::App* cmd, DomainArgs& args, const std::string& what) {
  cmd->add_option("--domain", args.spec, what)->capture_default_str();
  cmd->add_option("--size", args.options.gridworld_size, "With --domain gridworld: cells a side")
      ->check(CLI::Range(2, 200))
      ->capture_default_str();
}

void add_key_option(CLI::App* cmd, std::string& key_file, const std::string& what) {
  cmd->add_option("--key", key_file,
                  "The run's key file (services/launch.sh writes OUT/run.key): " + what + " (docs/RELIABILITY.md)");
}

void add_url_option(CLI::App* cmd, std::string& url, const std::string& what) {
  cmd->add_option(
      "--url", url,
      "LCM URL " + what + " (default: LCM's, udpm://239.255.76.67:7667?ttl=0; add ttl=1 to reach other machines)");
}

}  // namespace hbirl::app
