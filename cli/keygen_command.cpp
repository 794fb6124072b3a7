// hbirl keygen: a run key for the service set (services/keyed_bus.hpp; docs/RELIABILITY.md).
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "full_commands.hpp"
#include "services/keyed_bus.hpp"

namespace hbirl::cli {

Command add_keygen(CLI::App& app) {
  auto path = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(kKeygen.name, kKeygen.description);
  cmd->add_option("FILE", *path, "The key file to create (an existing file is not overwritten)")->required();
  return [path] {
    services::RunKey::generate().write(*path);
    std::cerr << "hbirl keygen: wrote " << *path << " (mode 0600)\n";
    return 0;
  };
}

}  // namespace hbirl::cli
