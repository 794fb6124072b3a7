#include "services/messages.hpp"

#include <string>
#include <vector>

#include "learner/input_error.hpp"
#include "learner/observations.hpp"

namespace hbirl::services {

void validate(const hbirl::observations_t& m) {
  if (m.num_symbols < 1) throw InputError("observations.num_symbols", "must be at least 1");
  if (m.num_sources < 1) throw InputError("observations.num_sources", "must be at least 1");
  if (m.episode < 0) throw InputError("observations.episode", "is negative");
  if (m.step < 0 || m.frame < 0 || m.step >= kMaxSteps || m.frame >= kMaxFramesPerStep) {
    throw InputError("observations.step", "step or frame out of range");
  }
  if (m.num_context != 0 && m.num_context != m.n) throw InputError("observations.num_context", "must be 0 or n");
  for (int i = 0; i < m.num_context; ++i) {
    const int c = m.context[static_cast<size_t>(i)];
    if (c < 0 || c >= kMaxContexts) {
      throw InputError("observations.context[" + std::to_string(i) + "]",
                       "is outside [0, " + std::to_string(kMaxContexts - 1) + "]");
    }
  }
  for (int i = 0; i < m.n; ++i) {
    const int s = m.symbol[static_cast<size_t>(i)];
    if (s < 0 || s >= m.num_symbols)
      throw InputError("observations.symbol[" + std::to_string(i) + "]", "is outside the alphabet");
    std::vector<double> eta = m.eta[static_cast<size_t>(i)];
    const std::string wrong = normalise_eta(eta.data(), m.num_sources);
    if (!wrong.empty()) throw InputError("observations.eta[" + std::to_string(i) + "]", wrong);
  }
}

}  // namespace hbirl::services
