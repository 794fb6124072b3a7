#pragma once
// `hbirl report --log FILE --out DIR`: the dashboard's views of a finished run as a static
// page for papers and lab notebooks -- DIR/index.html with the figures as PNG and SVG
// (gnuplot), the last annotated camera frame, and DIR/state.json (the dashboard's data).
#include <memory>
#include <string>
#include <vector>

#include "sim_driver/registry/domain.hpp"

namespace hbirl::dashboard {

struct Report {
  std::string page;                   // DIR/index.html
  std::vector<std::string> figures;   // stems drawn (each .png, .svg and its .gp script)
  std::vector<std::string> problems;  // figures that could not be drawn, and why
  long long messages = 0, bad_messages = 0;
  bool finished = false;  // the run's final reward is in the recording
};

// Throws InputError for a log that cannot be read (damaged, signed with another key,
// nothing in it readable, messages of several runs) or a folder that cannot be written.
// `domain`: the run's domain file, when it is one (else the built-in domain it names).
// `key_file`: the run's key when its messages were signed (services/keyed_bus.hpp).
Report write_report(const std::string& log_path, const std::string& out_dir,
                    std::shared_ptr<const Domain> domain = nullptr, const std::string& key_file = "");

}  // namespace hbirl::dashboard
