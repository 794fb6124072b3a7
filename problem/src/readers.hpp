#pragma once
// The readers problem files and domain files share (problem_file.cpp): each validates its
// part of the document and throws InputError naming the field.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "json_document.hpp"
#include "problem/json_node.hpp"
#include "problem/problem_file.hpp"

namespace hbirl::detail {

// A list of exactly `expected` names, one per `what`.
std::vector<std::string> read_names(const JsonNode& node, long long expected, const char* what);
// "context_names": the sensor's contexts (its labeller's rules) by name, context c the
// c-th: 1 to 65536 non-empty names (observations_t's contexts are 0 .. 65535).
std::vector<std::string> read_context_names(const JsonNode& node);
// "name": what EPISODE markers carry (short, printable, no spaces: it names the run on the bus).
std::string read_domain_name(const JsonNode& node);
// "mdp": the MDP, and its state, action and feature names into `problem`.
Mdp read_mdp(const JsonNode& node, Problem& problem, std::vector<std::string>* warnings);
// "observation_model": the Dirichlet priors and how they are learned.
ObservationPrior read_observation_model(const JsonNode& node, const Mdp& mdp, std::vector<std::string>* warnings);
// "true_weights": one per feature.
Eigen::VectorXd read_true_weights(const JsonNode& node, const Mdp& mdp);
// What the parser builds of "mdp" and "observation_model" (json_document.hpp), and the
// keys their readers know.
const JsonShape& mdp_shape();
const JsonShape& observation_model_shape();
// A tuple of the list `tuple` describes, or fail naming its shape.
void expect_tuple(const JsonNode& node, const TupleList& tuple);
// The largest problem or domain file read (256 MiB; a 200 x 200 Gridworld's is 15 MB): a
// bigger one is refused before it is read (its JSON tree takes several times the bytes).
constexpr size_t kMaxFileBytes = size_t{256} << 20;
// The whole of a regular file; anything else (a FIFO, a device such as /dev/zero, a
// directory, a socket), a file that cannot be read or one over kMaxFileBytes is a
// FileError, refused before a byte is read.
std::string read_text_file(const std::string& path);

}  // namespace hbirl::detail
