#pragma once
// How a built-in domain is made (sim_driver/registry/domain.hpp's open_domain), in a header of its own
// so that a command line can take the options without the domains' dependencies.
namespace hbirl {

struct DomainOptions {
  int gridworld_size = 5;
};

}  // namespace hbirl
