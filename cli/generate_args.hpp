#pragma once
// hbirl generate --domain F: a domain file's simulated sensor into a problem file. The
// simulation opens the domain as the services do (sim_driver's registry, in hbirl-full):
// `hbirl` runs it there (forward.cpp), hbirl-full here (generate_domain.cpp).
#include <cstdint>
#include <string>

namespace hbirl::cli {

struct GenerateDomainArgs {
  std::string domain;
  std::uint64_t seed = 1;
  std::string out;
};

int run_generate_from_domain(const GenerateDomainArgs& args);

}  // namespace hbirl::cli
