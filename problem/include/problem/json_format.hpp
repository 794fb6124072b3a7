#pragma once
// Human-friendly JSON text: objects are indented, arrays of scalars stay on one line and
// arrays of short tuples put one tuple per line. Numbers are written with enough digits
// to round-trip exactly.
#include <nlohmann/json.hpp>
#include <string>

namespace hbirl {

std::string format_json(const nlohmann::ordered_json& value);

}  // namespace hbirl
