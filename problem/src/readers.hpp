#pragma once
// The readers problem files and domain files share (problem_file.cpp): each validates its
// part of the document and throws InputError naming the field.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "problem/json_node.hpp"
#include "problem/problem_file.hpp"

namespace hbirl::detail {

// A list of exactly `expected` names, one per `what`.
std::vector<std::string> read_names(const JsonNode& node, long long expected, const char* what);
// "mdp": the MDP, and its state, action and feature names into `problem`.
Mdp read_mdp(const JsonNode& node, Problem& problem, std::vector<std::string>* warnings);
// "observation_model": the Dirichlet priors and how they are learned.
ObservationPrior read_observation_model(const JsonNode& node, const Mdp& mdp, std::vector<std::string>* warnings);
// "true_weights": one per feature.
Eigen::VectorXd read_true_weights(const JsonNode& node, const Mdp& mdp);
// The JSON document of `text`; malformed JSON is InputError("", "malformed JSON: ...").
nlohmann::json parse_json_text(const std::string& text);
// The largest problem or domain file read (256 MiB; a 200 x 200 Gridworld's is 15 MB): a
// bigger one, or an endless device such as /dev/zero, is refused before it fills memory
// (its JSON tree takes several times the bytes).
constexpr size_t kMaxFileBytes = size_t{256} << 20;
// The whole file; unreadable files are InputError("", ...).
std::string read_text_file(const std::string& path);

}  // namespace hbirl::detail
