// What the commands of hbirl-full share beyond common.cpp (they link the domains).
#include "commands.hpp"
#include "sim_driver/domain.hpp"

namespace hbirl::cli {

std::shared_ptr<const Domain> open_domain_args(const DomainArgs& args) {
  if (args.spec.empty()) return nullptr;
  std::vector<std::string> warnings;
  std::shared_ptr<const Domain> domain = open_domain(args.spec, args.options, &warnings);
  warn_all(args.spec, warnings);
  return domain;
}

}  // namespace hbirl::cli
