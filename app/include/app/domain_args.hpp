#pragma once
// The domain --domain/--size name (command_line.hpp), for executables that link the domain
// registry (hbirl_domains); header-only so the learning commands need not.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "app/command_line.hpp"
#include "learner/input_error.hpp"
#include "sim_driver/registry/domain.hpp"

namespace hbirl::app {

// Null when no --domain was given; warnings go to stderr, each "PROGRAM: warning: SPEC: ...".
inline std::shared_ptr<const Domain> open_domain_args(const DomainArgs& args, const std::string& program) {
  if (args.spec.empty()) return nullptr;
  std::vector<std::string> warnings;
  std::shared_ptr<const Domain> domain = open_domain(args.spec, args.options, &warnings);
  for (const auto& w : warnings)
    std::fprintf(stderr, "%s: warning: %s\n", program.c_str(), printable(args.spec + ": " + w).c_str());
  return domain;
}

}  // namespace hbirl::app
