// libFuzzer target: the problem-file and domain-file readers (problem/). The input is
// the file's text. InputError is the readers' answer to a bad file (what the user sees);
// anything else -- a sanitizer report, another exception escaping, a timeout, a huge
// allocation -- is a bug. A problem that reads is also written back (problem_to_json)
// and must read again: what hbirl writes, hbirl reads.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "learner/input_error.hpp"
#include "problem/domain_file.hpp"
#include "problem/json_format.hpp"
#include "problem/problem_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> warnings;
  std::optional<std::string> written;
  try {
    written = hbirl::format_json(hbirl::problem_to_json(hbirl::parse_problem(text, &warnings)));
  } catch (const hbirl::InputError&) {
    // Expected for almost every input.
  }
  if (written) {
    try {
      hbirl::parse_problem(*written);
    } catch (const hbirl::InputError&) {
      __builtin_trap();  // written by hbirl, refused by hbirl
    }
  }
  // The same text as a domain file (the readers of "mdp", "observation_model" and
  // "true_weights" are shared; "name" and "sensor" are the domain file's own).
  try {
    hbirl::parse_domain(text, "fuzz", &warnings);
  } catch (const hbirl::InputError&) {
  }
  return 0;
}
