// hbirl learn --log: learning from a recorded run of the service set (hbirl-full only).
#include <iostream>

#include "app/domain_args.hpp"
#include "learn_args.hpp"
#include "learner/input_error.hpp"
#include "problem/json_format.hpp"
#include "services/optimiser.hpp"

namespace hbirl::cli {

// Offline from a recorded run of the service set: the same data set and the same learning
// as hbirl-optimiser, so the same theta (services/optimiser.hpp).
int run_learn_from_log(const LearnArgs& args) {
  // Only what hbirl-optimiser can be told (the engine's settings and --restarts it has not):
  // the same data and settings, the same theta. --threads changes no result.
  static const app::LearnSettings defaults;
  for (const app::Setting& s : app::learn_settings_schema()) {
    if (s.optimiser || s.name == "threads" || s.get(args.settings) == s.get(defaults)) continue;
    throw InputError(s.flag,
                     "not with --log: hbirl-optimiser has no such setting, so the theta would not be the run's");
  }
  services::Counters counters;
  counters.service = "hbirl learn";
  const std::shared_ptr<const Domain> domain = app::open_domain_args(args.domain, "hbirl");
  const services::OptimiserResult r =
      services::learn_from_log({args.log, args.key_file, args.allow_incomplete}, args.settings, counters, domain);
  if (!r.incomplete.empty())
    std::cerr << "hbirl learn: warning: learned from an incomplete run: " << r.incomplete << "\n";
  nlohmann::ordered_json out;
  out["log"] = args.log;
  services::add_learned_run(out, r, domain);
  out["bad_messages"] = counters.bad_messages;
  out["authenticated"] = counters.authenticated;
  if (!r.incomplete.empty()) out["incomplete"] = r.incomplete;
  emit(out.dump(2) + "\n", args.out);
  return 0;
}

}  // namespace hbirl::cli
