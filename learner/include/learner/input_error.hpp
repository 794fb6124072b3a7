#pragma once
// The one error type for bad input: it names the offending field (a JSON-path-like
// position such as "demonstration[3].steps[2].observations[0]") and says what is wrong.
#include <stdexcept>
#include <string>

namespace hbirl {

// `text` with control characters (from a file or a message) written as \xNN, so that an
// error line cannot rewrite the terminal it is printed on.
inline std::string printable(const std::string& text) {
  static const char hex[] = "0123456789abcdef";
  std::string out;
  out.reserve(text.size());
  for (const unsigned char c : text) {
    if (c < 0x20 || c == 0x7f) {
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    } else {
      out += static_cast<char>(c);
    }
  }
  return out;
}

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
