#include "problem/json_node.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace hbirl {

namespace {

std::string format_number(double x) {
  std::ostringstream out;
  out.precision(10);
  out << x;
  return out.str();
}

size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

}  // namespace

std::string JsonNode::path() const {
  std::string p = *base_;
  for (int d = 0; d < depth_; ++d) p += "[" + std::to_string(index_[static_cast<size_t>(d)]) + "]";
  return p;
}

std::string JsonNode::describe() const {
  const auto& v = *value_;
  if (v.is_number()) return "the number " + format_number(v.get<double>());
  if (v.is_string()) return "the string \"" + v.get<std::string>() + "\"";
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_null()) return "null";
  if (v.is_array()) return "an array of " + std::to_string(v.size());
  return "an object";
}

bool JsonNode::has(const std::string& key) const { return value_->is_object() && value_->contains(key); }

JsonNode JsonNode::at(const std::string& key) const {
  if (!value_->is_object()) fail("expected an object, got " + describe());
  const auto it = value_->find(key);
  const std::string here = path();
  std::string child = here.empty() ? key : here + "." + key;
  if (it == value_->end()) throw InputError(child, "missing");
  return JsonNode(*it, std::make_shared<const std::string>(std::move(child)));
}

std::optional<JsonNode> JsonNode::find(const std::string& key) const {
  if (!value_->is_object()) fail("expected an object, got " + describe());
  if (!value_->contains(key)) return std::nullopt;
  return at(key);
}

void JsonNode::check_keys(const std::vector<std::string>& known, std::vector<std::string>* warnings) const {
  if (!value_->is_object()) fail("expected an object, got " + describe());
  for (const auto& item : value_->items()) {
    const std::string& key = item.key();
    if (key == "comment" || (!key.empty() && key[0] == '_')) continue;
    if (std::find(known.begin(), known.end(), key) != known.end()) continue;
    if (warnings == nullptr) continue;
    const std::string here = path();
    std::string line = (here.empty() ? key : here + "." + key) + ": unknown key, ignored";
    std::string closest;
    size_t best = 3;  // suggest only close misspellings
    for (const auto& k : known) {
      const size_t d = edit_distance(key, k);
      if (d < best) {
        best = d;
        closest = k;
      }
    }
    if (!closest.empty()) line += " (did you mean \"" + closest + "\"?)";
    warnings->push_back(line);
  }
}

size_t JsonNode::size() const {
  if (!value_->is_array()) fail("expected an array, got " + describe());
  return value_->size();
}

JsonNode JsonNode::operator[](size_t i) const {
  if (depth_ == kHeldIndices) {  // write the path out, and hold the new index below it
    JsonNode child((*value_)[i], std::make_shared<const std::string>(path()));
    child.index_[0] = i;
    child.depth_ = 1;
    return child;
  }
  JsonNode child((*value_)[i], base_);
  child.index_ = index_;
  child.index_[static_cast<size_t>(depth_)] = i;
  child.depth_ = depth_ + 1;
  return child;
}

void JsonNode::expect_tuple(size_t n, const char* shape) const {
  if (!value_->is_array() || value_->size() != n) {
    fail(std::string("expected ") + shape + ", got " + describe());
  }
}

long long JsonNode::as_int(long long lo, long long hi) const {
  const auto& v = *value_;
  const auto expected = [lo, hi] {
    return "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got ";
  };
  if (!v.is_number()) fail(expected() + describe());
  if (v.is_number_float()) {
    const double x = v.get<double>();
    if (!std::isfinite(x) || x != std::floor(x) || x < -9e15 || x > 9e15) fail(expected() + describe());
  }
  long long x = 0;
  if (v.is_number_unsigned()) {
    const auto u = v.get<unsigned long long>();
    if (u > static_cast<unsigned long long>(hi)) fail(expected() + std::to_string(u));
    x = static_cast<long long>(u);
  } else if (v.is_number_integer()) {
    x = v.get<long long>();
  } else {
    x = static_cast<long long>(v.get<double>());
  }
  if (x < lo || x > hi) fail(expected() + std::to_string(x));
  return x;
}

double JsonNode::as_number() const {
  const auto& v = *value_;
  if (!v.is_number()) fail("expected a number, got " + describe());
  const double x = v.get<double>();
  if (!std::isfinite(x)) fail("expected a finite number, got " + format_number(x));
  return x;
}

double JsonNode::as_number(double lo, double hi) const {
  const double x = as_number();
  if (x < lo || x > hi) {
    fail("expected a number in [" + format_number(lo) + ", " + format_number(hi) + "], got " + format_number(x));
  }
  return x;
}

bool JsonNode::as_bool() const {
  if (!value_->is_boolean()) fail("expected true or false, got " + describe());
  return value_->get<bool>();
}

std::string JsonNode::as_string() const {
  if (!value_->is_string()) fail("expected a string, got " + describe());
  return value_->get<std::string>();
}

}  // namespace hbirl
