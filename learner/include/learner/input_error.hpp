#pragma once
// The one error type for bad input: it names the offending field (a JSON-path-like
// position such as "demonstration[3].steps[2].observations[0]") and says what is wrong.
#include <stdexcept>
#include <string>

namespace hbirl {

class InputError : public std::runtime_error {
 public:
  InputError(std::string field, std::string message)
      : std::runtime_error(field.empty() ? message : field + ": " + message),
        field_(std::move(field)),
        message_(std::move(message)) {}

  const std::string& field() const { return field_; }
  const std::string& message() const { return message_; }

 private:
  std::string field_;
  std::string message_;
};

}  // namespace hbirl
