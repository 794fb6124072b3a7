#pragma once
// A read-only view of a JSON value that knows where it sits in the document
// ("demonstration[3].steps[2].observations[0]"), so every validation failure can name
// the field and position in one line.
//
// An array element's path is written out only when it is asked for (a failure): a reader
// walks every element of a file with millions of numbers and names at most one of them.
// A node holds the path of its nearest ancestor reached by a key, shared, and the array
// indices below it; a key lookup (objects are few) writes its path once.
#include <array>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "learner/input_error.hpp"

namespace hbirl {

class JsonNode {
 public:
  JsonNode(const nlohmann::json& value, std::string path)
      : value_(&value), base_(std::make_shared<const std::string>(std::move(path))) {}

  std::string path() const;
  const nlohmann::json& raw() const { return *value_; }

  [[noreturn]] void fail(const std::string& message) const { throw InputError(path(), message); }

  // Objects.
  bool has(const std::string& key) const;
  JsonNode at(const std::string& key) const;  // required: "path.key: missing"
  std::optional<JsonNode> find(const std::string& key) const;
  // Warns (one line each, into *warnings) about keys that are not in `known`; keys
  // named "comment" or starting with "_" are comments and pass silently.
  void check_keys(const std::vector<std::string>& known, std::vector<std::string>* warnings) const;

  // Arrays.
  size_t size() const;  // fails unless an array
  JsonNode operator[](size_t i) const;
  // An array of exactly n elements (a tuple such as [s, a, s', p]).
  void expect_tuple(size_t n, const char* shape) const;

  // Scalars; each fails with the expected type/range and what was found.
  long long as_int(long long lo, long long hi) const;
  double as_number() const;  // finite
  double as_number(double lo, double hi) const;
  bool as_bool() const;
  std::string as_string() const;
  bool is_string() const { return value_->is_string(); }

 private:
  static constexpr int kHeldIndices = 4;  // deeper nesting writes the path out once
  JsonNode(const nlohmann::json& value, std::shared_ptr<const std::string> base)
      : value_(&value), base_(std::move(base)) {}

  std::string describe() const;  // "a string", "the number 3.5", ...
  const nlohmann::json* value_;
  std::shared_ptr<const std::string> base_;   // the path down to the last key
  std::array<size_t, kHeldIndices> index_{};  // then these array indices
  int depth_ = 0;                             // how many of them
};

}  // namespace hbirl
