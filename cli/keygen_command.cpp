// hbirl keygen: a key for the service set, for many runs or for one (services/keyed_bus.hpp;
// docs/RELIABILITY.md).
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "full_commands.hpp"
#include "services/keyed_bus.hpp"

namespace hbirl::cli {

Command add_keygen(CLI::App& app) {
  struct Args {
    std::string path, key_of;
    bool run = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(kKeygen.name, kKeygen.description);
  cmd->add_option("FILE", args->path, "The key file to create (an existing file is not overwritten)")->required();
  cmd->add_flag("--run", args->run,
                "A key file for one run: a fresh key and a fresh run identity (what services/launch.sh writes to\n"
                "OUT/run.key when no --key is given)");
  cmd->add_option(
      "--run-of", args->key_of,
      "A key file for one run of the key in this file (made without --run: a key for many runs, e.g. shared\n"
      "with workers on other machines): the same key and a fresh run identity (what services/launch.sh\n"
      "--key FILE writes to OUT/run.key)");
  return [args] {
    services::RunKey key = args->key_of.empty() ? services::RunKey::generate() : services::RunKey::read(args->key_of);
    if (args->run || !args->key_of.empty()) key = key.for_new_run();
    key.write(args->path);
    std::cerr << "hbirl keygen: wrote " << args->path << " (mode 0600; "
              << (key.run() ? "run " + services::run_id_text(*key.run())
                            : std::string("a key for many runs, no run of its own"))
              << ")\n";
    return 0;
  };
}

}  // namespace hbirl::cli
