#include <fstream>
#include <iostream>

#include "commands.hpp"
#include "learner/input_error.hpp"

namespace hbirl::cli {

void emit(const std::string& text, const std::string& path) {
  if (path.empty()) {
    std::cout << text << std::flush;
    return;
  }
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.flush();
  if (!out) throw InputError("--out", "cannot write " + path);
}

void warn_all(const std::string& source, const std::vector<std::string>& warnings) {
  for (const auto& w : warnings) std::cerr << "hbirl: warning: " << source << ": " << w << "\n";
}

}  // namespace hbirl::cli

namespace hbirl::cli {

Problem load_problem(const std::string& path) {
  std::vector<std::string> warnings;
  try {
    Problem problem = read_problem_file(path, &warnings);
    warn_all(path, warnings);
    return problem;
  } catch (const InputError& e) {
    throw in_file(path, e);
  }
}

InputError in_file(const std::string& path, const InputError& e) {
  return InputError(e.field().empty() ? path : path + ": " + e.field(), e.message());
}

}  // namespace hbirl::cli

namespace hbirl::cli {

std::vector<std::string> engine_names() { return {"exact"}; }

EngineFactory engine_factory(const std::string& name) {
  if (name == "exact") return exact_engine_factory();
  throw InputError("--engine", "unknown engine \"" + name + "\"");
}

}  // namespace hbirl::cli
