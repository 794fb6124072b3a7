#include "problem/json_format.hpp"

namespace hbirl {

namespace {

constexpr size_t kWidth = 100;

bool is_scalar(const nlohmann::ordered_json& v) { return !v.is_array() && !v.is_object(); }

bool is_flat_array(const nlohmann::ordered_json& v) {
  if (!v.is_array()) return false;
  for (const auto& e : v) {
    if (!is_scalar(e)) return false;
  }
  return true;
}

// An array whose elements are flat arrays (tuples), possibly holding one more level of
// flat arrays, such as an observation [symbol, [eta...]].
bool is_tuple(const nlohmann::ordered_json& v) {
  if (!v.is_array()) return false;
  for (const auto& e : v) {
    if (!is_scalar(e) && !is_flat_array(e)) return false;
  }
  return true;
}

}  // namespace

void format_json_into(const nlohmann::ordered_json& v, int indent, std::string& out) {
  const std::string pad(static_cast<size_t>(indent), ' ');
  const std::string inner(static_cast<size_t>(indent + 2), ' ');
  if (v.is_object()) {
    if (v.empty()) {
      out += "{}";
      return;
    }
    out += "{\n";
    bool first = true;
    for (const auto& item : v.items()) {
      if (!first) out += ",\n";
      first = false;
      out += inner + nlohmann::ordered_json(item.key()).dump() + ": ";
      format_json_into(item.value(), indent + 2, out);
    }
    out += "\n" + pad + "}";
  } else if (v.is_array()) {
    if (is_tuple(v) && v.dump().size() <= kWidth) {
      out += v.dump();
      return;
    }
    // Pack scalars and tuples several to a line; anything bigger gets a line of its own.
    out += "[\n" + inner;
    size_t column = 0;
    bool first = true;
    for (const auto& e : v) {
      const bool packable = is_scalar(e) || is_tuple(e);
      const std::string text = packable ? e.dump() : std::string();
      if (!first) {
        out += ",";
        if (!packable || column + text.size() + 1 > kWidth) {
          out += "\n" + inner;
          column = 0;
        } else {
          out += " ";
          ++column;
        }
      }
      first = false;
      if (packable) {
        out += text;
        column += text.size() + 1;
      } else {
        format_json_into(e, indent + 2, out);
        column = kWidth;  // what follows starts a new line
      }
    }
    out += "\n" + pad + "]";
  } else {
    out += v.dump();
  }
}

std::string format_json(const nlohmann::ordered_json& value) {
  std::string out;
  format_json_into(value, 0, out);
  out += "\n";
  return out;
}

// Per context (the file's or the sensor's, else each distinct stated eta): stated and
// learned source distributions and how many observations the context covers.
nlohmann::ordered_json learned_eta_json(const LearnedEta& eta, const std::vector<std::string>& names) {
  nlohmann::ordered_json contexts = nlohmann::ordered_json::array();
  const auto row = [](const RowMatrix& m, Eigen::Index r) {
    return std::vector<double>(m.row(r).begin(), m.row(r).end());
  };
  for (Eigen::Index c = 0; c < eta.learned.rows(); ++c) {
    nlohmann::ordered_json item = {{"context", c}};
    if (static_cast<size_t>(c) < names.size()) item["name"] = names[static_cast<size_t>(c)];
    item["stated"] = row(eta.stated, c);
    item["learned"] = row(eta.learned, c);
    item["observations"] = eta.observations[c];
    contexts.push_back(std::move(item));
  }
  return contexts;
}

}  // namespace hbirl
