#pragma once
// Human-friendly JSON text: objects are indented, arrays of scalars stay on one line and
// arrays of short tuples put one tuple per line. Numbers are written with enough digits
// to round-trip exactly.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "learner/estep_observations.hpp"

namespace hbirl {

std::string format_json(const nlohmann::ordered_json& value);
// The same text for a value nested `indent` spaces deep, appended to `out` (what a writer
// that streams a document piece by piece writes each piece with).
void format_json_into(const nlohmann::ordered_json& value, int indent, std::string& out);

// Learned eta as hbirl learn and hbirl-optimiser print it: per context, its id, the
// stated and learned source distributions and how many observations it covers; and its
// name when `names` has one for it (a domain's labeller rules, DomainNames::contexts).
nlohmann::ordered_json learned_eta_json(const LearnedEta& eta, const std::vector<std::string>& names = {});

}  // namespace hbirl
