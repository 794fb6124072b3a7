// Recorded runs of the service set in Python (hbirl.read_log, bindings.hpp): app/recorded_problem.hpp,
// in process -- the same problem `hbirl export` writes.
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cctype>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "app/recorded_problem.hpp"
#include "learner/input_error.hpp"
#include "bindings.hpp"

namespace hbirl::python {

namespace {

// The readers of recordings are shared with `hbirl learn --log`, and name its flags; here
// an error names read_log's arguments instead, as the caller wrote them.
// A flag is a whole word (not part of a path such as /data/run--key/x.lcmlog).
std::string with_argument_names(std::string text) {
  static const std::pair<std::string, std::string> kNames[] = {{"--allow-incomplete", "allow_incomplete=True"},
                                                               {"--log", "path"},
                                                               {"--key", "key"},
                                                               {"--domain", "domain"},
                                                               {"--eta", "eta"}};
  const auto word_char = [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '/' || c == '.';
  };
  for (const auto& [flag, argument] : kNames) {
    for (size_t at = text.find(flag); at != std::string::npos;) {
      const size_t end = at + flag.size();
      // (A flag ends a sentence with a full stop, a path goes on after one.)
      const bool whole = (at == 0 || !word_char(text[at - 1])) &&
                         (end == text.size() || !word_char(text[end]) ||
                          (text[end] == '.' && (end + 1 == text.size() || text[end + 1] == ' ')));
      if (whole) text.replace(at, flag.size(), argument);
      at = text.find(flag, at + (whole ? argument.size() : flag.size()));
    }
  }
  return text;
}

Problem read_log(const std::string& path, const std::optional<std::string>& key_file,
                 const std::optional<std::string>& domain_file, bool allow_incomplete,
                 const std::optional<std::string>& eta) {
  app::LearnSettings prior;
  if (eta) app::set(prior, app::learn_setting("eta"), *eta);
  std::vector<std::string> warnings;
  app::RecordedProblem r;
  {
    py::gil_scoped_release released;  // a long recording takes seconds
    std::shared_ptr<const Domain> domain;
    if (domain_file) domain = open_domain(*domain_file, {}, &warnings);
    try {
      r = app::read_recorded_problem({path, key_file.value_or(""), allow_incomplete}, domain, prior, "hbirl.read_log");
    } catch (const InputError& e) {  // named by the recording first, as load_problem names its file
      const bool the_recording = e.field().empty() || e.field() == "--log";  // the path says it already
      throw InputError(path + (the_recording ? "" : ": " + with_argument_names(e.field())),
                       with_argument_names(e.message()));
    }
  }
  if (!warnings.empty()) {
    py::module_ w = py::module_::import("warnings");
    for (const auto& line : warnings) w.attr("warn")(*domain_file + ": " + line);
  }
  return std::move(r.problem);
}

}  // namespace

void bind_recording(py::module_& m) {
  m.def("_read_log", &read_log, py::arg("path"), py::arg("key") = py::none(), py::arg("domain") = py::none(),
        py::arg("allow_incomplete") = false, py::arg("eta") = py::none(),
        "A recorded run of the service set as a Problem (app/recorded_problem.hpp); hbirl.read_log wraps it.");
}

}  // namespace hbirl::python
