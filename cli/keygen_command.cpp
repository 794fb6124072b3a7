// hbirl keygen: a run key for the service set (services/keyed_bus.hpp; docs/RELIABILITY.md).
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "services/keyed_bus.hpp"

namespace hbirl::cli {

Command add_keygen(CLI::App& app) {
  auto path = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "keygen",
      "Write a fresh run key (32 random bytes as 64 hexadecimal digits) to a new file with mode 0600.\n"
      "Services, `hbirl publish`, the dashboard and readers of a recording given the same --key FILE\n"
      "sign every message and drop those not signed with it. services/launch.sh makes one per run.");
  cmd->add_option("FILE", *path, "The key file to create (an existing file is not overwritten)")->required();
  return [path] {
    services::RunKey::generate().write(*path);
    std::cerr << "hbirl keygen: wrote " << *path << " (mode 0600)\n";
    return 0;
  };
}

}  // namespace hbirl::cli
