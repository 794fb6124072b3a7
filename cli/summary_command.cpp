// hbirl summary: what a learned result says, for a person (docs/commands.md "Commands"):
// the weights by feature name, how right they are when the truth is known, the policy by
// state and action names, learned eta by the labeller's rule. Reads hbirl-optimiser's
// result.json (services/launch.sh prints this at the end of a run), hbirl learn's output
// and hbirl learn --log's.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "commands.hpp"
#include "learner/input_error.hpp"

namespace hbirl::cli {

namespace {

using nlohmann::json;

// A result is a few MB at most (a 200 x 200 Gridworld's policy is ~3 MB): refused above
// this before it is read.
constexpr std::uintmax_t kMaxResultBytes = std::uintmax_t{16} << 20;

json read_result(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError("FILE", "'" + path + "' is not a file it can read");
  if (std::filesystem::file_size(path, ec) > kMaxResultBytes)
    throw InputError("FILE", "'" + path + "' is larger than a result can be (16 MiB)");
  std::ifstream in(path);
  json j = json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object())
    throw InputError("FILE", "'" + path + "' is not a JSON result of hbirl learn or hbirl-optimiser");
  if (!j.contains("weights") || !j["weights"].is_array())
    throw InputError("FILE", "'" + path + "' has no \"weights\": not a result of hbirl learn or hbirl-optimiser");
  return j;
}

std::string number(const json& v) {
  if (!v.is_number()) return v.is_string() ? v.get<std::string>() : v.dump();
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v.get<double>());
  return buf;
}

std::string text(const json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); }

std::string count(const json& v) { return v.is_number() ? std::to_string(std::llround(v.get<double>())) : text(v); }

// "name 1.23, other -0.5": values by name, names from `names` when it has them all.
std::string by_name(const json& values, const json& names) {
  std::string out;
  const bool named = names.is_array() && names.size() == values.size();
  for (size_t k = 0; k < values.size(); ++k) {
    out += (k ? ", " : "") + (named ? text(names.at(k)) : "#" + std::to_string(k)) + " " + number(values.at(k));
  }
  return out;
}

std::string vector_text(const json& v) {
  std::string out;
  for (size_t k = 0; k < v.size(); ++k) out += (k ? " " : "") + number(v.at(k));
  return out;
}

void print_policy(std::ostream& out, const json& policy, size_t shown, const std::string& path) {
  if (!policy.is_array() || policy.empty()) return;
  size_t width = 5;
  for (size_t i = 0; i < std::min(shown, policy.size()); ++i)
    width = std::max(width, text(policy.at(i).at("state")).size());
  out << "  policy (the learned reward's: the action a robot would take, and the learned model's probability that the "
         "expert does):\n";
  for (size_t i = 0; i < std::min(shown, policy.size()); ++i) {
    const std::string state = text(policy.at(i).at("state"));
    out << "    " << state << std::string(width - state.size() + 2, ' ') << "-> " << text(policy.at(i).at("action"))
        << "  (" << number(policy.at(i).at("probability")) << ")\n";
  }
  if (policy.size() > shown)
    out << "    ... " << policy.size() - shown << " more states: all in " << path << " \"policy\"\n";
}

// The `shown` contexts that cover the most observations (a labeller may have dozens of
// rules), in the result's order.
void print_eta(std::ostream& out, const json& eta, size_t shown, const std::string& path) {
  if (!eta.is_array() || eta.empty()) return;
  std::vector<size_t> order(eta.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  const auto observations = [&eta](size_t i) {
    const json& n = eta.at(i).at("observations");
    return n.is_number() ? n.get<double>() : 0.0;
  };
  std::stable_sort(order.begin(), order.end(),
                   [&observations](size_t a, size_t b) { return observations(a) > observations(b); });
  order.resize(std::min(shown, order.size()));
  std::sort(order.begin(), order.end());
  out << "  learned eta (per labeller rule, the subject first): stated -> learned (observations)\n";
  for (size_t i : order) {
    const json& c = eta.at(i);
    const std::string name = c.contains("name") ? text(c.at("name")) : "context " + text(c.at("context"));
    out << "    " << name << ": " << vector_text(c.at("stated")) << " -> " << vector_text(c.at("learned")) << " ("
        << count(c.at("observations")) << ")\n";
  }
  if (eta.size() > shown)
    out << "    ... " << eta.size() - shown << " more contexts, with no more observations: all in " << path
        << " \"learned_eta\"\n";
}

struct Shown {
  size_t states = 20, contexts = 8;
};

void print_summary(std::ostream& out, const json& r, const std::string& path, const Shown& shown) {
  out << "Learned";
  if (r.contains("domain")) out << " on " << text(r.at("domain"));
  if (r.contains("demonstrations")) out << " from " << text(r.at("demonstrations")) << " demonstrations";
  if (r.contains("controlled_episodes"))
    out << " (and " << text(r.at("controlled_episodes")) << " controlled episodes)";
  out << ":\n";
  const json names = r.value("feature_names", json());
  out << "  weights: " << by_name(r.at("weights"), names) << "\n";
  if (r.contains("true_weights")) out << "  true weights: " << by_name(r.at("true_weights"), names) << "\n";
  if (r.contains("ile")) {
    out << "  ILE " << number(r.at("ile"));
    if (r.contains("ile_relative"))
      out << " (" << number(r.at("ile_relative").get<double>() * 100.0) << "% of the optimal value)";
    out << ": what the learned policy loses against the expert's, under the true reward\n";
  }
  const json confidence = r.contains("posterior") ? r.at("posterior").value("confidence", json()) : json();
  if (confidence.is_number())
    out << "  confidence " << number(confidence) << " that the learned policy is within 5% of optimal\n";
  print_policy(out, r.value("policy", json()), shown.states, path);
  print_eta(out,
            r.contains("learned_eta") ? r.at("learned_eta")
                                      : r.value("observation_model", json::object()).value("learned_eta", json()),
            shown.contexts, path);
  if (r.contains("incomplete")) out << "  INCOMPLETE: " << text(r.at("incomplete")) << "\n";
}

// The summary, or one line naming the file when a field is missing or of another type
// (a hand-edited or foreign file): printed whole or not at all.
int run_summary(const std::string& path, const Shown& shown) {
  const json r = read_result(path);
  std::ostringstream text;
  try {
    print_summary(text, r, path, shown);
  } catch (const json::exception& e) {
    throw InputError("FILE", "'" + path + "' is not a result hbirl wrote (" + e.what() + ")");
  }
  std::cout << text.str();
  return 0;
}

}  // namespace

Command add_summary(CLI::App& app) {
  struct Args {
    std::string path;
    Shown shown;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "summary",
      "What a learned result says, for a person: the weights by feature name (and the true ones, the ILE\n"
      "when known), the confidence when drawn, the learned policy by state and action names, learned eta\n"
      "by the labeller's rule. FILE: hbirl-optimiser's result.json (services/launch.sh prints this at the\n"
      "end of a run) or what hbirl learn wrote.");
  cmd->add_option("FILE", args->path, "The result (JSON)")->required();
  cmd->add_option("--states", args->shown.states, "Show the policy in this many states at most")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  cmd->add_option("--contexts", args->shown.contexts,
                  "Show learned eta in this many contexts at most: those with the most observations")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  return [args] { return run_summary(args->path, args->shown); };
}

}  // namespace hbirl::cli
